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

* **feasible**: the old AND new footprint of every changed object (its axis-aligned bounding box
  grown by the planner's ``obstacle_activation_m``) lies outside the swept volume of the answer's
  motion (:func:`swept_volume`: per trajectory segment and per body, arm links and carried
  object, a box that provably contains the body during the whole segment). WHY it is still true:
  the planning scene of ``(R, o)`` differs from the old one only by the changed objects (R and o
  are unchanged, so are the drop-slot envelopes of R); the trajectory was verified collision-free
  against the old scene with every other body, and no changed object, before or after the
  change, comes within the activation distance of any point the arm or carried object occupies
  along it. So the same trajectory is collision-free with the same clearances in the new scene,
  and its placement slot is the same.
* **infeasible, OBJECT_TOO_BIG**: decided from ``o``'s size and the hand only (o unchanged).
* **infeasible, blocked_by_immovable** (no approach works even with every movable object
  removed): decided in the statics-only scene of :mod:`.blockers`, which holds no movable
  object; statics, home and drop slots are unchanged, so that computation gives the same.
* any other infeasible answer is dropped: the planner's search (RRT-connect detours, IK
  restarts) may have touched any part of the workspace, so no region bounds what it depended on.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from qtree_scene.placement import drop_slots
from qtree_scene.scene import ObjectSpec, Scenario

from stpik_motion_planner.result import PlanResult, Reason

CacheKey = tuple[frozenset[str], str]
ARM_JOINTS_N = 7  # arm joints of the planning model [-]
SWEEP_STEP_RAD = 0.02  # largest Σ|Δq| between two swept configurations [rad] (pads ≤ ~1 cm)


@dataclass(frozen=True)
class Boxes:
    """Axis-aligned boxes in the world (= base) frame.

    Attributes:
        lo: lower corners [m], shape (K, 3).
        hi: upper corners [m], shape (K, 3).
    """

    lo: np.ndarray
    hi: np.ndarray

    def meets(self, lo: np.ndarray, hi: np.ndarray) -> bool:
        """Whether the box ``[lo, hi]`` [m] (3,) intersects (or touches) any of the boxes."""
        if len(self.lo) == 0:
            return False
        overlap = np.all((self.lo <= hi) & (lo <= self.hi), axis=1)
        return bool(np.any(overlap))


def footprint(obj: ObjectSpec, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounding box of ``obj`` grown by ``margin_m`` on every side: ``(lo, hi)`` [m] (3,)."""
    centre = np.asarray(obj.position, dtype=float)
    if obj.shape == 'cylinder':
        half = np.array([obj.radius, obj.radius, obj.height / 2])
    else:
        c, s = abs(math.cos(obj.yaw)), abs(math.sin(obj.yaw))
        sx, sy, sz = (v / 2 for v in obj.size)
        half = np.array([c * sx + s * sy, s * sx + c * sy, sz])
    half = half + margin_m
    return centre - half, centre + half


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
    footprints: Iterable[tuple[np.ndarray, np.ndarray]],
    swept: Callable[[], Boxes],
    slots: int,
) -> str:
    """Why the cached answer ``result`` of ``key`` is still true, or '' when it must be dropped.

    Args:
        key: ``(frozenset(relocated), object_id)``.
        result: the cached answer.
        changed: ids of the changed objects.
        footprints: old and new footprints ``(lo, hi)`` [m] of the changed objects, grown by the
            activation distance.
        swept: gives the swept volume of the answer's motion (called for feasible answers only).
        slots: how many leading drop slots are unchanged (:func:`same_slots`).
    """
    relocated, object_id = key
    if object_id in changed or relocated & changed or len(relocated) >= slots:
        return ''
    if result.feasible:
        volume = swept()
        if any(volume.meets(lo, hi) for lo, hi in footprints):
            return ''
        return 'every changed footprint outside the swept volume of its verified motion'
    if result.reason == Reason.OBJECT_TOO_BIG:
        return "decided by the object's size and the hand only"
    if result.blocked_by_immovable:
        return 'decided in the statics-only scene, which is unchanged'
    return ''


def reuse_answers(
    old: Scenario,
    new: Scenario,
    entries: Mapping[CacheKey, PlanResult],
    margin_m: float,
    swept_of: Callable[[CacheKey, PlanResult], Boxes],
) -> tuple[dict[CacheKey, PlanResult], str]:
    """The answers of ``entries`` (made in ``old``) still true in ``new``, and a summary line.

    Args:
        margin_m: the planner's obstacle activation distance [m] (footprints grow by it).
        swept_of: the swept volume of a feasible answer.
    """
    ids, specs = changed_objects(old, new)
    if not entries:
        return {}, 'no cached answers'
    why_not = scene_blocks_reuse(old, new, specs)
    if why_not:
        return {}, f'kept 0 of {len(entries)} cached answers: {why_not}'
    prints = [footprint(o, margin_m) for o in specs]
    slots = same_slots(old, new)
    kept = {
        key: result
        for key, result in entries.items()
        if kept_because(key, result, ids, prints, lambda k=key, r=result: swept_of(k, r), slots)
    }
    names = ', '.join(sorted(ids)) or 'nothing'
    return kept, f'kept {len(kept)} of {len(entries)} cached answers (changed: {names})'


def _bounding_radius(geometry: Any) -> float:
    """Radius [m] of a sphere about the geometry's origin holding it (coal primitive)."""
    if hasattr(geometry, 'halfSide'):
        return float(np.linalg.norm(geometry.halfSide))
    if hasattr(geometry, 'halfLength'):
        return math.hypot(geometry.radius, geometry.halfLength)
    if hasattr(geometry, 'radius'):
        return float(geometry.radius)
    raise TypeError(f'unsupported geometry {type(geometry).__name__}')


def _object_radius(obj: ObjectSpec) -> float:
    """Radius [m] of a sphere about the object's centre holding it."""
    if obj.shape == 'cylinder':
        return math.hypot(obj.radius, obj.height / 2)
    return float(np.linalg.norm(np.asarray(obj.size) / 2))


def swept_volume(robot: Any, reach: Callable, result: PlanResult, carried: ObjectSpec) -> Boxes:
    """Boxes holding the arm and the carried object along the whole motion of ``result``.

    The motion is linear in joint space between samples (as the verifier and the closed loop
    take it). A point p on a body moves, over a segment with joint change Δq, at most
    ``B = Σ_j |Δq_j| D_j`` where ``D_j`` bounds its distance to joint axis j (``reach``, the
    verifier's bound); so at every instant it is within B/2 of where it is at one end of the
    segment. Each body is bounded by a sphere about its origin; the box of both end spheres grown
    by B/2 holds the body over the whole segment.

    Args:
        robot: the planner's :class:`~jaco2_description.model.Jaco2Model`.
        reach: ``reach(joint, placement, geometry)`` → D [m] (7,)
            (:meth:`~.verifier.TrajectoryVerifier.reach`).
        result: a feasible answer (joint trajectory, grasp and release indices).
        carried: the relocated object at its pose before the grasp.

    Returns:
        One box per segment and body [m].
    """
    q, grasp, release = _subdivided(result)
    if len(q) < 2:
        return Boxes(np.zeros((0, 3)), np.zeros((0, 3)))
    objects = robot.geometry_model.geometryObjects
    radii = [_bounding_radius(g.geometry) for g in objects]
    reaches = [reach(g.parentJoint, g.placement, g.geometry) for g in objects]
    in_hand = None
    if 0 <= grasp <= release:
        robot.forward(q[grasp])
        hand = robot.data.oMi[ARM_JOINTS_N]
        obj_pose = pin.SE3(
            pin.rpy.rpyToMatrix(0.0, 0.0, carried.yaw), np.asarray(carried.position, float)
        )
        in_hand = hand.inverse() * obj_pose
        ball = coal.Sphere(_object_radius(carried))
        reaches.append(reach(ARM_JOINTS_N, in_hand, ball))
        radii.append(ball.radius)
    centres = np.full((len(q), len(radii), 3), np.nan)
    for k, qk in enumerate(q):
        robot.forward(qk)
        for g, placement in enumerate(robot.geometry_data.oMg):
            centres[k, g] = placement.translation
        if in_hand is not None and grasp <= k <= release:
            centres[k, -1] = (robot.data.oMi[ARM_JOINTS_N] * in_hand).translation
    radii_arr, reach_arr = np.asarray(radii), np.asarray(reaches)  # (G,), (G, 7)
    motion = np.abs(np.diff(q, axis=0)) @ reach_arr.T / 2  # (N-1, G) [m]
    a, b = centres[:-1], centres[1:]
    pad = radii_arr[None, :, None] + motion[:, :, None]
    lo, hi = np.fmin(a, b) - pad, np.fmax(a, b) + pad
    valid = ~np.isnan(lo).any(axis=2)  # the carried body only while in the hand
    return Boxes(lo[valid], hi[valid])


def _subdivided(result: PlanResult) -> tuple[np.ndarray, int, int]:
    """The joint trajectory [rad] (N, 7) with every segment cut into pieces of Σ|Δq| ≤
    :data:`SWEEP_STEP_RAD` (linear in joint space, as executed), and the grasp and release
    indices in it (-1 when none)."""
    q = np.asarray(result.joint_trajectory, dtype=float)
    if len(q) < 2:
        return q, -1, -1
    pieces = np.maximum(1, np.ceil(np.abs(np.diff(q, axis=0)).sum(axis=1) / SWEEP_STEP_RAD))
    rows, index = [q[:1]], [0]
    for k, n in enumerate(pieces.astype(int)):
        s = np.arange(1, n + 1)[:, None] / n
        rows.append(q[k] + s * (q[k + 1] - q[k]))
        index.append(index[-1] + n)

    def new_index(i: int) -> int:
        return index[i] if 0 <= i < len(index) else -1

    return np.vstack(rows), new_index(result.grasp_index), new_index(result.release_index)


def carry_over(old: Any, new: Any, memo: dict[int, Boxes] | None = None) -> str:
    """Put the answers of planner ``old`` still true in the scene of planner ``new`` into the
    cache of ``new`` (:class:`~.planner.MotionPlanner` s); the summary line (for the log).

    The kinematics run on ``new``'s robot model (same arm): a check may still be running on
    ``old``'s, and ``new`` serves no request before this returns.

    Args:
        memo: swept volumes by ``id(result)``, kept between calls (a kept answer is the same
            object in the next planner's cache); pruned to the kept answers.
    """
    margin = max(new.config.obstacle_activation_m, new.config.obstacle_min_distance_m)
    by_id = {o.id: o for o in old.scenario.objects}

    memo = {} if memo is None else memo

    def swept_of(key: CacheKey, result: PlanResult) -> Boxes:
        if id(result) not in memo:  # new's model: not yet serving, so no check is using it
            memo[id(result)] = swept_volume(new.robot, new.verifier.reach, result, by_id[key[1]])
        return memo[id(result)]

    entries = dict(old.cache.items())
    kept, summary = reuse_answers(old.scenario, new.scenario, entries, margin, swept_of)
    for (relocated, object_id), result in kept.items():
        new.cache.put(object_id, relocated, result)
    alive = {id(r) for r in kept.values()}
    for stale in [i for i in memo if i not in alive]:  # ids of dropped results may be reused
        del memo[stale]
    return summary
