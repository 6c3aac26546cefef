"""Choices of the side grasp that make the planner work on any household clutter (no ROS).

Kept apart from :mod:`.planner` so that the planner's own code changes little:

* :func:`carry_height`: the lift clears the objects near the way to the drop zone (relocated
  ones included), not the tallest object of the whole table.
* :func:`candidate_yaws`: two more approach yaws, wider around the object.
* :func:`grasp_height`: the hand's lowest point, not its half height, is kept off the table.
* :func:`transit_raised`: a detour above the pre-grasp when the straight joint move dips.
* :func:`pregrasp_seeds` / :func:`converge_first`: several IK seeds for the pre-grasp instead
  of one (the single READY seed fails on half the approaches in clutter).
* :func:`turned_joint`: joint 1 of the ready posture turned to an azimuth, on the 2π branch with
  the most room to its limits, so the IK does not run into ±2π on objects to the right.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from qtree_scene.scene import ObjectSpec, Scenario

from stpik_motion_planner.cartesian_path import SHOULDER, WRIST_TO_EE_M, approach_yaws
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import IkNotConverged, MotionPlannerError, PlanningTimeout

if TYPE_CHECKING:
    from stpik_motion_planner.stpik import Stpik

HAND_BELOW_EE_M = 0.06  # lowest point of the hand below the EE origin in a side grasp [m]
TOP_MARGIN_M = 0.015  # the EE stays this far below the object's top [m]
MAX_WRIST_REACH_M = 0.70  # shoulder–wrist centre distance of the stretched arm is 0.72 m [m]
EXTRA_YAWS = 2  # approach yaws tried beyond the configured ones [-]
RAISE_M = 0.12  # height of the detour above the pre-grasp of a transit [m]
LIFT_NEIGHBOURHOOD_M = 0.2  # objects whose footprint centre is this close are lifted over [m]
JOINT_ROOM_RAD = 0.6  # wanted room of joint 1 to its limits in the ready posture [rad]


def candidate_yaws(centre: np.ndarray, config: PlannerConfig) -> list[float]:
    """Approach yaws [rad] to try: the configured ones, then :data:`EXTRA_YAWS` wider ones.

    Front-row objects need the wide ones: approached radially their pre-grasp puts the wrist
    over the base (self-hit, joint 4 limit); from the side it stays clear.
    """
    return approach_yaws(
        centre, config.approach_directions + EXTRA_YAWS, config.approach_yaw_step_rad
    )


def grasp_height(obj: ObjectSpec, activation_m: float, min_distance_m: float) -> float:
    """EE height [m] of the side grasp of ``obj``.

    Mid-height, raised so that the hand's lowest point stays ``activation_m`` + 5 mm above the
    object's bottom (the table; the obstacle task then stays inactive there) and
    :data:`TOP_MARGIN_M` below its top. A short object with no room for both is grasped as low
    as the hand may go, ``min_distance_m`` + 5 mm above the table, or just under its top.

    Args:
        obj: the object to grasp.
        activation_m: obstacle task activation distance [m].
        min_distance_m: scene safety margin [m].
    """
    half = obj.height / 2 if obj.shape == 'cylinder' else obj.size[2] / 2
    centre, bottom, top = obj.position[2], obj.position[2] - half, obj.position[2] + half
    low = bottom + HAND_BELOW_EE_M + activation_m + 0.005
    high = top - TOP_MARGIN_M
    if low <= high:
        return min(max(centre, low), high)
    return max(high, bottom + HAND_BELOW_EE_M + min_distance_m + 0.005)


def carry_height(
    scenario: Scenario, obj: ObjectSpec, grasp_z: float, clearance: float, hand_below: float
) -> float:
    """EE height [m] of the lift: the carried object's bottom ``clearance`` [m] above the tops
    of the objects near its way to the drop zone, and the hand ``hand_below`` [m] below the EE
    above them too.

    "Near its way": footprint centre within :data:`LIFT_NEIGHBOURHOOD_M` of the segment from
    the object to the drop-zone centre (table plane), relocated objects included so that a
    motion planned without them also clears them. Far objects are not lifted over: lifting a
    front-row object as high as the tallest object of the table folds the elbow past its limit.

    Args:
        scenario: the whole scene.
        obj: the grasped object.
        grasp_z: EE height at the grasp [m].
        clearance: wanted gap under the carried object [m].
        hand_below: lowest point of the hand below the EE [m].
    """
    half = obj.height / 2 if obj.shape == 'cylinder' else obj.size[2] / 2
    below = max(grasp_z - (obj.position[2] - half), hand_below)  # object bottom under the EE
    start = np.asarray(obj.position[:2], dtype=float)
    end = np.asarray(scenario.drop_zone_center[:2], dtype=float)
    tops = [
        o.top_z
        for o in scenario.objects
        if o.role != 'static'
        and _segment_distance(np.asarray(o.position[:2], dtype=float), start, end)
        <= LIFT_NEIGHBOURHOOD_M
    ]
    return max(max(tops, default=obj.top_z) + clearance + below, grasp_z + 0.05)


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance [m] from point ``p`` to the segment ``a``–``b`` (all (2,))."""
    ab = b - a
    t = float(np.clip((p - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0))
    return float(np.linalg.norm(p - a - t * ab))


def turned_joint(value: float, q1: float, lower: float, upper: float) -> float:
    """The 2π branch of ``value`` [rad] nearest ``q1`` among those with
    :data:`JOINT_ROOM_RAD` to both limits, else the one with the most room."""
    branches = [value + 2 * math.pi * k for k in range(-3, 4)]
    inside = [b for b in branches if lower <= b <= upper]
    roomy = [b for b in inside if min(b - lower, upper - b) >= JOINT_ROOM_RAD]
    if roomy:
        return min(roomy, key=lambda b: abs(b - q1))
    if inside:
        return max(inside, key=lambda b: min(b - lower, upper - b))
    return min(max(value, lower), upper)


def pregrasp_seeds(
    stpik: Stpik, pregrasp: pin.SE3, q1: float, random_seeds: int = 0, seed: int = 0
) -> list[np.ndarray]:
    """IK seeds [rad] (each (7,)) for the pre-grasp, most successful first.

    :data:`~.stpik.READY` turned to the pre-grasp azimuth (or to the wrist centre's), joint 7
    turned by the approach yaw's offset from that azimuth and taken on its lower 2π branch (the
    READY value 5.06 rad leaves little room to +2π); then READY itself, then ``random_seeds``
    seeded random configurations. On generated clutter the first four give a pre-grasp IK
    solution on 85 % of (object, yaw) pairs against 51 % for READY alone.

    Args:
        stpik: the tracker (its ready posture and joint limits are used).
        pregrasp: EE pose of the pre-grasp (world).
        q1: joint 1 of the start configuration [rad] (the turned branch nearest it is used).
        random_seeds: number of random seeds appended.
        seed: seed of their generator.
    """
    axis = pregrasp.rotation[:, 2]
    yaw = math.atan2(axis[1], axis[0])
    wrist = pregrasp.translation - WRIST_TO_EE_M * axis
    seeds = []
    for point, j7_offset in ((pregrasp.translation, True), (wrist, True), (wrist, False)):
        q = stpik.ready_posture(point, q1)
        offset = yaw - math.atan2(point[1], point[0]) if j7_offset else 0.0
        q[6] = q[6] + _wrap(offset) - 2 * math.pi
        seeds.append(q)
    q = stpik.ready_posture(pregrasp.translation, q1)
    seeds.append(np.r_[q[:6], q[6] - 2 * math.pi])
    seeds.append(q)
    rng = np.random.default_rng(
        [seed, int(abs(yaw) * 1e3), int(abs(pregrasp.translation[0]) * 1e3)]
    )
    lower, upper = np.maximum(stpik.lower, -math.pi), np.minimum(stpik.upper, 2 * math.pi)
    seeds += [rng.uniform(lower, upper) for _ in range(random_seeds)]
    return seeds


def converge_first(
    stpik: Stpik, seeds: list[np.ndarray], target: pin.SE3, scene: SceneWorld, deadline: float
) -> np.ndarray:
    """:meth:`~.stpik.Stpik.converge` from each seed in turn; the first solution [rad] (7,).

    A target whose wrist centre is farther than :data:`MAX_WRIST_REACH_M` from the shoulder
    is rejected at once (``IkNotConverged`` with that excess as residual).

    Raises:
        the first seed's planning error when no seed converges; PlanningTimeout at once.
    """
    wrist = target.translation - WRIST_TO_EE_M * target.rotation[:, 2]
    if float(np.linalg.norm(wrist - SHOULDER)) > MAX_WRIST_REACH_M:  # no seed can help
        raise IkNotConverged(-1, float(np.linalg.norm(wrist - SHOULDER)) - MAX_WRIST_REACH_M, 0.0)
    first: MotionPlannerError | None = None
    for seed in seeds:
        try:
            return stpik.converge(seed, target, scene, deadline=deadline)
        except PlanningTimeout:
            raise
        except MotionPlannerError as err:
            first = first or err
    assert first is not None
    raise first


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def transit_raised(
    stpik: Stpik,
    q_a: np.ndarray,
    q_b: np.ndarray,
    pose_b: pin.SE3,
    scene: SceneWorld,
    deadline: float,
) -> np.ndarray:
    """Joint transit ``q_a`` → ``q_b`` [rad]; if the straight joint move hits something (the
    fingers dip into the table on the way down to a low pre-grasp), go through the pose
    :data:`RAISE_M` above ``pose_b`` instead (IK seeded at ``q_b``).

    Returns:
        Samples after ``q_a`` up to ``q_b`` [rad], shape (n, 7).

    Raises:
        the straight move's error when the raised detour fails too; PlanningTimeout at once.
    """
    try:
        return stpik.transit(q_a, q_b, scene, deadline)
    except PlanningTimeout:
        raise
    except MotionPlannerError as err:
        first = err
    try:
        above = pin.SE3(pose_b.rotation, pose_b.translation + np.r_[0.0, 0.0, RAISE_M])
        q_up = stpik.converge(q_b, above, scene, deadline=deadline)
        return np.vstack(
            [stpik.transit(q_a, q_up, scene, deadline), stpik.transit(q_up, q_b, scene, deadline)]
        )
    except PlanningTimeout:
        raise
    except MotionPlannerError:
        raise first from None
