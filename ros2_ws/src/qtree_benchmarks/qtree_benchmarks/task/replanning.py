"""Replanning benchmark (#32 item 6): a world change in the middle of a retrieval, in process.

One run: learn the retrieval of a scene with BLOCKER-SEARCH on the in-process motion planner,
execute (count as done) its first ``k`` relocations, then change the world before relocation
``k`` (:data:`EVENTS`), and recover as the ROS graph does (``goal_run.execute_with_replans`` and
``stpik_motion_planner.service``): a planner for the new scene, the old answers still true
carried over (:func:`stpik_motion_planner.answer_reuse.carry_over`), the rest of the retrieval
learned again from the current state (:class:`~qtree_task_planner.replanning.PrefixOracle`).

Measured per run (:class:`RunOutcome`):

* ``recovery_s``: wall time from the event to the next relocation's motion being ready (new
  planner, carry-over, re-plan). The ROS graph adds the arm's stop and its undo motion, and DDS.
* ``extra_planner_runs``: real planner runs of the re-plan (answers not from the cache).
* ``reused_share``: answers kept across the change / answers cached before it.
* ``violations``: the verifier (:class:`~stpik_motion_planner.verifier.TrajectoryVerifier`) run
  again, in the NEW scene, on every kept feasible answer and on every relocation executed after
  the event: each clearance violation counts (target 0).
* ``solvable``: whether a sequence still exists after the event (the re-plan's certified result,
  else the exact set search within a budget; None when neither decides).

No ROS import; the motion planner is imported lazily (heavy).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from statistics import mean, median
from typing import Any

import numpy as np
from qtree_scene.scenario import validate_scenario
from qtree_scene.scene import ObjectSpec, Scenario
from qtree_task_planner.blocker_search import BlockerSearchConfig, blocker_search
from qtree_task_planner.exact import solve_exact
from qtree_task_planner.exceptions import SearchLimitExceededError
from qtree_task_planner.oracle import MemoOracle, MotionPlannerOracle
from qtree_task_planner.replanning import PrefixOracle

EVENTS = ('moved_into_path', 'moved_out_of_way', 'object_added', 'target_moved', 'grasp_failure')
ADDED_ID = 'X1'
ADDED_RADIUS_M = 0.03  # the object an ``object_added`` event puts on the table [m]
ADDED_HEIGHT_M = 0.15
GAP_M = 0.01  # free distance kept between footprints when placing a moved object [m]
EXACT_MAX_SETS = 60  # budget of the exact search that decides ``solvable`` [sets]
SEARCH = BlockerSearchConfig(max_planner_runs=2000, time_limit_s=300.0)


@dataclass(frozen=True)
class RunOutcome:
    """One event run (see the module docstring for the measured quantities)."""

    scenario: str
    event: str
    seed: int
    step: int  # relocations executed before the event [-]
    changed: str  # what the event did, e.g. "'O4' moved 0.231 m"
    solvable: bool | None
    decided_by: str  # what decided ``solvable`` (:func:`decide_solvable`)
    retrieved: bool
    replans: int
    extra_planner_runs: int
    cached: int  # answers cached before the change [-]
    reused: int  # of them kept [-]
    recovery_s: float
    violations: int
    sequence: tuple[str, ...]  # the whole executed retrieval (prefix, then the re-plan's)
    kept_infeasible: int = 0  # kept infeasible answers, each planned again afresh [-]
    kept_infeasible_differ: int = 0  # of them, kept as replaying: answered otherwise afresh [-]
    kept_harder: int = 0  # of them, kept as their scene only gained bodies [-]
    kept_harder_feasible_afresh: int = 0  # of those, feasible for a fresh planner [-]
    kept_harder_reason_differs: int = 0  # of those, infeasible afresh for another reason [-]
    dropped_by: dict[str, int] = field(default_factory=dict)  # dropped answers by why [-]

    @property
    def reused_share(self) -> float:
        """Kept / cached answers [-] (1 with nothing cached)."""
        return self.reused / self.cached if self.cached else 1.0


def learn(planner: Any, prefix: Sequence[str], remaining: Iterable[str], target: str) -> Any:
    """BLOCKER-SEARCH for the rest of a retrieval after ``prefix``; its result (real planner
    runs in ``planner_runs``: answers served from ``planner``'s cache do not count).
    """
    oracle = MotionPlannerOracle(planner.scenario, planner)
    result = blocker_search(tuple(remaining), target, PrefixOracle(oracle, prefix), SEARCH)
    return dataclasses.replace(result, planner_runs=oracle.planner_runs)


def table_top(scenario: Scenario) -> float:
    """Height of the table's top face [m] (the bottom of the standing objects)."""
    obj = scenario.target
    half = obj.height / 2 if obj.shape == 'cylinder' else obj.size[2] / 2
    return obj.position[2] - half


def _radius(obj: ObjectSpec) -> float:
    """Radius of the footprint's enclosing circle [m]."""
    if obj.shape == 'cylinder':
        return obj.radius
    return math.hypot(obj.size[0], obj.size[1]) / 2


def _with(scenario: Scenario, objects: Iterable[ObjectSpec]) -> Scenario | None:
    """``scenario`` with ``objects`` (a valid scene), or None when it is not valid."""
    changed = dataclasses.replace(scenario, objects=tuple(objects))
    try:
        validate_scenario(changed)
    except ValueError:
        return None
    return changed


def place(
    scenario: Scenario, obj: ObjectSpec, spots: Iterable[tuple[float, float]]
) -> Scenario | None:
    """The scene with ``obj`` (new or moved, by id) at the roomiest of ``spots`` (x, y) [m]: the
    valid spot farthest from every other footprint (at least :data:`GAP_M`), as a person puts an
    object down where it fits rather than squeezed against its neighbours (a hand needs room for
    its fingers); None when no spot is valid.
    """
    others = [o for o in scenario.objects if o.id != obj.id and o.role != 'static']

    def room(xy: tuple[float, float]) -> float:
        gaps = [math.dist(o.position[:2], xy) - _radius(o) - _radius(obj) for o in others]
        return min(gaps, default=math.inf)

    ranked = sorted((xy for xy in spots if room(xy) > GAP_M), key=room, reverse=True)
    for x, y in ranked:
        moved = dataclasses.replace(obj, position=(float(x), float(y), obj.position[2]))
        scene = _with(scenario, [*(o for o in scenario.objects if o.id != obj.id), moved])
        if scene is not None:
            return scene
    return None


def spots_in_front(
    scenario: Scenario, of: ObjectSpec, radius_m: float
) -> list[tuple[float, float]]:
    """Spots (x, y) [m] between ``of`` and the robot's base, up to 15 cm in front of it and 4 cm
    aside: where an object of footprint radius ``radius_m`` stands in the way of a side approach
    to ``of``.
    """
    xy = np.asarray(of.position[:2], dtype=float)
    towards = -xy / np.linalg.norm(xy)
    side = np.array([-towards[1], towards[0]])
    first = _radius(of) + radius_m + GAP_M
    return [
        tuple(xy + d * towards + s * side)
        for d in np.arange(first, first + 0.15, 0.01)
        for s in (0.0, 0.02, -0.02, 0.04, -0.04)
    ]


def spots_around(
    centre: Sequence[float], rng: np.random.Generator, near_m: float, far_m: float, n: int = 400
) -> list[tuple[float, float]]:
    """``n`` random spots (x, y) [m] at ``near_m`` to ``far_m`` from ``centre``."""
    angle = rng.uniform(0.0, 2 * math.pi, n)
    dist = rng.uniform(near_m, far_m, n)
    return [
        (centre[0] + r * math.cos(a), centre[1] + r * math.sin(a))
        for a, r in zip(angle, dist, strict=True)
    ]


def apply_event(
    scenario: Scenario,
    event: str,
    sequence: Sequence[str],
    step: int,
    rng: np.random.Generator,
) -> tuple[Scenario, str] | None:
    """The scene after ``event`` strikes before relocation ``step`` of ``sequence``, and what
    changed; None when the event cannot happen there (no object to move, no free spot).

    Events: ``moved_into_path`` (an object still standing, not the next one, jumps in front of
    the next one), ``moved_out_of_way`` (an obstacle the plan still has to remove moves away
    from the target), ``object_added`` (a new cylinder in front of the next one),
    ``target_moved`` (the target slides 5 to 15 cm), ``grasp_failure`` (nothing moves: the grasp
    of the next one failed and was undone).
    """
    done = set(sequence[:step])
    next_id = sequence[step]
    standing = [o for o in scenario.objects if o.role == 'obstacle' and o.id not in done]
    target = scenario.target
    if event == 'grasp_failure':
        return scenario, f'grasp of {next_id!r} failed'
    if event == 'moved_into_path':
        later = [o for o in standing if o.id not in sequence]  # not planned: a new blocker
        pool = later or [o for o in standing if o.id != next_id]
        if not pool:
            return None
        obj = pool[int(rng.integers(len(pool)))]
        front = spots_in_front(scenario, scenario.object(next_id), _radius(obj))
        scene = place(scenario, obj, front)
        how = 'moved in front of'
    elif event == 'moved_out_of_way':
        pool = [o for o in standing if o.id in sequence[step:]]
        if not pool:
            return None
        obj = pool[int(rng.integers(len(pool)))]
        scene = place(scenario, obj, spots_around(target.position, rng, 0.30, 0.45))
        how = 'moved out of the way (still to be removed before)'
    elif event == 'object_added':
        z = table_top(scenario) + ADDED_HEIGHT_M / 2
        obj = ObjectSpec(
            ADDED_ID, 'obstacle', 'cylinder', (0.0, 0.0, z), radius=ADDED_RADIUS_M,
            height=ADDED_HEIGHT_M,
        )  # fmt: skip
        front = spots_in_front(scenario, scenario.object(next_id), ADDED_RADIUS_M)
        scene = place(scenario, obj, front)
        how = 'added in front of'
    elif event == 'target_moved':
        obj = target
        scene = place(scenario, obj, spots_around(target.position, rng, 0.05, 0.15))
        how = 'moved, before'
    else:
        raise ValueError(f'unknown event {event!r}, expected one of {EVENTS}')
    if scene is None:
        return None
    after = scene.object(obj.id)
    moved = math.dist(after.position, obj.position) if obj.id != ADDED_ID else 0.0
    what = f'{obj.id!r} {how} {next_id!r}' + (f' ({moved:.3f} m)' if moved else '')
    if event == 'moved_out_of_way':
        what = f'{obj.id!r} moved {moved:.3f} m out of the way (the plan still had to remove it)'
    return scene, what


def reverify(planner: Any, relocated: Iterable[str], object_id: str, result: Any) -> int:
    """Clearance violations of the feasible answer ``result`` checked again in ``planner``'s
    scene (its verifier, the bodies standing during that relocation) [-].
    """
    from stpik_motion_planner.verifier import Carried

    obj = planner.scenario.object(object_id)
    carried = Carried(obj, result.grasp_index, result.release_index)
    standing = planner.planning_scene(object_id, list(relocated))
    report = planner.verifier.verify(np.asarray(result.joint_trajectory), standing, carried)
    return len(report.violations)


def is_solvable(planner: Any, prefix: Sequence[str], remaining: Sequence[str], target: str):
    """Whether a retrieval exists after ``prefix`` (exact set search, cache shared with the
    re-plan); None when the search budget ran out.
    """
    oracle = MemoOracle(MotionPlannerOracle(planner.scenario, planner))
    try:
        found = solve_exact(
            tuple(remaining), target, PrefixOracle(oracle, prefix), max_sets=EXACT_MAX_SETS
        )
    except SearchLimitExceededError:
        return None
    return found.solvable


def decide_solvable(
    planner: Any, prefix: Sequence[str], remaining: Sequence[str], target: str, result: Any
) -> tuple[bool | None, str]:
    """Whether a retrieval still exists after the event, and what decided it: ``'re-plan'`` (it
    found one), ``'exact'`` (the exact set search within :data:`EXACT_MAX_SETS`), else
    ``'certificate'`` (BLOCKER-SEARCH's certified ``unsolvable``: sound under monotone
    feasibility) or ``'none'``.
    """
    if result.status == 'optimal':
        return True, 're-plan'
    exact = is_solvable(planner, prefix, remaining, target)
    if exact is not None:
        return exact, 'exact'
    if result.status == 'unsolvable' and result.certified:
        return False, 'certificate'
    return None, 'none'


def run_event(
    old: Any, sequence: Sequence[str], event: str, seed: int, make_planner: Any
) -> RunOutcome | None:
    """One run of ``event`` on the learned ``sequence`` of planner ``old`` (its cache full of the
    first training's answers); None when the event cannot happen in this scene.

    Args:
        old: the planner of the first training, its cache full.
        sequence: the learned sequence, the target last.
        event: the kind of world change (a key of the benchmark's events).
        seed: seed of the step and the change drawn.
        make_planner: ``make_planner(scenario)`` → a MotionPlanner (the benchmark's config).
    """
    from stpik_motion_planner.answer_reuse import HARDER, carry_over_answers

    rng = np.random.default_rng(seed)
    steps = range(len(sequence) - 1) if event == 'moved_out_of_way' else range(len(sequence))
    if not steps:
        return None
    step = int(rng.integers(steps.start, steps.stop))
    changed = apply_event(old.scenario, event, sequence, step, rng)
    if changed is None:
        return None
    scene, what = changed
    prefix = tuple(sequence[:step])
    cached = len(old.cache)
    start = time.perf_counter()
    if event == 'grasp_failure':  # no geometry changed: the node keeps its planner (and cache)
        planner, reused = old, cached
        why: dict[tuple[frozenset[str], str], str] = {}
        dropped: dict[tuple[frozenset[str], str], str] = {}
    else:
        planner = make_planner(scene)
        reuse = carry_over_answers(old, planner)
        why, dropped = reuse.kept, reuse.dropped
        reused = len(planner.cache)
    kept = list(planner.cache.items()) if planner is not old else []
    target = scene.target.id
    remaining = [o.id for o in scene.obstacles if o.id not in prefix]
    result = learn(planner, prefix, remaining, target)
    recovery_s = time.perf_counter() - start
    retrieved = result.status == 'optimal'
    solvable, decided_by = decide_solvable(planner, prefix, remaining, target, result)
    violations = sum(
        reverify(planner, relocated, object_id, answer)
        for (relocated, object_id), answer in kept
        if answer.feasible
    )
    # Each kept infeasible answer against a fresh planner's in the new scene (#32 item 4): one
    # kept as replaying must be the same answer, message and blockers included; one kept as
    # its scene only gained bodies must stay infeasible (its reason may differ).
    infeasible = [(key, answer) for key, answer in kept if not answer.feasible]
    fresh = make_planner(scene) if infeasible else planner
    differ = harder = harder_feasible = harder_reason = 0
    for (relocated, object_id), answer in infeasible:
        again = fresh.check(object_id, list(relocated))
        if why.get((relocated, object_id)) == HARDER:
            harder += 1
            harder_feasible += again.feasible
            harder_reason += not again.feasible and again.reason != answer.reason
        else:
            differ += not same_answer(answer, again)
    executed = [*prefix, *result.sequence]
    for i in range(len(prefix), len(executed) if retrieved else 0):
        answer = planner.check(executed[i], executed[:i])
        violations += (
            reverify(planner, executed[:i], executed[i], answer) if answer.feasible else 1
        )
    return RunOutcome(
        scenario=old.scenario.name,
        event=event,
        seed=seed,
        step=step,
        changed=what,
        solvable=solvable,
        decided_by=decided_by,
        retrieved=retrieved,
        replans=1,
        extra_planner_runs=result.planner_runs,
        cached=cached,
        reused=reused,
        recovery_s=round(recovery_s, 3),
        violations=violations,
        sequence=tuple(executed) if retrieved else (),
        kept_infeasible=len(infeasible),
        kept_infeasible_differ=differ,
        kept_harder=harder,
        kept_harder_feasible_afresh=harder_feasible,
        kept_harder_reason_differs=harder_reason,
        dropped_by=dict(Counter(dropped.values())),
    )


def same_answer(kept: Any, fresh: Any) -> bool:
    """Whether two answers agree: feasibility, reason, message and blockers."""
    fields = ('feasible', 'reason', 'message', 'blocking_ids', 'blocked_by_immovable')
    return all(getattr(kept, f) == getattr(fresh, f) for f in fields)


def summary_rows(outcomes: Sequence[RunOutcome]) -> list[dict[str, Any]]:
    """One row per (scenario, event) with the keys of #32 item 6.

    ``retrieved`` is the share of runs retrieved among those where a sequence still exists
    (``solvable`` true); ``reused_answers_share`` the mean kept / cached share.
    """
    rows = []
    keys = dict.fromkeys((o.scenario, o.event) for o in outcomes)
    for scenario, event in keys:
        runs = [o for o in outcomes if (o.scenario, o.event) == (scenario, event)]
        possible = [o for o in runs if o.solvable]
        rows.append(
            {
                'scenario': scenario,
                'event': event,
                'runs': len(runs),
                'retrieved': round(mean(o.retrieved for o in possible), 3) if possible else None,
                'replans_mean': round(mean(o.replans for o in runs), 2),
                'extra_planner_runs_mean': round(mean(o.extra_planner_runs for o in runs), 1),
                'reused_answers_share': round(mean(o.reused_share for o in runs), 3),
                'recovery_s_median': round(median(o.recovery_s for o in runs), 3),
            }
        )
    return rows
