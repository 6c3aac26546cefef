"""Keep the cached answers a scene change provably leaves true (#32 item 4; no ROS import).

When /scene changes (an object moved, added or removed under an execution, or between two
relocations) the motion planner is rebuilt and its cache (:mod:`.cache`) starts empty: every
question of the re-plan would be planned again. :func:`carry_over` instead moves into the new
planner's cache every answer of the old one that cannot depend on the change, by this rule
(:func:`kept_because`; anything else is dropped and planned again when asked):

Scene-level conditions (else nothing is kept): same scene name, drop zone and home; no changed
object is static or the target.

Per answer ``(R, o)``: neither ``o`` nor any object of ``R`` changed; the drop slots 0 … |R|
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
* **infeasible, blocked_by_immovable** (no approach works even with every movable object
  removed): decided in the statics-only scene of :mod:`.blockers`, which holds no movable
  object; statics, home and drop slots are unchanged, so that computation gives the same.
* any other infeasible answer is dropped: the planner's search (RRT-connect detours, IK
  restarts) may have touched any part of the workspace, so no region bounds what it depended on.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from qtree_scene.placement import drop_slots
from qtree_scene.scene import ObjectSpec, Scenario

from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.verifier import Carried

CacheKey = tuple[frozenset[str], str]


def changed_objects(old: Scenario, new: Scenario) -> tuple[set[str], list[ObjectSpec]]:
    """Ids that moved, appeared or disappeared, and their specs before and after (both)."""
    before = {o.id: o for o in old.objects}
    after = {o.id: o for o in new.objects}
    ids = {i for i in before.keys() | after.keys() if before.get(i) != after.get(i)}
    specs = [d[i] for i in sorted(ids) for d in (before, after) if i in d]
    return ids, specs


def scene_blocks_reuse(old: Scenario, new: Scenario, changed: list[ObjectSpec]) -> str:
    """Why no answer of ``old`` may be kept in ``new`` ('' when the per-answer rule applies)."""
    if old.name != new.name:
        return f'another scene ({old.name!r} -> {new.name!r})'
    if old.drop_zone_center != new.drop_zone_center or tuple(old.home) != tuple(new.home):
        return 'drop zone or home changed'
    for obj in changed:
        if obj.role in ('static', 'target'):
            return f'{obj.role} {obj.id!r} changed'
    return ''


def same_slots(old: Scenario, new: Scenario) -> int:
    """How many leading drop slots (in relocation order) ``old`` and ``new`` share [-]."""
    count = 0
    for a, b in zip(drop_slots(old), drop_slots(new), strict=False):
        if a != b:
            break
        count += 1
    return count


def kept_because(
    key: CacheKey,
    result: PlanResult,
    changed: set[str],
    clear: Callable[[], bool],
    slots: int,
) -> str:
    """Why the cached answer ``result`` of ``key`` is still true, or '' when it must be dropped.

    Args:
        key: ``(frozenset(relocated), object_id)``.
        result: the cached answer.
        changed: ids of the changed objects.
        clear: whether the answer's motion keeps the verifier's clearance from the changed
            objects as they are now (called for feasible answers only, :func:`clear_of_changes`).
        slots: how many leading drop slots are unchanged (:func:`same_slots`).
    """
    relocated, object_id = key
    if object_id in changed or relocated & changed or len(relocated) >= slots:
        return ''
    if result.feasible:
        if not clear():
            return ''
        return 'its verified motion verified again among the changed objects as they are now'
    if result.reason == Reason.OBJECT_TOO_BIG:
        return "decided by the object's size and the hand only"
    if result.blocked_by_immovable:
        return 'decided in the statics-only scene, which is unchanged'
    return ''


def reuse_answers(
    old: Scenario,
    new: Scenario,
    entries: Mapping[CacheKey, PlanResult],
    clear_of: Callable[[CacheKey, PlanResult], bool],
) -> tuple[dict[CacheKey, PlanResult], str]:
    """The answers of ``entries`` (made in ``old``) still true in ``new``, and a summary line.

    Args:
        old: the scene the answers were made in.
        new: the scene now.
        entries: the cached answers by ``(frozenset(relocated), object id)``.
        clear_of: whether a feasible answer's motion is clear of the changed objects now
            (:func:`clear_of_changes`).
    """
    ids, specs = changed_objects(old, new)
    if not entries:
        return {}, 'no cached answers'
    why_not = scene_blocks_reuse(old, new, specs)
    if why_not:
        return {}, f'kept 0 of {len(entries)} cached answers: {why_not}'
    slots = same_slots(old, new)
    kept = {
        key: result
        for key, result in entries.items()
        if kept_because(key, result, ids, functools.partial(clear_of, key, result), slots)
    }
    names = ', '.join(sorted(ids)) or 'nothing'
    return kept, f'kept {len(kept)} of {len(entries)} cached answers (changed: {names})'


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

    The verifications run on ``new``'s robot model (same arm): a check may still be running on
    ``old``'s, and ``new`` serves no request before this returns.
    """
    ids, _ = changed_objects(old.scenario, new.scenario)
    now = [o for o in new.scenario.objects if o.id in ids]  # the changed ones, as they stand

    def clear_of(key: CacheKey, result: PlanResult) -> bool:
        return clear_of_changes(new, result, key[1], now)

    entries = dict(old.cache.items())
    kept, summary = reuse_answers(old.scenario, new.scenario, entries, clear_of)
    for (relocated, object_id), result in kept.items():
        new.cache.put(object_id, relocated, result)
    return summary
