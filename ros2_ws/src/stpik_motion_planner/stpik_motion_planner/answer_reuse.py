"""Keep the cached answers a scene change provably leaves true (#32 item 4; no ROS import).

When /scene changes (an object moved, added or removed under an execution, or between two
relocations) the motion planner is rebuilt and its cache (:mod:`.cache`) starts empty: every
question of the re-plan would be planned again. :func:`carry_over` instead moves into the new
planner's cache every answer of the old one that cannot depend on the change, by this rule
(:func:`judge`; anything else is dropped and planned again when asked):

Scene-level conditions (else nothing is kept): same scene name, drop zone and home; no changed
object is static (the target is an object like the others for the answers of the others).

Per answer ``(R, o)``: ``o`` did not change, and an object of ``R`` changed only by a move (same
shape, size and role, :func:`moved_only`: while ``(R, o)`` is planned it stands in its drop slot
as an envelope of R's sizes, wherever it stood on the table, so its table pose is not part of
the answer's planning scene; the changed objects that count for the answer are the others, its
*standing* changes); the drop slots 0 … |R|
(:func:`qtree_scene.placement.drop_slots`, which depend on every clutter object) are the same
before and after: the answer places ``o`` in slot |R| (the blocker sweeps use slot 0) and plans
around the envelopes of R in slots 0 … |R|−1; and

* **feasible**: the answer's motion, verified again by the planner's own
  :class:`~.verifier.TrajectoryVerifier` among the changed objects as they stand NOW (those of
  the new scene; removed ones are gone), keeps the verifier's clearance from all of them
  (:func:`clear_of_changes`). WHY it is still true: the planning scene of ``(R, o)`` differs from
  the old one only by the changed objects (R and o are unchanged, so are the drop-slot envelopes
  of R); the trajectory was verified against every other body when it was planned, and is now
  verified against the changed ones, with the same sampling and clearance bounds. A body that
  moved away or disappeared cannot make it collide. So the same trajectory is a verified motion
  in the new scene, and its placement slot is the same: the answer would pass the check a new
  plan must pass. (It replaced a swept-volume test of the arm's bounding boxes, which dropped
  almost every answer in the clutter: the boxes of a carry over the table hold most of it.)
* **infeasible, OBJECT_TOO_BIG**: decided from ``o``'s size and the hand only (o unchanged).
* **any other infeasible answer** (the planner's search failed, ``blocked_by_immovable`` too:
  RRT-connect detours, IK restarts, every approach) when its plan would go exactly as it went
  (:func:`replays`): the plan recorded every scene query it made (:mod:`.footprint`); no object
  one of them met changed, no changed object as it stands now comes within reach of one of
  them, the unchanged objects keep their order and the tallest movable object standing (it sets
  the carry height) is as high. WHY it is still true: each query of the plan, asked again in
  the new scene, finds the same objects within its threshold in the same order (its result
  depends on those only), so each computation step, and the answer, is the same bit for bit
  (the planner is deterministic: its random restarts and RRT-connect are seeded by the
  question, :func:`.rrt_connect.question_seed`). Its blockers are derived again from the sweeps
  (:meth:`.blockers.BlockerFinder.adopt`). Answers whose plan was not wholly recorded (the
  verifier ran, a memo result without its queries) are dropped.
  (``blocked_by_immovable`` answers were kept on their own before: the statics-only sweeps try
  every other approach only, and the answer's message names the movable objects in the way,
  which a fresh planner then named otherwise: the replanning benchmark's fresh re-check found it.)
* **a planning failure (2xx) whose scene only gained bodies** (:func:`only_gains`): each
  standing change is a body added to the answer's planning scene, and each body it replaced
  (an object moved) was never met by a recorded query of the plan; the tallest movable object
  standing is as high before, after and without those bodies; the blocker sweeps are at hand to
  name its blockers again. WHY it is still true: take the old planning scene S0 without the
  replaced bodies, S'. The plan in S' makes the same queries with the same results as in S0
  (no query met a body taken away, the others keep their order, the carry height is the same),
  so it is the same computation and finds no motion in S' either. The new planning scene S1 is
  S' plus bodies (the same drop slots and envelopes, the same carry height), so its free space
  is a subset of the free space of S': every motion collision-free now was collision-free in S',
  where the plan, over every approach with its fallbacks, found none. The answer is as true as
  it was; only its blockers can differ, and they are derived again from the sweeps, which
  measure the changed bodies along their motions. Its plan now may fail otherwise (another
  reason or message); the replanning benchmark counts how often, and how often a fresh planner
  finds a motion the first did not (``kept_harder_*``). Its recorded queries no longer show
  what a plan in the new scene would look at, so it can get harder again but never replays.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping, Sequence, Set
from typing import Any, NamedTuple

import numpy as np
from qtree_scene.placement import drop_slots, top_place_slots
from qtree_scene.scene import ObjectSpec, Scenario

from stpik_motion_planner.footprint import PlannedAnswer
from stpik_motion_planner.result import PlanResult, Reason, ReasonFamily, reason_family
from stpik_motion_planner.verifier import Carried

CacheKey = tuple[frozenset[str], str]
# Why an answer is kept (:func:`judge`) ...
VERIFIED_AGAIN = 'its verified motion verified again among the changed objects as they are now'
SIZE_ONLY = "decided by the object's size and the hand only"
REPLAYED = 'its plan, asked again, makes the same scene queries (none meets a change)'
HARDER = 'its planning scene only gained bodies: no motion is possible now that was not then'
# ... or dropped.
DROPPED_OBJECT = 'its object changed'
DROPPED_RELOCATED = 'an object of its relocated set changed other than by a move'
DROPPED_SLOTS = 'a drop slot it uses changed'
DROPPED_NOT_CLEAR = 'its motion is not clear of the changed objects as they are now'
DROPPED_PLAN = 'its plan may go otherwise (it met a changed object, or a change may meet it)'


class Verdict(NamedTuple):
    """Whether a cached answer is kept across a scene change, and why (or why not)."""

    kept: bool
    why: str


@dataclasses.dataclass(frozen=True)
class Reuse:
    """The cached answers a scene change leaves true (:func:`reuse_answers`).

    Attributes:
        kept: why each kept answer is still true, by cache key.
        dropped: why each other answer was dropped, by cache key (empty when the scene-level
            conditions already dropped all: the summary says why).
        summary: one line for the log, e.g. ``'kept 3 of 5 cached answers (changed: O2)'``.
    """

    kept: dict[CacheKey, str]
    dropped: dict[CacheKey, str]
    summary: str


def changed_objects(old: Scenario, new: Scenario) -> tuple[set[str], list[ObjectSpec]]:
    """Ids that moved, appeared or disappeared, and their specs before and after (both)."""
    before = {o.id: o for o in old.objects}
    after = {o.id: o for o in new.objects}
    ids = {i for i in before.keys() | after.keys() if before.get(i) != after.get(i)}
    specs = [d[i] for i in sorted(ids) for d in (before, after) if i in d]
    return ids, specs


def moved_only(old: Scenario, new: Scenario, ids: set[str]) -> set[str]:
    """The ids of ``ids`` that only moved: in both scenes, with the same spec but for the
    position and yaw (same shape, size and role: the same envelope in a drop slot,
    :func:`qtree_scene.placement.occupied_envelopes`).
    """
    before = {o.id: o for o in old.objects}
    after = {o.id: o for o in new.objects}
    return {
        i
        for i in ids
        if i in before
        and i in after
        and dataclasses.replace(before[i], position=after[i].position, yaw=after[i].yaw)
        == after[i]
    }


def scene_blocks_reuse(old: Scenario, new: Scenario, changed: list[ObjectSpec]) -> str:
    """Why no answer of ``old`` may be kept in ``new`` ('' when the per-answer rule applies)."""
    if old.name != new.name:
        return f'another scene ({old.name!r} -> {new.name!r})'
    if old.drop_zone_center != new.drop_zone_center or tuple(old.home) != tuple(new.home):
        return 'drop zone or home changed'
    for obj in changed:
        if obj.role == 'static':  # the statics-only blocker sweeps and the immovable reasons
            return f'{obj.role} {obj.id!r} changed'
    return ''


def same_slots(old: Scenario, new: Scenario, families: Sequence[str] = ('side',)) -> int:
    """How many leading drop slots (in relocation order) ``old`` and ``new`` share [-]: of
    :func:`~qtree_scene.placement.drop_slots` and, for a planner whose grasp ``families``
    include ``'top'``, of both lists of :func:`~qtree_scene.placement.top_place_slots` (the
    fewest).
    """

    def leading(a: Sequence, b: Sequence) -> int:
        count = 0
        for x, y in zip(a, b, strict=False):
            if x != y:
                break
            count += 1
        return count

    lists = [(drop_slots(old), drop_slots(new))]
    if 'top' in families:
        lists += zip(top_place_slots(old), top_place_slots(new), strict=True)
    return min(leading(a, b) for a, b in lists)


def same_order(old: Scenario, new: Scenario, changed: set[str]) -> bool:
    """Whether the objects not in ``changed`` come in the same order in both scenes (the
    scene worlds, and so the culls' pairs, follow the scene's order).
    """
    return [o.id for o in old.objects if o.id not in changed] == [
        o.id for o in new.objects if o.id not in changed
    ]


def tallest_movable(planner: Any, key: CacheKey, without: Set[str] = frozenset()) -> float | None:
    """Top [m] of the tallest non-static body standing while ``key`` is planned (it sets the
    height of the carry, :meth:`.geometric_planner.GeometricPlanner._sample_path`), the objects
    ``without`` left out; None without one.
    """
    relocated, object_id = key
    standing = planner.planning_scene(object_id, relocated)
    return max(
        (o.top_z for o in standing if o.role != 'static' and o.id not in without), default=None
    )


def replays(
    planned: PlannedAnswer | None, before: list[ObjectSpec], now: list[ObjectSpec]
) -> bool:
    """Whether the plan of ``planned`` makes the same scene queries once the changed objects
    ``before`` (as they stood) are replaced by ``now`` (as they stand): every query was recorded,
    none met an object of ``before``, and none can reach one of ``now``
    (:meth:`.footprint.Region.may_meet`, conservative). The caller checks the rest (order,
    tallest movable, drop slots, the answer's own objects).
    """
    if planned is None or not planned.region.complete:
        return False
    region = planned.region
    return not any(o in region.met for o in before) and not any(map(region.may_meet, now))


def judge(
    key: CacheKey,
    result: PlanResult,
    changed: set[str],
    clear: Callable[[], bool],
    slots: int,
    replay: Callable[[], bool] = lambda: False,
    moved: Set[str] = frozenset(),
    harder: Callable[[], bool] = lambda: False,
) -> Verdict:
    """Whether the cached answer ``result`` of ``key`` is still true, and why (or why not).

    Args:
        key: ``(frozenset(relocated), object_id)``.
        result: the cached answer.
        changed: ids of the changed objects.
        clear: whether the answer's motion keeps the verifier's clearance from its standing
            changes as they are now (called for feasible answers only, :func:`clear_of_changes`).
        slots: how many leading drop slots are unchanged (:func:`same_slots`).
        replay: whether the infeasible answer's plan would go as it went (called for search
            failures only, :func:`replays`).
        moved: the ids of ``changed`` that only moved (:func:`moved_only`): they may be in R.
        harder: whether the answer's planning scene only gained bodies (called for planning
            failures that do not replay, :func:`only_gains`).
    """
    relocated, object_id = key
    if object_id in changed:
        return Verdict(False, DROPPED_OBJECT)
    if relocated & (changed - moved):
        return Verdict(False, DROPPED_RELOCATED)
    if len(relocated) >= slots:
        return Verdict(False, DROPPED_SLOTS)
    if result.feasible:
        if not clear():
            return Verdict(False, DROPPED_NOT_CLEAR)
        return Verdict(True, VERIFIED_AGAIN)
    if result.reason == Reason.OBJECT_TOO_BIG:
        return Verdict(True, SIZE_ONLY)
    if replay():
        return Verdict(True, REPLAYED)
    if reason_family(result.reason) == ReasonFamily.PLANNING_FAILURE and harder():
        return Verdict(True, HARDER)
    return Verdict(False, DROPPED_PLAN)


def reuse_answers(
    old: Scenario,
    new: Scenario,
    entries: Mapping[CacheKey, PlanResult],
    clear_of: Callable[[CacheKey, PlanResult], bool],
    replays_of: Callable[[CacheKey], bool] = lambda key: False,
    families: Sequence[str] = ('side',),
    harder_of: Callable[[CacheKey], bool] = lambda key: False,
) -> Reuse:
    """Which answers of ``entries`` (made in ``old``) are still true in ``new``, and why.

    Args:
        old: the scene the answers were made in.
        new: the scene now.
        entries: the cached answers by ``(frozenset(relocated), object id)``.
        clear_of: whether a feasible answer's motion is clear of its standing changes now
            (:func:`clear_of_changes`).
        replays_of: whether an infeasible answer's plan would go as it went (:func:`replays`).
        families: the planner's grasp families (which drop slots it fills, :func:`same_slots`).
        harder_of: whether a planning failure's scene only gained bodies (:func:`only_gains`).
    """
    ids, specs = changed_objects(old, new)
    if not entries:
        return Reuse({}, {}, 'no cached answers')
    why_not = scene_blocks_reuse(old, new, specs)
    if why_not:
        return Reuse({}, {}, f'kept 0 of {len(entries)} cached answers: {why_not}')
    slots = same_slots(old, new, families)
    moved = moved_only(old, new, ids)
    verdicts = {
        key: judge(
            key,
            result,
            ids,
            functools.partial(clear_of, key, result),
            slots,
            functools.partial(replays_of, key),
            moved,
            functools.partial(harder_of, key),
        )
        for key, result in entries.items()
    }
    kept = {key: v.why for key, v in verdicts.items() if v.kept}
    dropped = {key: v.why for key, v in verdicts.items() if not v.kept}
    names = ', '.join(sorted(ids)) or 'nothing'
    return Reuse(
        kept, dropped, f'kept {len(kept)} of {len(entries)} cached answers (changed: {names})'
    )


def only_gains(
    planned: PlannedAnswer | None, before: list[ObjectSpec], now: list[ObjectSpec]
) -> bool:
    """Whether, for the plan of ``planned``, the answer's planning scene only gained bodies: the
    changed objects ``now`` (as they stand) are bodies added to it, and those ``before`` (as they
    stood) either were not there (an object added) or were never met by a query of the plan (its
    queries were all recorded), so that taking them away changes nothing the plan computed.
    False when nothing changed for it (``now`` empty: :func:`replays` decides).
    """
    if planned is None or not now:
        return False
    if not before:
        return True
    region = planned.region
    return region.complete and not any(o in region.met for o in before)


def clear_of_changes(planner: Any, result: PlanResult, object_id: str, now: list[ObjectSpec]):
    """Whether the feasible ``result`` (relocating ``object_id``) keeps ``planner``'s verifier
    clearance from the bodies ``now`` [the changed objects standing in the new scene] along its
    whole motion, the carried object included (True when ``now`` is empty).
    """
    if not now:
        return True
    carried = Carried(planner.scenario.object(object_id), result.grasp_index, result.release_index)
    trajectory = np.asarray(result.joint_trajectory, dtype=float)
    return planner.verifier.verify(trajectory, now, carried).ok


def carry_over(old: Any, new: Any) -> str:
    """Put the answers of planner ``old`` still true in the scene of planner ``new`` into the
    cache of ``new`` (:class:`~.planner.MotionPlanner` s); the summary line (for the log).
    """
    return carry_over_answers(old, new).summary


def carry_over_answers(old: Any, new: Any) -> Reuse:
    """:func:`carry_over`, with why each kept answer is still true (by cache key).

    The verifications run on ``new``'s robot model (same arm): a check may still be running on
    ``old``'s, and ``new`` serves no request before this returns.
    """
    if old.config != new.config:
        return Reuse(
            {}, {}, f'kept 0 of {len(old.cache)} cached answers: another planner configuration'
        )
    families = new.config.grasp_families
    ids, specs = changed_objects(old.scenario, new.scenario)
    now = [o for o in new.scenario.objects if o.id in ids]  # the changed ones, as they stand
    before = [o for o in old.scenario.objects if o.id in ids]  # and as they stood
    sweeps_kept = (
        not scene_blocks_reuse(old.scenario, new.scenario, specs)
        and same_slots(old.scenario, new.scenario, families) >= 1  # the sweeps use slot 0
    )
    if sweeps_kept:
        new.blockers.adopt(old.blockers, ids, now)
    in_order = same_order(old.scenario, new.scenario, ids)

    def standing(key: CacheKey, specs: list[ObjectSpec]) -> list[ObjectSpec]:
        return [o for o in specs if o.id not in key[0]]  # R's stand in their slots

    def clear_of(key: CacheKey, result: PlanResult) -> bool:
        return clear_of_changes(new, result, key[1], standing(key, now))

    def swept(key: CacheKey) -> bool:  # its blockers come from the adopted sweeps, no planning
        return not new.blockers.enabled or key[1] in new.blockers.sweeps

    def replays_of(key: CacheKey) -> bool:
        return (
            in_order
            and swept(key)
            and replays(old.footprints.get(key), standing(key, before), standing(key, now))
            and tallest_movable(old, key) == tallest_movable(new, key)
        )

    def harder_of(key: CacheKey) -> bool:
        tallest = tallest_movable(old, key)
        return (
            swept(key)  # and its answer before its blockers in old.footprints, to name them
            and only_gains(old.footprints.get(key), standing(key, before), standing(key, now))
            and tallest == tallest_movable(old, key, without=ids) == tallest_movable(new, key)
        )

    entries = dict(old.cache.items())
    reuse = reuse_answers(
        old.scenario, new.scenario, entries, clear_of, replays_of, families, harder_of
    )
    kept = reuse.kept
    for key in kept:
        relocated, object_id = key
        result = entries[key]
        planned = old.footprints.get(key)
        if planned is not None and swept(key):  # an infeasible answer: its blockers now
            annotated = new.blockers.annotate(planned.result, object_id, relocated)
            result = dataclasses.replace(
                annotated, planning_time=result.planning_time, cpu_time=result.cpu_time
            )
            if kept[key] == HARDER:  # its queries were asked in a scene with fewer bodies: they
                # no longer show what it looked at, so it can never replay, only get harder
                planned = dataclasses.replace(
                    planned, region=dataclasses.replace(planned.region, complete=False)
                )
            new.footprints[key] = planned
        new.cache.put(object_id, relocated, result)
    return reuse
