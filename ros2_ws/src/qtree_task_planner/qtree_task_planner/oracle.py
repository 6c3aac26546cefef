"""Feasibility oracles: who answers "can object o be relocated once S has been relocated?".

The Q-Tree only needs a binary answer (Sect. 3.2). Implementations:

* :class:`TableOracle`: a hand-built table, for unit tests and property tests only.
* :class:`MotionPlannerOracle`: the real in-process STPIK motion planner (imported lazily).
* :class:`MemoOracle`: memoises any oracle on the set key ``(frozenset(S), o)`` (Assumption 2) and
  counts the distinct keys it had to forward: the real planner runs of one training.
* The ROS client oracle (RelocateObject service) lives in ``task_planner_node``.

``planner_runs`` counts real planner runs (cache misses); ``queries`` counts every call.

Blocker extension (issue #14): an oracle may also implement ``answer(relocated, object_id)``,
returning a :class:`FeasibilityAnswer` ``(feasible, blocking_ids)``; :func:`ask` falls back to
``feasible()`` with ``blocking_ids=None`` (no report) for oracles that do not. For an infeasible
answer ``blocking_ids`` is a tuple of movable ids believed to stand in the way (``()``: blocked
by nothing movable, relocating others cannot help); ``None`` means no report (timeouts, planners
without blockers). ``sound_blockers`` on an oracle declares its reports SOUND: every set of objects
whose removal would make the object feasible contains at least one reported blocker (with
monotone feasibility: the object stays infeasible when every movable object except the reported
ones is removed). :class:`TableOracle` reports are sound; the planner's are not guaranteed, and
:mod:`qtree_task_planner.blocker_search` verifies them.

Verification queries (:func:`ask_clear`): "is o feasible once S is gone, placing it in the EMPTY
drop zone?". An oracle may implement ``clear_zone_feasible(relocated, object_id)`` for it; the
real planner does (drop slot 0, no placed objects standing), because its ordinary answer after a
large S plans into slot |S| among |S| placed envelopes, where the drop zone, not the clutter, can
say no: removing objects then stops being monotone and a verification would wrongly confirm a
blocker report. Oracles without it answer with ``feasible()``.

Rechecks (issue #30, item 4): an answer may carry the planner's reason code
(``FeasibilityAnswer.reason``, equal to ``stpik_motion_planner.result.Reason`` and the
``RelocateObject`` constants; :data:`REASON_NONE` when not given). An ``IK_NOT_CONVERGED`` "no"
may be false (the IK stalled where another seed converges), so an oracle may implement
``recheck(relocated, object_id)``: the same question planned again with more effort (the
in-process planner: :func:`recheck_config`). :mod:`qtree_task_planner.blocker_search` asks it
only for such answers that a final certificate relies on.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from itertools import accumulate
from typing import Any, NamedTuple, Protocol, runtime_checkable

SetKey = tuple[frozenset[str], str]
REASON_NONE = 0  # no reason given (or SUCCESS)
REASON_IK_NOT_CONVERGED = 202  # Reason.IK_NOT_CONVERGED, RelocateObject.IK_NOT_CONVERGED
RECHECK_IK_RESTARTS = 20  # random IK seeds of a recheck, at least [-] (default config: 5)
RECHECK_EFFORT = 4  # time limit, restarts and RRTConnect budget of a recheck, times [-]


class _Answer(NamedTuple):
    feasible: bool
    blocking_ids: tuple[str, ...] | None = None


class FeasibilityAnswer(_Answer):
    """One answer with its blockers (unpacks and compares as ``feasible, blocking_ids``).

    Args:
        feasible: the object can be relocated.
        blocking_ids: infeasible answers: movable ids in the way (``()``: nothing movable can
            help), or None when the oracle gave no report; ``()`` when feasible.
        reason: the planner's reason code (:data:`REASON_NONE` when not given); an attribute
            outside the tuple, so answers still unpack and compare as pairs.
    """

    reason: int = REASON_NONE

    def __new__(
        cls,
        feasible: bool,
        blocking_ids: tuple[str, ...] | None = None,
        reason: int = REASON_NONE,
    ) -> FeasibilityAnswer:
        """Build the pair and keep ``reason`` beside it."""
        self = super().__new__(cls, feasible, blocking_ids)
        self.reason = int(reason)
        return self

    def __getnewargs__(self) -> tuple[Any, ...]:
        """Pickle (process pools) with the reason."""
        return (self.feasible, self.blocking_ids, self.reason)

    def __repr__(self) -> str:
        """The pair, and the reason when one was given."""
        tail = f', reason={self.reason}' if self.reason != REASON_NONE else ''
        return f'FeasibilityAnswer({self.feasible!r}, {self.blocking_ids!r}{tail})'


def ask(oracle: Any, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
    """``oracle.answer(...)`` if the oracle reports blockers, else ``feasible()`` and no report."""
    answer = getattr(oracle, 'answer', None)
    if answer is not None:
        return answer(tuple(relocated), object_id)
    feasible = bool(oracle.feasible(tuple(relocated), object_id))
    return FeasibilityAnswer(feasible, () if feasible else None)


@runtime_checkable
class FeasibilityOracle(Protocol):
    """Answers feasibility queries (the motion-planner layer of Figure 2)."""

    @property
    def planner_runs(self) -> int:
        """Real planner runs so far (cache misses)."""
        ...

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Can ``object_id`` be grasped and relocated once ``relocated`` are gone?

        Raises:
            OracleUnavailableError: no answer (only oracles that talk to another process).
        """
        ...


class TableOracle:
    """Hand-built feasibility: an object is feasible once ANY of its clearing sets is relocated.

    Args:
        requirements: object id -> list of clearing sets (each an iterable of object ids). An
            object absent from the mapping is always feasible; an object mapped to ``[]`` never is.

    Example:
        ``TableOracle({'T': [{'O1', 'O2'}, {'O3'}], 'O1': [{'O3'}]})``: T needs O1 and O2 gone, or
        O3 gone; O1 needs O3 gone.
    """

    def __init__(
        self, requirements: Mapping[str, Sequence[Iterable[str]]], *, report: str = 'union'
    ) -> None:
        if report not in ('union', 'fewest', 'none'):
            raise ValueError(f"report must be 'union', 'fewest' or 'none', got {report!r}")
        self.requirements = {o: [frozenset(s) for s in sets] for o, sets in requirements.items()}
        self.report = report
        self.sound_blockers = report == 'union'
        self.planner_runs = 0
        self.queries = 0
        self._seen: set[SetKey] = set()

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """True if some clearing set of ``object_id`` is contained in ``relocated``."""
        return self.answer(relocated, object_id).feasible

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """Feasibility and blockers: with ``report='union'`` (sound and complete) the objects of
        every clearing set not yet relocated; ``'fewest'`` only those of the clearing set with
        the fewest left (like the planner's "most promising approach", not sound); ``'none'``
        no report.
        """
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self._seen:
            self._seen.add(key)
            self.planner_runs += 1
        if object_id not in self.requirements:
            return FeasibilityAnswer(True, ())
        done = key[0]
        needs = self.requirements[object_id]
        if any(need <= done for need in needs):
            return FeasibilityAnswer(True, ())
        if self.report == 'none':
            return FeasibilityAnswer(False, None)
        left = [sorted(need - done) for need in needs]
        if self.report == 'fewest':
            fewest: list[str] = min(left, key=len) if left else []
            return FeasibilityAnswer(False, tuple(fewest))
        return FeasibilityAnswer(False, tuple(sorted({o for need in left for o in need})))

    def approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[frozenset[str], ...] | None:
        """Each clearing set minus ``relocated`` (the planner's per-approach blockers' analogue;
        exact, so as sound as the ``'union'`` report); None with ``report='none'`` or when the
        object is feasible or has no clearing set.
        """
        needs = self.requirements.get(object_id)
        done = frozenset(relocated)
        if self.report == 'none' or not needs or any(need <= done for need in needs):
            return None
        return tuple(need - done for need in needs)


def ask_clear(oracle: Any, relocated: tuple[str, ...], object_id: str) -> bool:
    """Is ``object_id`` feasible once ``relocated`` are gone, placing it in the empty drop zone?

    Uses ``oracle.clear_zone_feasible`` when the oracle has it, else ``oracle.feasible``.
    """
    clear = getattr(oracle, 'clear_zone_feasible', None)
    if clear is None:
        return bool(oracle.feasible(tuple(relocated), object_id))
    return bool(clear(tuple(relocated), object_id))


class MemoOracle:
    """Memoise another oracle on ``(frozenset(relocated), object_id)``.

    Args:
        inner: the oracle asked on a cache miss.

    Attributes:
        planner_runs: distinct set keys forwarded to ``inner`` (what a fresh planner with a set
            cache would have run).
        queries: every call.
        results: the memo, set key -> feasible.
        rechecks: the memo of :meth:`recheck`, set key -> answer.
    """

    def __init__(self, inner: FeasibilityOracle) -> None:
        self.inner = inner
        self.planner_runs = 0
        self.queries = 0
        self.results: dict[SetKey, bool] = {}
        self.answers: dict[SetKey, FeasibilityAnswer] = {}
        self.clear_results: dict[SetKey, bool] = {}
        self.rechecks: dict[SetKey, FeasibilityAnswer] = {}
        self.sound_blockers = bool(getattr(inner, 'sound_blockers', False))

    def clear_zone_feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Verification query (:func:`ask_clear`), memoised and counted like the others; the
        ordinary memoised answer when ``inner`` has no verification query of its own.
        """
        if not hasattr(self.inner, 'clear_zone_feasible'):
            return self.feasible(relocated, object_id)
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self.clear_results:
            self.clear_results[key] = ask_clear(self.inner, tuple(relocated), object_id)
            self.planner_runs += 1
        return self.clear_results[key]

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Answer from the memo, or ask ``inner`` once."""
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self.results:
            self.results[key] = bool(self.inner.feasible(tuple(relocated), object_id))
            self.planner_runs += 1
        return self.results[key]

    @property
    def can_recheck(self) -> bool:
        """``inner`` has a :meth:`recheck` of its own (else this one is not offered)."""
        return callable(getattr(self.inner, 'recheck', None))

    def recheck(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """``inner``'s recheck, once per pair (a real run); a feasible one updates the memo.

        Raises:
            AttributeError: ``inner`` has no recheck (see :attr:`can_recheck`).
        """
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self.rechecks:
            recheck = getattr(self.inner, 'recheck')  # noqa: B009 (see can_recheck)
            self.rechecks[key] = recheck(tuple(relocated), object_id)
            self.planner_runs += 1
            if self.rechecks[key].feasible:
                self.results[key] = True
                self.answers[key] = self.rechecks[key]
        return self.rechecks[key]

    def approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[frozenset[str], ...] | None:
        """``inner``'s per-approach blockers of a pair already asked, or None (no run)."""
        read = getattr(self.inner, 'approach_blockers', None)
        return None if read is None else read(tuple(relocated), object_id)

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """Answer with blockers from the memo, or ask ``inner`` once (see :func:`ask`)."""
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self.answers:
            if self.results.get(key):
                self.answers[key] = FeasibilityAnswer(True, ())
            else:
                self.answers[key] = ask(self.inner, tuple(relocated), object_id)
                self.planner_runs += key not in self.results
                self.results[key] = self.answers[key].feasible
        return self.answers[key]


class MotionPlannerOracle:
    """The real in-process motion planner (``stpik_motion_planner.planner.MotionPlanner``).

    Args:
        scenario: a ``qtree_scene.scene.Scenario`` or an installed scenario name (``'s1'``).
        planner: an existing ``MotionPlanner`` to reuse (its cache persists across trainings).

    Attributes:
        planner_runs: planner answers not served from the planner's own cache.
        planning_time_s: total planning time reported by the planner [s].
    """

    def __init__(self, scenario: Any, planner: Any | None = None) -> None:
        if planner is None:
            from stpik_motion_planner.planner import MotionPlanner  # lazy: heavy imports

            if isinstance(scenario, str):
                from qtree_scene.scenario import load_scenario

                scenario = load_scenario(scenario)
            planner = MotionPlanner(scenario)
        self.scenario = scenario
        self.planner = planner
        self.planner_runs = 0
        self.queries = 0
        self.planning_time_s = 0.0
        self._approaches: dict[SetKey, tuple[frozenset[str], ...] | None] = {}

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Ask the planner (``check(object_id, relocated_ids)``) and count real runs."""
        return self.answer(relocated, object_id).feasible

    def clear_zone_feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """The planner's plan into drop slot 0 with no placed object standing (a real run)."""
        self.queries += 1
        self.planner_runs += 1
        result = self.planner.plan(object_id, list(relocated), slot_index=0)
        self.planning_time_s += float(getattr(result, 'planning_time', 0.0) or 0.0)
        return bool(result.feasible)

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """Ask the planner; blockers from the result's ``blocking_ids`` (issue #14, item 3).

        ``blocked_by_immovable`` gives ``()``; a result without blockers (a time-out, or a
        planner that names none) gives None: no report.
        """
        self.queries += 1
        result = self.planner.check(object_id, list(relocated))
        if not getattr(result, 'from_cache', False):
            self.planner_runs += 1
            self.planning_time_s += float(getattr(result, 'planning_time', 0.0) or 0.0)
        if result.feasible:
            return FeasibilityAnswer(True, ())
        key = (frozenset(relocated), object_id)
        self._approaches[key] = approach_blockers_of(result, relocated, object_id)
        union = self._all_approach_blockers(relocated, object_id)
        reason = int(getattr(result, 'reason', REASON_NONE) or REASON_NONE)
        if union is not None and not getattr(result, 'blocked_by_immovable', False):
            return FeasibilityAnswer(False, union, reason)
        return FeasibilityAnswer(False, blockers_of(result, relocated, object_id), reason)

    def recheck(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """The same question planned again with more effort (:func:`recheck_config`; a real
        run, the planner's cache bypassed): for an ``IK_NOT_CONVERGED`` "no" before a proof
        relies on it. A feasible answer replaces the cached one (its trajectory is verified
        like any other). Not thread-safe: the planner's config is swapped during the plan.

        Returns:
            The answer, without blockers (``None``) when infeasible, with its reason.
        """
        planner = self.planner
        effort = recheck_config(planner.config)
        self.queries += 1
        self.planner_runs += 1
        with planner.configured(effort):  # the planner and its STPIK solver
            result = planner.plan(object_id, list(relocated))
        self.planning_time_s += float(getattr(result, 'planning_time', 0.0) or 0.0)
        reason = int(getattr(result, 'reason', REASON_NONE) or REASON_NONE)
        if not result.feasible:
            return FeasibilityAnswer(False, None, reason)
        cache = getattr(planner, 'cache', None)
        if cache is not None:
            cache.put(object_id, list(relocated), result)
        self._approaches.pop((frozenset(relocated), object_id), None)
        return FeasibilityAnswer(True, (), reason)

    def approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[frozenset[str], ...] | None:
        """The blockers of every working approach of the last answer about this pair (no run).

        The finer form of :meth:`_all_approach_blockers`: the object needs every blocker of ONE
        approach removed, so any set meeting each of these sets is a constraint too
        (:class:`~qtree_task_planner.blocker_search.BlockerSearch` verifies the smallest). See
        :func:`approach_blockers_of`; None for a pair not asked yet.
        """
        return self._approaches.get((frozenset(relocated), object_id))

    def _all_approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[str, ...] | None:
        """Union over the planner's working approaches of their blockers, or None.

        The response field names only the most promising approach's blockers, which need not
        hit every approach; in process the planner's per-approach sweeps
        (``planner.blockers.sweeps``, issue #14 item 3) give the blockers of every approach, a
        report that is sound whenever the sweeps are. None when the planner has no sweeps.
        """
        finder = getattr(self.planner, 'blockers', None)
        sweeps = getattr(finder, 'sweeps', {}).get(object_id) if finder is not None else None
        if not sweeps:
            return None
        from stpik_motion_planner import blockers as module  # lazy: heavy imports

        done = frozenset(relocated) | {object_id}
        ids: set[str] = set()
        for sweep in sweeps:
            if sweep.works:
                ids.update(sweep.blockers(done, module.HIT_MARGIN_M))
        return tuple(sorted(ids)) or None


def recheck_config(config: Any) -> Any:
    """The "more effort" planner config of a recheck (``PlannerConfig.replace``).

    :data:`RECHECK_EFFORT` times the time limit (5 s -> 20 s), the random IK restarts of
    ``robust_stpik`` (5 -> 20, at least :data:`RECHECK_IK_RESTARTS`), the RRTConnect transit
    iterations and time cap (1000 -> 4000, 5 s -> 10 s; turned on when off) and twice the STPIK
    iterations per path sample (12 -> 24), each capped at the top of its range
    (``stpik_motion_planner.config.RANGES``). The restarts are drawn from the same seed, so the
    recheck tries the first answer's seeds and more.
    """
    restarts = max(RECHECK_IK_RESTARTS, RECHECK_EFFORT * int(config.ik_restarts))
    return config.replace(
        time_limit_s=min(600.0, RECHECK_EFFORT * float(config.time_limit_s)),
        ik_restarts=min(50, restarts),
        rrt_iterations=min(100_000, RECHECK_EFFORT * max(int(config.rrt_iterations), 250)),
        rrt_transit_s=min(10.0, RECHECK_EFFORT * max(float(config.rrt_transit_s), 1.0)),
        max_iterations=min(100, 2 * int(config.max_iterations)),
    )


def approach_blockers_of(
    result: Any, relocated: Sequence[str], object_id: str
) -> tuple[frozenset[str], ...] | None:
    """The per-approach blockers of an infeasible planner result (``approach_blockers``) or
    RelocateObject response (``approach_blocking_ids`` cut by ``approach_blocker_counts``).

    Returns:
        One set per working approach, ids already relocated and the object itself dropped; None
        when none is reported, the counts do not add up to the ids (a malformed response), or
        some approach names nobody (the planner failed where its sweep is clear: no model).
    """
    groups = getattr(result, 'approach_blockers', None)
    if groups is None:
        ids = list(getattr(result, 'approach_blocking_ids', ()) or ())
        counts = [int(c) for c in getattr(result, 'approach_blocker_counts', ()) or ()]
        if sum(counts) != len(ids):
            return None
        ends = accumulate(counts)
        groups = [ids[end - count : end] for count, end in zip(counts, ends, strict=True)]
    done = set(relocated) | {object_id}
    sets = tuple(frozenset(group) - done for group in groups)
    return sets if sets and all(sets) else None


def blockers_of(result: Any, relocated: Sequence[str], object_id: str) -> tuple[str, ...] | None:
    """The blocker report of an infeasible planner result or RelocateObject response.

    Reads ``blocking_ids`` and ``blocked_by_immovable`` (absent fields: no report); drops ids
    already relocated and the object itself.

    Returns:
        ``()`` when blocked by nothing movable, the ids, or None when nothing was reported.
    """
    if getattr(result, 'blocked_by_immovable', False):
        return ()
    ids = tuple(getattr(result, 'blocking_ids', ()) or ())
    done = set(relocated) | {object_id}
    ids = tuple(i for i in ids if i not in done)
    return ids or None
