"""A slow, thorough reference planner and an independent dense verifier: BENCHMARKS ONLY.

Used by ``scripts/bench_false_infeasible.py`` to measure how often the real planner answers
"infeasible" where a motion exists (no ROS import). Never used to answer requests.

:class:`ReferencePlanner` is the motion planner with an exhaustive search: 33 approach yaws every
0.1 rad (±1.6 rad around the object's azimuth) instead of 17 every 0.2 rad, two more STPIK
iterations per path sample, 12 random IK restarts instead of 5 on every failed IK solve, 3000
instead of 1000 RRTConnect iterations wherever a straight joint transit collides
(:mod:`.robust_stpik`), 2000 instead of 500 in free Cartesian space, and a 60 s time limit.

:func:`verify_motion` checks a whole answer independently of the planner's collision code: the
``jaco2_description`` model's own python-fcl bodies every :data:`VERIFY_STEP_RAD` of joint
motion, against every object still in the scene (table included; the base link and link 1 that
stand on it excepted, as in the planner), the grasped object carried between the grasp and
release samples, non-adjacent link pairs, and the joint limits.
"""

from __future__ import annotations

import math
from typing import Any

import fcl
import numpy as np
import pinocchio as pin
from jaco2_description.model import Jaco2Model
from qtree_scene.scene import Scenario
from stpik_motion_planner.collision import object_geometry, object_transform
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult

VERIFY_STEP_RAD = 0.01  # largest joint change between two verified configurations [rad]
REFERENCE_CONFIG: dict[str, Any] = {
    'approach_directions': 33,
    'approach_yaw_step_rad': 0.1,
    'max_iterations': 14,
    'ik_restarts': 12,
    'rrt_iterations': 3000,
    'rrt_transit_s': 10.0,
    'sampling_iterations': 2000,
    'time_limit_s': 60.0,
}
_SKIPPED_LINKS = ('link_base', 'link_1')


class ReferencePlanner(MotionPlanner):
    """The motion planner with the exhaustive settings of the module docstring."""

    def __init__(self, scenario: Scenario, model: Jaco2Model | None = None) -> None:
        super().__init__(scenario, PlannerConfig(**REFERENCE_CONFIG), model)


def verify_motion(
    scenario: Scenario,
    relocated: list[str],
    object_id: str,
    result: PlanResult,
    robot: Jaco2Model,
    step_rad: float = VERIFY_STEP_RAD,
) -> tuple[bool, str]:
    """Check a feasible answer densely and independently (see the module docstring), at most
    ``step_rad`` [rad] of joint motion between two checked configurations.

    Returns:
        (valid, reason): reason names the first violation ('' when valid).
    """
    q = np.asarray(result.joint_trajectory, dtype=float)
    if q.ndim != 2 or len(q) < 2 or not 0 <= result.grasp_index < result.release_index < len(q):
        return False, 'no trajectory'
    lower, upper = np.asarray(robot.limits.lower), np.asarray(robot.limits.upper)
    gone = {*relocated, object_id}
    present = [o for o in scenario.objects if o.id not in gone]
    scene = _manager(
        [fcl.CollisionObject(object_geometry(o), object_transform(o)) for o in present]
    )
    movable = _manager(
        [
            fcl.CollisionObject(object_geometry(o), object_transform(o))
            for o in present
            if o.role != 'static'
        ]
    )
    obj = scenario.object(object_id)
    world_obj = pin.SE3(
        pin.rpy.rpyToMatrix(0.0, 0.0, obj.yaw), np.asarray(obj.position, dtype=float)
    )
    offset = robot.ee_pose(q[result.grasp_index]).actInv(world_obj)
    carried = fcl.CollisionObject(object_geometry(obj, inflate=-0.004), fcl.Transform())
    links = [(n, o) for n, o in robot.fcl_objects() if not n.endswith(_SKIPPED_LINKS)]
    for index in range(1, len(q)):
        a, b = q[index - 1], q[index]
        n = max(1, math.ceil(float(np.max(np.abs(b - a))) / step_rad))
        holding = result.grasp_index < index <= result.release_index
        for t in np.arange(1, n + 1) / n:
            qt = a + (b - a) * t
            if np.any(qt < lower - 1e-9) or np.any(qt > upper + 1e-9):
                return False, f'joint limit at sample {index}'
            if np.min(robot.self_collision_distances(qt)) <= 0.0:  # also places the links
                return False, f'self collision at sample {index}'
            for name, probe in links:
                if _hits(scene, probe):
                    return False, f'{name} hits the scene at sample {index}'
            if holding:
                placed = robot.ee_pose(qt) * offset
                carried.setTransform(fcl.Transform(placed.rotation, placed.translation))
                if _hits(movable, carried):  # the table excepted: set down at the release
                    return False, f'carried object hits the scene at sample {index}'
    return True, ''


def _manager(bodies: list[fcl.CollisionObject]) -> fcl.DynamicAABBTreeCollisionManager:
    manager = fcl.DynamicAABBTreeCollisionManager()
    if bodies:
        manager.registerObjects(bodies)
    manager.setup()
    return manager


def _hits(manager: fcl.DynamicAABBTreeCollisionManager, probe: fcl.CollisionObject) -> bool:
    data = fcl.CollisionData()
    manager.collide(probe, data, fcl.defaultCollisionCallback)
    return bool(data.result.is_collision)
