"""BLOCKER-SEARCH (ours, issue #14): a conflict-directed best-first search over SETS of relocated
obstacles that only considers objects that block the target or block a blocker.

Model. By Assumption 2 relocating o after S depends on the set S only; we also assume MONOTONICITY
(removing more objects never makes a feasible relocation infeasible; true of the clearing-set model
of :class:`~qtree_task_planner.oracle.TableOracle` and of a collision-only planner). An infeasible
answer for (S, o) with blockers B yields the CONSTRAINT "before o, at least one object of X must be
relocated", X = B minus S, o and the target. A constraint is SOUND when every set whose removal
makes o feasible meets X; with monotonicity this is the same as: o stays infeasible when every
obstacle except X is removed. Sound constraints come from an oracle that declares
``sound_blockers`` (complete reports), or are VERIFIED by that one extra query, (all obstacles but
X relocated, o), asked with the empty drop zone where the oracle can
(:func:`~qtree_task_planner.oracle.ask_clear`: the real planner would otherwise plan into slot N −
|X| among as many placed objects, and a drop-zone failure would confirm a wrong report); a report
that fails the check, or no report at all (``blocking_ids=None``), is replaced by the trivial sound
constraint X = all obstacles not in S. An oracle that also reports the blockers of EACH approach
(``approach_blockers(S, o)``: the in-process planner's sweeps, a TableOracle's clearing sets) gives
a stronger constraint: o needs every blocker of one approach removed, so every set freeing o meets
any HITTING SET of the approaches' blocker sets; the smallest one (often the single object in front
of the hand in every approach, where the union names a dozen) is tried first, verified the same
way, and the union is the fallback when its check fails.

Search. A set S of obstacles is a CANDIDATE when its objects can be ordered so that each one's
known constraints are met by the objects before it, and the target's by all of S (known
infeasibility is never asked again). Every true solution is a candidate, so the smallest
candidate size k is a lower bound of the optimum. Candidates of size <= k are found by
depth-first branching on an unmet constraint (the target's, or, when some objects of S cannot
be ordered, the union of one unmet constraint of each of them): every candidate containing S
must contain one of the branch objects, so the branching is complete, and only objects named
in constraints ever enter S. The smallest candidate is tested with real queries in its order;
a failed query adds a constraint and the search resumes at the same k; when no candidate of
size k is left, k grows by one. A tested candidate that succeeds is returned.

When the answer is provably optimal (``certified=True`` in the result): Assumption 2,
monotonicity (for the planner: in the clutter, and no relocation harder in the empty drop zone
than among placed objects), and every constraint sound (declared or verified, see above). Then
``status='optimal'`` means no feasible sequence has fewer objects, and ``status='unsolvable'``
means no feasible sequence exists at all (e.g. the target blocked by nothing movable). With
``verify=False`` on an oracle whose reports are not declared sound (the planner's response field
names only its most promising approach), the search is a HEURISTIC: constraints may be wrong, the
answer is feasible (every step was checked) but may be longer than the optimum, and
``unsolvable`` may be wrong. Without monotonicity a verification can also be wrong; a constraint
X of o contradicted by a known feasible answer (o feasible after a set that meets none of X, or
a verification that found o feasible with more objects than X standing) proves that
monotonicity fails: the result is then uncertified (``contradictions`` > 0), the constraint is
replaced by the weakest one its answer gives (X = all obstacles not in that answer's set S, which
only claims that no subset of S frees o), and the enumeration starts again from the smallest size
(found on generated clutter, N = 50: the planner freed the target with O1 standing but not once
O1 was gone too, and a verified constraint hid the optimum of 2 relocations).

Budget and anytime answers (issue #30, item 4). ``max_planner_runs`` (real oracle runs, rechecks
included), ``time_limit_s`` and ``max_expansions`` (DFS nodes of the candidate enumeration)
bound the search; hitting one returns ``status='budget'`` with ``budget_hit`` naming it,
``certified=False`` (nothing is proven optimal), the INCUMBENT (the shortest feasible sequence
found so far, every step an oracle answer, or ``()``) and ``bound`` (= ``lower_bound``: no
feasible sequence is shorter; level, target included), proven when ``bound_certified`` (the
conditions above). Incumbents: once :data:`ANYTIME_SHARE` of any budget is spent without one,
each failed candidate (and each growth of k) is followed by a GREEDY COMPLETION from its feasible
prefix: ask the target, else relocate the first object that the target's unmet constraints (then
those objects' own) name, preferring objects already found feasible after a subset, until the
target goes or nothing more can; a completion spends at most :data:`COMPLETION_SHARE` of the
runs left. A search that ends within that share of its budgets never completes anything, so its
answers and runs are those of the plain search. An incumbent no longer than the bound is
optimal: the search stops there.

Nothing movable (item 4.2). A verification is a question the exact search never asks; in a scene
where no obstacle can go first, the exact search pays N + 1 runs (the target and each obstacle
after nothing) and this search would pay those answers plus their verifications. So before its
first verification, while no obstacle is known movable (feasible after nothing), :meth:`run`
asks the remaining "obstacle after nothing" questions, the objects that reports name first,
stopping at the first feasible one. If none is, nothing can ever be relocated: every answer gets
the trivial constraint (sound without verification) and the scene is proven unsolvable within
the exact search's N + 1 runs; else the verification goes on as before (the answers asked are
learned when the search reaches them, as if it had asked them itself).

Rechecks (item 4.3). An infeasible answer with reason ``IK_NOT_CONVERGED`` may be a false "no".
Before a final certificate (``unsolvable``, or an optimum's "no candidate is smaller"), when the
oracle has ``recheck(relocated, object_id)`` (more planning effort,
:func:`~qtree_task_planner.oracle.recheck_config`), the search drops every constraint that only
such unrechecked answers support and enumerates again: a candidate found then relies on them, and
the answers behind the constraints it breaks are rechecked (counted in ``rechecks``). A recheck
that stays infeasible confirms them; one that turns feasible removes the constraints it
supported and the search goes on from the smallest size. Verification answers carry no reason
and are not rechecked.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from itertools import combinations

from qtree_task_planner.exceptions import InvalidParameterError, InvalidScenarioError
from qtree_task_planner.oracle import (
    REASON_IK_NOT_CONVERGED,
    REASON_NONE,
    FeasibilityAnswer,
    FeasibilityOracle,
    SetKey,
    ask,
    ask_clear,
)

STATUS_OPTIMAL = 'optimal'
STATUS_UNSOLVABLE = 'unsolvable'
STATUS_BUDGET = 'budget'
BUDGET_RUNS = 'planner_runs'
BUDGET_TIME = 'time'
BUDGET_EXPANSIONS = 'expansions'
BUDGET_CANCELLED = 'cancelled'
ANYTIME_SHARE = 0.5  # share of a budget spent without an incumbent that starts completions [-]
COMPLETION_SHARE = 0.75  # most of the runs left that one greedy completion may spend [-]


@dataclass(frozen=True, kw_only=True)
class BlockerSearchConfig:
    """Budget and options of one search.

    Attributes:
        max_planner_runs: real oracle runs allowed (> 0).
        time_limit_s: wall-time cap [s] (> 0), checked between queries and DFS nodes.
        max_expansions: DFS nodes of the candidate enumeration allowed (> 0).
        verify: 'auto' (verify reports unless the oracle declares ``sound_blockers``), 'always'
            or 'never' (heuristic unless the reports are sound).
    """

    max_planner_runs: int = 5000
    time_limit_s: float = 120.0
    max_expansions: int = 200_000
    verify: str = 'auto'

    def __post_init__(self) -> None:
        """Validate every field.

        Raises:
            InvalidParameterError: a field out of range (names the field).
        """
        if self.max_planner_runs <= 0:
            raise InvalidParameterError('max_planner_runs', self.max_planner_runs, 'must be > 0')
        if not self.time_limit_s > 0.0:
            raise InvalidParameterError('time_limit_s', self.time_limit_s, 'must be > 0')
        if self.max_expansions <= 0:
            raise InvalidParameterError('max_expansions', self.max_expansions, 'must be > 0')
        if self.verify not in ('auto', 'always', 'never'):
            raise InvalidParameterError('verify', self.verify, "must be 'auto', 'always', 'never'")


@dataclass(frozen=True, kw_only=True)
class BlockerSearchResult:
    """Outcome of one search.

    Attributes:
        sequence: obstacles in relocation order, then the target: the optimum when ``optimal``,
            the incumbent (best found so far, or ``()``) when ``budget``, ``()`` when
            ``unsolvable``.
        status: ``'optimal'``, ``'unsolvable'`` or ``'budget'``.
        lower_bound: no feasible sequence is shorter than this level (target included;
            ``len(sequence)`` when optimal, 0 when unsolvable); kept for compatibility.
        certified: the status is proven (optimum, or no sequence at all) under Assumption 2 and
            monotonicity: every constraint was sound (declared or verified); always False for
            ``budget`` (see ``bound_certified``); False otherwise: heuristic.
        budget_hit: ``''``, ``'planner_runs'``, ``'time'`` or ``'expansions'``.
        bound: the same level as ``lower_bound`` (``len(sequence) >= bound`` for an incumbent).
        bound_certified: ``bound`` is proven (same conditions as ``certified``; equal to it
            unless the budget ran out).
        rechecks: ``IK_NOT_CONVERGED`` answers rechecked with more effort (real runs).
        completions: greedy completions tried (see the module docstring).
        planner_runs: real oracle runs of this search (verifications and rechecks included).
        queries: questions asked to the oracle (cached repeats excluded).
        verifications: of those, soundness checks of reports.
        contradictions: constraints contradicted by a known feasible answer (non-monotone
            feasibility: the result is then a heuristic, ``certified=False``).
        candidates: candidate sets tested with real queries.
        expansions: DFS nodes of the candidate enumeration.
        constraints: constraints learned.
        relevant: objects named in constraints (the only ones that may enter a candidate).
        wall_time_s: duration [s].
    """

    sequence: tuple[str, ...]
    status: str
    lower_bound: int
    certified: bool
    budget_hit: str
    planner_runs: int
    queries: int
    verifications: int
    contradictions: int
    candidates: int
    expansions: int
    constraints: int
    relevant: int
    wall_time_s: float
    bound: int = 0
    bound_certified: bool = False
    rechecks: int = 0
    completions: int = 0

    @property
    def solved(self) -> bool:
        """A feasible sequence ending with the target was found."""
        return bool(self.sequence)


class _SearchStop(Exception):  # noqa: N818 (a control-flow signal, not an error)
    """The search's own budget (runs, time, expansions) is used up or it was cancelled: unwinds
    to :func:`blocker_search`, which returns the incumbent. Never leaves this module.
    """

    def __init__(self, which: str) -> None:
        self.which = which


class _CompletionStopError(Exception):
    """A greedy completion spent its share of the runs."""


class BlockerSearch:
    """One search (see the module docstring); state readable after :meth:`run`.

    Args:
        obstacle_ids: the obstacles, in scenario order (deterministic tie-breaking).
        target_id: the target T.
        oracle: any feasibility oracle; blocker reports are read through
            :func:`~qtree_task_planner.oracle.ask`.
        config: budget and options.
        on_candidate: called after each tested candidate and each greedy completion with the
            objects walked (the last may have failed) and whether the target was reached;
            returning False cancels the search (``budget_hit='cancelled'``).

    Raises:
        InvalidScenarioError: the target is an obstacle, or duplicate ids.
    """

    def __init__(
        self,
        obstacle_ids: tuple[str, ...],
        target_id: str,
        oracle: FeasibilityOracle,
        config: BlockerSearchConfig | None = None,
        on_candidate: Callable[[tuple[str, ...], bool], bool] | None = None,
    ) -> None:
        obstacles = tuple(obstacle_ids)
        if target_id in obstacles:
            raise InvalidScenarioError(f'target {target_id!r} is also listed as an obstacle')
        if len(set(obstacles)) != len(obstacles):
            raise InvalidScenarioError('duplicate obstacle ids')
        self.obstacles = obstacles
        self.target = target_id
        self.oracle = oracle
        self.config = config or BlockerSearchConfig()
        self.on_candidate = on_candidate
        self.rank = {o: i for i, o in enumerate(obstacles)}
        self.all = frozenset(obstacles)
        sound = bool(getattr(oracle, 'sound_blockers', False))
        self.verify = self.config.verify == 'always' or (
            self.config.verify == 'auto' and not sound
        )
        self.certified = sound or self.verify
        self.constraints: dict[str, list[frozenset[str]]] = {}
        self.answers: dict[SetKey, FeasibilityAnswer] = {}
        self._clear: dict[SetKey, bool] = {}
        self.queries = self.verifications = self.candidates = self.expansions = 0
        self.contradictions = 0
        self._origin: dict[tuple[str, frozenset[str]], list[frozenset[str]]] = {}  # -> its sets S
        self._weakest: set[tuple[str, frozenset[str]]] = set()  # repaired: never again
        self._standing: dict[str, list[frozenset[str]]] = {}  # obstacles standing, o feasible
        self._restart = False  # a repair weakened a constraint: enumerate from the smallest size
        self.lower_bound = 1
        self._cut = False
        self._failed: dict[frozenset[str], bool] = {}
        self.incumbent: tuple[str, ...] = ()  # shortest feasible sequence found (target last)
        self.rechecks = self.completions = 0
        self._rechecked: set[SetKey] = set()
        read = getattr(oracle, 'recheck', None)
        usable = callable(read) and bool(getattr(oracle, 'can_recheck', True))
        self._recheck: Callable[[tuple[str, ...], str], FeasibilityAnswer] | None = (
            read if usable else None
        )
        self._guard = False  # run(): exhaust "after nothing" before the first verification
        self._movable = False  # some obstacle was found feasible after nothing
        self._nothing_movable = False  # every obstacle was found infeasible after nothing
        self._prefix: tuple[str, ...] = ()  # feasible prefix of the last failed candidate
        self._cap: int | None = None  # runs count at which a completion stops
        self._completed: set[frozenset[str]] = set()  # prefixes completed from
        self._runs0 = oracle.planner_runs
        self._start = time.monotonic()

    # -- oracle with constraints --

    def _runs(self) -> int:
        return self.oracle.planner_runs - self._runs0

    def _check_budget(self) -> None:
        if self._runs() >= self.config.max_planner_runs:
            raise _SearchStop(BUDGET_RUNS)
        if time.monotonic() - self._start > self.config.time_limit_s:
            raise _SearchStop(BUDGET_TIME)
        if self._cap is not None and self._runs() >= self._cap:
            raise _CompletionStopError

    def _hurry(self) -> bool:
        """:data:`ANYTIME_SHARE` of some budget is spent and no incumbent is known."""
        c, share = self.config, ANYTIME_SHARE
        return not self.incumbent and (
            self._runs() >= share * c.max_planner_runs
            or time.monotonic() - self._start >= share * c.time_limit_s
            or self.expansions >= share * c.max_expansions
        )

    def _ask(self, order: tuple[str, ...], obj: str) -> FeasibilityAnswer:
        key = (frozenset(order), obj)
        if key not in self.answers:
            self._check_budget()
            self.queries += 1
            self.answers[key] = ask(self.oracle, order, obj)
            if self.answers[key].feasible:
                self._standing.setdefault(obj, []).append(self.all - key[0] - {obj})
                self._movable = self._movable or (not key[0] and obj != self.target)
        return self.answers[key]

    def _verify(self, rest: tuple[str, ...], obj: str) -> bool:
        """Verification query: ``obj`` feasible once ``rest`` are gone, empty drop zone."""
        key = (frozenset(rest), obj)
        if key not in self._clear:
            self._check_budget()
            self.queries += 1
            self.verifications += 1
            self._clear[key] = ask_clear(self.oracle, rest, obj)
            if self._clear[key]:
                self._standing.setdefault(obj, []).append(self.all - key[0] - {obj})
        return self._clear[key]

    def _met(self, obj: str, done: frozenset[str]) -> bool:
        """Every known constraint of ``obj`` is met by ``done``."""
        return all(c & done for c in self.constraints.get(obj, ()))

    def query(self, order: tuple[str, ...], obj: str) -> bool:
        """Can ``obj`` be relocated after ``order``? Known constraints answer without a query; an
        infeasible answer adds a (sound, or verified, or trivial) constraint.
        """
        done = frozenset(order)
        if not self._met(obj, done):
            return False
        answer = self._ask(order, obj)
        if not answer.feasible:
            self._learn(done, obj, answer.blocking_ids)
        return answer.feasible

    def _learn(self, done: frozenset[str], obj: str, blockers: tuple[str, ...] | None) -> None:
        trivial = self.all - done - {obj}
        if blockers is None:
            blocking = trivial
        else:
            blocking = frozenset(blockers) & self.all - done - {obj}
            narrow = self._narrow(done, obj, blocking)
            checks = self.verify and (narrow is not None or blocking != trivial)
            if checks and not self._may_verify():
                blocking = trivial  # nothing movable: sound without a verification
            elif narrow is not None and not (
                self.verify and self._verify(self._rest(narrow, obj), obj)
            ):
                blocking = narrow  # a sound (declared or verified) hitting set of the approaches
            elif (
                self.verify
                and blocking != trivial
                and self._verify(self._rest(blocking, obj), obj)
            ):
                blocking = trivial  # the report missed an approach
        if self._contradicted(obj, blocking):  # a known answer already refutes it
            self._uncertify()
            blocking = trivial
            self._weakest.add((obj, blocking))
        known = self.constraints.setdefault(obj, [])
        if blocking not in known:
            known.append(blocking)
        origins = self._origin.setdefault((obj, blocking), [])
        if done not in origins:
            origins.append(done)
        self._repair(obj)

    def _may_verify(self) -> bool:
        """Whether a verification may be paid: always outside :meth:`run` or once an obstacle
        is known movable; else first every remaining "obstacle after nothing" question (those
        named by reports first), so that a scene where nothing is movable costs no more runs
        than the exact search (see the module docstring). False: nothing is movable, and every
        answer after nothing has been given its trivial constraint.
        """
        if not self._guard or self._movable:
            return True
        if self._nothing_movable:
            return False
        empty: frozenset[str] = frozenset()
        while True:
            left = [o for o in self.obstacles if (empty, o) not in self.answers]
            if not left:
                break
            named: set[str] = set()
            for o in (self.target, *self.obstacles):
                answer = self.answers.get((empty, o))
                if answer is not None and answer.blocking_ids:
                    named.update(answer.blocking_ids)
            nxt = min(left, key=lambda o: (o not in named, self.rank[o]))
            if self._ask((), nxt).feasible:
                return True
        self._nothing_movable = True
        for o in (self.target, *self.obstacles):
            answer = self.answers.get((empty, o))
            if answer is not None and not answer.feasible:
                self._learn(empty, o, None)
        return False

    def _contradicted(self, obj: str, x: frozenset[str]) -> bool:
        """``obj`` was found feasible with every object of ``x`` standing (and maybe more): by
        monotonicity ``x`` could not then be a constraint. Repaired constraints are final.
        """
        if (obj, x) in self._weakest:
            return False
        return any(x <= p for p in self._standing.get(obj, ()))

    def _uncertify(self) -> None:
        self.certified = False
        self.contradictions += 1

    def _repair(self, obj: str) -> None:
        """Replace each contradicted constraint of ``obj`` by the weakest constraints of the
        answers it came from (all obstacles not in their set S; see the module docstring).
        """
        repaired: list[frozenset[str]] = []
        for x in self.constraints.get(obj, ()):
            weaker = [x]
            if self._contradicted(obj, x):
                self._uncertify()
                self._restart = True
                weaker = [self.all - done - {obj} for done in self._origin[(obj, x)]]
                for w, done in zip(weaker, self._origin[(obj, x)], strict=True):
                    self._weakest.add((obj, w))
                    self._origin.setdefault((obj, w), [done])
            repaired += [w for w in weaker if w not in repaired]
        self.constraints[obj] = repaired

    def _rest(self, keep: frozenset[str], obj: str) -> tuple[str, ...]:
        """Every obstacle but ``keep`` and ``obj`` (the relocated set of a verification)."""
        return tuple(o for o in self.obstacles if o not in keep and o != obj)

    def _narrow(
        self, done: frozenset[str], obj: str, blocking: frozenset[str]
    ) -> frozenset[str] | None:
        """A smallest set meeting every approach's blockers, when the oracle reports them per
        approach (``approach_blockers``) and it differs from the report ``blocking`` and is no
        larger (the planner's union contains it; a one-approach report need not); else None.

        Each approach needs ALL of its blockers removed, so every set that frees ``obj`` meets
        every hitting set of the approaches' blocker sets: one object in front of the hand in
        every approach gives the constraint {that object} instead of the union of all.
        """
        read = getattr(self.oracle, 'approach_blockers', None)
        sets = read(tuple(sorted(done)), obj) if read is not None else None
        if not sets:
            return None
        sets = [frozenset(b) & self.all - done - {obj} for b in sets]
        if not all(sets):
            return None
        hitting = smallest_hitting_set(sets, self.rank)
        return hitting if hitting != blocking and len(hitting) <= len(blocking) else None

    # -- candidate enumeration --

    def _closure(self, chosen: frozenset[str]) -> list[str]:
        """An order of the objects of ``chosen`` meeting the known constraints, greedily."""
        order: list[str] = []
        done: frozenset[str] = frozenset()
        left = sorted(chosen, key=self.rank.__getitem__)
        progress = True
        while left and progress:
            progress = False
            for obj in left:
                if self._met(obj, done):
                    order.append(obj)
                    done = done | {obj}
                    left.remove(obj)
                    progress = True
                    break
        return order

    def _branch(self, chosen: frozenset[str], order: list[str]) -> list[str] | None:
        """Objects one of which every candidate containing ``chosen`` must add; None: ``chosen``
        is a candidate itself.
        """
        done = frozenset(order)
        if len(order) == len(chosen):
            unmet = [c for c in self.constraints.get(self.target, ()) if not c & done]
            if not unmet:
                return None
            fewest = min(unmet, key=len)
            return sorted(fewest, key=self.rank.__getitem__)
        union: set[str] = set()
        for obj in chosen - done:
            unmet = [c for c in self.constraints.get(obj, ()) if not c & done]
            union |= min(unmet, key=len) - chosen
        return sorted(union, key=self.rank.__getitem__)

    def _disjoint_unmet(self, chosen: frozenset[str], order: list[str]) -> int:
        """How many more objects any candidate containing ``chosen`` needs at least: a greedy
        packing of pairwise disjoint unmet constraints that no object of ``chosen`` can meet.
        """
        done = frozenset(order)
        needs = [c for c in self.constraints.get(self.target, ()) if not c & chosen]
        for obj in chosen - done:
            needs += [c for c in self.constraints.get(obj, ()) if not c & chosen]
        count, used = 0, set[str]()
        for c in sorted(needs, key=len):
            if not c & used:
                count += 1
                used |= c
        return count

    def _reachable(self) -> frozenset[str]:
        """Obstacles that may belong to some candidate: the least fixpoint of "every known
        constraint of o meets the set" grown from the empty set (an object never refused has no
        constraint and is in it). In a candidate's order each object's constraints are met by
        the objects before it, so by induction every candidate lies inside this set.
        """
        reach: set[str] = set()
        grown = True
        while grown:
            grown = False
            for obj in self.obstacles:
                if obj not in reach and all(c & reach for c in self.constraints.get(obj, ())):
                    reach.add(obj)
                    grown = True
        return frozenset(reach)

    def _candidate(self, k: int) -> list[str] | None:
        """The first candidate with at most ``k`` obstacles (in its order), or None.

        Sets shown to have no candidate superset of size <= k stay in ``self._failed`` until k
        grows: more constraints never create a candidate. Only objects of :meth:`_reachable`
        are branched on: a target constraint that none of them meets proves at once that no
        candidate exists (unsolvable), where plain branching would enumerate every cycle of
        mutually blocked objects up to size k.
        """
        failed = self._failed  # set -> whether the size bound cut its sub-tree
        reach = self._reachable()

        def dfs(chosen: frozenset[str]) -> tuple[list[str] | None, bool]:
            self.expansions += 1
            if self.expansions > self.config.max_expansions:
                raise _SearchStop(BUDGET_EXPANSIONS)
            if self.expansions % 256 == 0 and time.monotonic() - self._start > (
                self.config.time_limit_s
            ):
                raise _SearchStop(BUDGET_TIME)
            order = self._closure(chosen)
            branch = self._branch(chosen, order)
            if branch is None:
                return order, False
            branch = [o for o in branch if o in reach]
            if not branch:
                return None, False
            if len(chosen) >= k or len(chosen) + self._disjoint_unmet(chosen, order) > k:
                return None, True  # a larger candidate may exist
            cut = False
            for obj in branch:
                child = chosen | {obj}
                if child in failed:
                    cut = cut or failed[child]
                    continue
                found, child_cut = dfs(child)
                if found is not None:
                    return found, False
                failed[child] = child_cut
                cut = cut or child_cut
            return None, cut

        root: frozenset[str] = frozenset()
        if root in failed:
            self._cut = failed[root]
            return None
        found, self._cut = dfs(root)
        if found is None:
            failed[root] = self._cut
        return found

    def _test(self, order: list[str]) -> bool:
        """Relocate the candidate in its order, then the target; False at the first failure
        (its feasible prefix kept for a completion).
        """
        self.candidates += 1
        walked: list[str] = []
        reached = True
        for i, obj in enumerate((*order, self.target)):
            walked.append(obj)
            if not self.query(tuple(order[:i]), obj):
                reached = False
                self._prefix = tuple(order[:i])
                break
        if reached:
            self._keep((*order, self.target))
        self._report(tuple(walked), reached)
        return reached

    def _report(self, walked: tuple[str, ...], reached: bool) -> None:
        if self.on_candidate is not None and self.on_candidate(walked, reached) is False:
            raise _SearchStop(BUDGET_CANCELLED)

    def _keep(self, sequence: tuple[str, ...]) -> None:
        """``sequence`` (every step answered feasible) becomes the incumbent if shorter."""
        if not self.incumbent or len(sequence) < len(self.incumbent):
            self.incumbent = sequence

    # -- anytime: greedy completions --

    def _complete(self, prefix: tuple[str, ...]) -> None:
        """Greedy completion of the feasible ``prefix`` into an incumbent (module docstring),
        within :data:`COMPLETION_SHARE` of the runs left; every step is a real answer.
        """
        if frozenset(prefix) in self._completed:
            return
        self._completed.add(frozenset(prefix))
        self.completions += 1
        left = self.config.max_planner_runs - self._runs()
        self._cap = self._runs() + max(1, int(COMPLETION_SHARE * left))
        order = list(prefix)
        asked_target = reached = False
        try:
            while True:
                asked_target = False
                if self.query(tuple(order), self.target):
                    reached = True
                    break
                asked_target = True
                nxt = self._next_step(order)
                if nxt is None:
                    break
                order.append(nxt)
        except _CompletionStopError:
            pass
        finally:
            self._cap = None
        if reached:
            self._keep((*order, self.target))
        walked = (*order, self.target) if reached or asked_target else tuple(order)
        if walked:
            self._report(walked, reached)

    def _next_step(self, order: list[str]) -> str | None:
        """The first of :meth:`_next_objects` feasible after ``order`` (asked in turn; each
        failure adds a constraint, so the objects it names are tried next), or None.
        """
        while True:
            objects = self._next_objects(order)
            if not objects:
                return None
            if self.query(tuple(order), objects[0]):
                return objects[0]

    def _next_objects(self, order: list[str]) -> list[str]:
        """Objects a completion may relocate after ``order``: those that the target's unmet
        constraints name, smallest constraint first, then those that theirs name (breadth
        first); objects already found feasible after a subset of ``order`` first.
        """
        done = frozenset(order)
        seen: list[str] = []
        layer = [self.target]
        while layer:
            named: list[str] = []
            for obj in layer:
                unmet = [c for c in self.constraints.get(obj, ()) if not c & done]
                for c in sorted(unmet, key=len):
                    named += sorted(c - done - set(seen) - set(named), key=self.rank.__getitem__)
            seen += named
            layer = named

        def known_feasible(obj: str) -> bool:
            return any(
                k[1] == obj and a.feasible and k[0] <= done for k, a in self.answers.items()
            )

        usable = [
            o
            for o in seen
            if self._met(o, done) and self.answers.get((done, o), FeasibilityAnswer(True)).feasible
        ]
        return sorted(usable, key=lambda o: not known_feasible(o))

    # -- rechecks of IK_NOT_CONVERGED answers --

    def _suspect_answer(self, key: SetKey) -> bool:
        """An unrechecked ``IK_NOT_CONVERGED`` "no" of an oracle that can recheck."""
        answer = self.answers.get(key)
        return (
            self._recheck is not None
            and key not in self._rechecked
            and answer is not None
            and not answer.feasible
            and getattr(answer, 'reason', REASON_NONE) == REASON_IK_NOT_CONVERGED
        )

    def _suspects(self) -> dict[str, list[frozenset[str]]]:
        """Constraints that only suspect answers support (object -> constraints)."""
        found: dict[str, list[frozenset[str]]] = {}
        for obj, sets in self.constraints.items():
            for c in sets:
                origins = self._origin.get((obj, c), [])
                if origins and all(self._suspect_answer((d, obj)) for d in origins):
                    found.setdefault(obj, []).append(c)
        return found

    def _confirm(self, size: int | None) -> bool:
        """Recheck the suspect answers that the certificate "no candidate of at most ``size``
        obstacles" (None: of any size) relies on (module docstring). True: the certificate
        stands; False: a recheck turned feasible and the enumeration must start again.
        """
        if self._recheck is None or (size is not None and size < 0):
            return True
        limit = len(self.obstacles) if size is None else size
        while True:
            suspects = self._suspects()
            if not suspects:
                return True
            order = self._relaxed_candidate(limit, suspects)
            if order is None:
                return True
            keys = self._broken(order, suspects)
            if not keys:
                return True  # cannot happen: the full constraints allowed no candidate
            flipped = False
            for key in keys:
                flipped = self._recheck_answer(key) or flipped
            if flipped:
                return False

    def _relaxed_candidate(
        self, k: int, suspects: dict[str, list[frozenset[str]]]
    ) -> list[str] | None:
        """:meth:`_candidate` without the ``suspects`` constraints (state restored)."""
        saved = self.constraints, self._failed, self._cut
        self.constraints = {
            o: [c for c in sets if c not in suspects.get(o, ())]
            for o, sets in self.constraints.items()
        }
        self._failed = {}
        try:
            return self._candidate(k)
        finally:
            self.constraints, self._failed, self._cut = saved

    def _broken(self, order: list[str], suspects: dict[str, list[frozenset[str]]]) -> list[SetKey]:
        """The suspect answers behind the constraints that ``order`` (then the target) breaks."""
        keys: list[SetKey] = []
        done: frozenset[str] = frozenset()
        for obj in (*order, self.target):
            for c in suspects.get(obj, ()):
                if not c & done:
                    origins = self._origin.get((obj, c), [])
                    keys += [(d, obj) for d in origins if (d, obj) not in keys]
            done = done | {obj}
        return keys

    def _recheck_answer(self, key: SetKey) -> bool:
        """Recheck one answer (a real run); True when it turned feasible (constraints it
        alone supported removed).
        """
        done, obj = key
        self._check_budget()
        self.rechecks += 1
        self._rechecked.add(key)
        assert self._recheck is not None
        relocated = tuple(o for o in self.obstacles if o in done)
        answer = self._recheck(relocated, obj)
        if not answer.feasible:
            return False
        self.answers[key] = FeasibilityAnswer(True, ())
        for (o, _), origins in self._origin.items():
            if o == obj and done in origins:
                origins.remove(done)
        self.constraints[obj] = [
            c for c in self.constraints.get(obj, ()) if self._origin.get((obj, c))
        ]
        self._standing.setdefault(obj, []).append(self.all - done - {obj})
        self._movable = self._movable or (not done and obj != self.target)
        self._repair(obj)
        return True

    # -- driver --

    def run(self) -> BlockerSearchResult:
        """Search until the optimum, a proof of unsolvability, or the budget (then the
        incumbent, if any).
        """
        self._guard = True
        try:
            return self._search()
        except _SearchStop as hit:
            return self._result(self.incumbent, STATUS_BUDGET, hit.which)
        finally:
            self._guard = False

    def _search(self) -> BlockerSearchResult:
        k = 0
        while k <= len(self.obstacles):
            self.lower_bound = k + 1
            if self.incumbent and len(self.incumbent) <= k + 1:  # nothing shorter: optimal
                if self._confirm(len(self.incumbent) - 2):
                    return self._result(self.incumbent, STATUS_OPTIMAL, '')
                k, self._failed = 0, {}
                continue
            order = self._candidate(k)
            if order is None:
                if not self._cut:  # no candidate of any size: unsolvable
                    if self._confirm(None):
                        break
                    k, self._failed = 0, {}
                    continue
                if self._hurry():
                    self._complete(self._prefix)
                k += 1
                self._failed = {}
                continue
            if self._test(order):
                if self._confirm(len(order) - 1):
                    return self._result((*order, self.target), STATUS_OPTIMAL, '')
                k, self._failed = 0, {}
                continue
            if self._hurry():
                self._complete(self._prefix)
            if self._restart:  # weaker constraints: smaller candidates may exist again
                k, self._failed, self._restart = 0, {}, False
        self.lower_bound = 0
        return self._result((), STATUS_UNSOLVABLE, '')

    def _result(self, sequence: tuple[str, ...], status: str, hit: str) -> BlockerSearchResult:
        relevant = {o for sets in self.constraints.values() for c in sets for o in c}
        bound = len(sequence) if status == STATUS_OPTIMAL else self.lower_bound
        return BlockerSearchResult(
            sequence=sequence,
            status=status,
            lower_bound=bound,
            certified=self.certified and status != STATUS_BUDGET,
            budget_hit=hit,
            planner_runs=self._runs(),
            queries=self.queries,
            verifications=self.verifications,
            contradictions=self.contradictions,
            candidates=self.candidates,
            expansions=self.expansions,
            constraints=sum(len(v) for v in self.constraints.values()),
            relevant=len(relevant),
            wall_time_s=time.monotonic() - self._start,
            bound=bound,
            bound_certified=self.certified,
            rechecks=self.rechecks,
            completions=self.completions,
        )


def smallest_hitting_set(
    sets: list[frozenset[str]], rank: dict[str, int], exact_up_to: int = 4
) -> frozenset[str]:
    """A set meeting every one of ``sets`` (all non-empty): a smallest one when some has at most
    ``exact_up_to`` objects (tried in ``rank`` order), else the greedy one (most sets met first).
    """
    universe = sorted(set().union(*sets), key=rank.__getitem__)
    for size in range(1, min(exact_up_to, len(universe)) + 1):
        for combo in combinations(universe, size):
            chosen = frozenset(combo)
            if all(b & chosen for b in sets):
                return chosen
    greedy: set[str] = set()
    left = list(sets)
    while left:
        best = max(universe, key=lambda o: (sum(o in b for b in left), -rank[o]))
        greedy.add(best)
        left = [b for b in left if best not in b]
    return frozenset(greedy)


def blocker_search(
    obstacle_ids: tuple[str, ...],
    target_id: str,
    oracle: FeasibilityOracle,
    config: BlockerSearchConfig | None = None,
) -> BlockerSearchResult:
    """Run a :class:`BlockerSearch` (see there and the module docstring)."""
    return BlockerSearch(obstacle_ids, target_id, oracle, config).run()
