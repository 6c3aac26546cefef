"""IK peers (STPIK, pink, plain DLS) tracking the same whole planned EE paths, judged
independently (:class:`IndependentCheck`). No ROS import.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import fcl
import numpy as np
import pink
import pinocchio as pin
from jaco2_description.model import EE_FRAME, Jaco2Model
from pink.limits import ConfigurationLimit, VelocityLimit
from pink.tasks import FrameTask, PostureTask
from qtree_scene.scene import Scenario
from stpik_motion_planner.collision import SceneWorld, object_geometry, object_transform
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import MotionPlannerError
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult
from stpik_motion_planner.stpik import Stpik
from stpik_motion_planner.tasks.ee_pose_task import pose_error

PEER_ITERATIONS = 10  # IK iterations allowed per waypoint, same for every peer [-]
QP_SOLVER = 'daqp'  # qpsolvers back-end of pink
PEERS = ('stpik', 'pink', 'dls')
# Links never checked against the scene, as in the planner: the base stands on the table.
NOT_VS_SCENE = ('j2s7s300_link_base', 'j2s7s300_link_1')


@dataclass
class PeerRun:
    """One peer tracking one EE path.

    Attributes:
        q: joint angles reached at each waypoint [rad], shape (n, 7) (fewer rows if aborted).
        position_error: largest position error over the waypoints [m].
        orientation_error: largest orientation error over the waypoints [rad].
        seconds: wall time of the tracking alone [s].
        message: why STPIK stopped early ('' otherwise).
    """

    q: np.ndarray
    position_error: float
    orientation_error: float
    seconds: float
    message: str = ''


def _errors(target: pin.SE3, reached: pin.SE3) -> tuple[float, float]:
    error = pose_error(target, reached)
    return float(np.linalg.norm(error[:3])), float(np.linalg.norm(error[3:]))


def track_stpik(
    robot: Jaco2Model,
    config: PlannerConfig,
    q0: np.ndarray,
    path: list[pin.SE3],
    scene,
    references: np.ndarray | None = None,
) -> PeerRun:
    """The planner's own STPIK (all four tasks + posture), every waypoint at full tolerance.

    ``references`` [rad] (len(path), 7): the posture reference at each waypoint (the plan's
    configuration there, which keeps STPIK in the plan's arm family); default: the start.
    """
    stpik = Stpik(robot, config.replace(max_iterations=PEER_ITERATIONS))
    start = time.perf_counter()
    try:
        if references is None:
            q = stpik.track(q0, path, scene, [True] * len(path))
        else:
            rows, current = [], np.array(q0, dtype=float)
            for target, reference in zip(path, references, strict=True):
                current = stpik.track(current, [target], scene, [True], reference=reference)[0]
                rows.append(current)
            q = np.array(rows)
        message = ''
    except MotionPlannerError as err:
        q, message = np.empty((0, 7)), f'{type(err).__name__}: {err}'
    seconds = time.perf_counter() - start
    if not len(q):
        return PeerRun(q, math.inf, math.inf, seconds, message)
    worst = np.max([_errors(t, robot.ee_pose(qi)) for t, qi in zip(path, q, strict=True)], axis=0)
    return PeerRun(q, float(worst[0]), float(worst[1]), seconds)


def track_pink(
    robot: Jaco2Model, config: PlannerConfig, q0: np.ndarray, path: list[pin.SE3], scene
) -> PeerRun:
    """pink: FrameTask + low-cost PostureTask, ConfigurationLimit + VelocityLimit, one QP per step.

    dt is chosen so that v_max·dt equals the planner's ``max_joint_step_rad`` on the fastest
    joint: the velocity limit then plays the role of STPIK's step clamp.
    """
    del scene  # pink here has no collision avoidance
    model = robot.model
    dt = config.max_joint_step_rad / float(np.max(model.velocityLimit))  # [s]
    configuration = pink.Configuration(model, model.createData(), np.array(q0, dtype=float))
    ee_task = FrameTask(EE_FRAME, position_cost=1.0, orientation_cost=1.0)  # [cost]/[m], /[rad]
    posture = PostureTask(cost=1e-3)  # [cost]/[rad]
    posture.set_target(np.array(q0, dtype=float))
    limits = [ConfigurationLimit(model), VelocityLimit(model)]
    tasks = [ee_task, posture]
    tol_m, tol_rad = config.position_tolerance_m, config.orientation_tolerance_rad
    out, worst = np.empty((len(path), 7)), np.zeros(2)
    start = time.perf_counter()
    for index, target in enumerate(path):
        ee_task.set_target(target)
        for _ in range(PEER_ITERATIONS):
            err = _errors(target, configuration.get_transform_frame_to_world(EE_FRAME))
            if err[0] <= tol_m and err[1] <= tol_rad:
                break
            velocity = pink.solve_ik(
                configuration, tasks, dt, solver=QP_SOLVER, limits=limits, safety_break=False
            )
            configuration.integrate_inplace(velocity, dt)
        out[index] = configuration.q
        worst = np.maximum(
            worst, _errors(target, configuration.get_transform_frame_to_world(EE_FRAME))
        )
    return PeerRun(out, float(worst[0]), float(worst[1]), time.perf_counter() - start)


def track_dls(
    robot: Jaco2Model, config: PlannerConfig, q0: np.ndarray, path: list[pin.SE3], scene
) -> PeerRun:
    """Plain damped least squares on the EE pose (no limits, no collision), same step clamp."""
    del scene
    model = robot.model
    data = model.createData()
    ee = model.getFrameId(EE_FRAME)
    tol_m, tol_rad = config.position_tolerance_m, config.orientation_tolerance_rad
    damping2 = config.damping**2
    q = np.array(q0, dtype=float)
    out, worst = np.empty((len(path), 7)), np.zeros(2)
    start = time.perf_counter()
    for index, target in enumerate(path):
        for _ in range(PEER_ITERATIONS):
            pin.framesForwardKinematics(model, data, q)
            error = pose_error(target, data.oMf[ee])
            if error[:3] @ error[:3] <= tol_m**2 and error[3:] @ error[3:] <= tol_rad**2:
                break
            J = pin.computeFrameJacobian(model, data, q, ee, pin.LOCAL_WORLD_ALIGNED)
            dq = J.T @ np.linalg.solve(J @ J.T + damping2 * np.eye(6), error)
            largest = float(np.max(np.abs(dq)))
            if largest > config.max_joint_step_rad:
                dq *= config.max_joint_step_rad / largest
            q = q + dq
        pin.framesForwardKinematics(model, data, q)
        out[index] = q
        worst = np.maximum(worst, _errors(target, data.oMf[ee]))
    return PeerRun(out, float(worst[0]), float(worst[1]), time.perf_counter() - start)


PEER_FUNCTIONS: dict[str, Callable[..., PeerRun]] = {
    'stpik': track_stpik,
    'pink': track_pink,
    'dls': track_dls,
}


class IndependentCheck:
    """Joint limits, scene clearance and self-hit distances of a joint path, computed with the
    model's own python-fcl objects (``Jaco2Model.fcl_objects``, all its self-collision pairs)
    and pairwise ``fcl.distance``: no broad phase, nothing shared with the planner's managers.
    The carried object is not modelled (none of the peers knows it).
    """

    def __init__(self, scenario: Scenario, removed: set[str]) -> None:
        self.robot = Jaco2Model()
        self.scene = [
            fcl.CollisionObject(object_geometry(o), object_transform(o))
            for o in scenario.objects
            if o.id not in removed
        ]
        self.links = [b for name, b in self.robot.fcl_objects() if name not in NOT_VS_SCENE]
        self.request = fcl.DistanceRequest(enable_signed_distance=True)

    def __call__(self, q_path: np.ndarray) -> dict[str, float | bool]:
        """Limits respected, smallest scene clearance [m] and self distance [m] along the path."""
        limits = self.robot.limits
        within = bool(
            np.all(q_path >= limits.lower - 1e-9) and np.all(q_path <= limits.upper + 1e-9)
        )
        scene_min, self_min = math.inf, math.inf
        for q in q_path:
            self_min = min(self_min, float(np.min(self.robot.self_collision_distances(q))))
            for link in self.links:  # placed by self_collision_distances (update_fcl)
                for obj in self.scene:
                    d = fcl.distance(link, obj, self.request, fcl.DistanceResult())
                    scene_min = min(scene_min, d)
        return {'limits_ok': within, 'scene_clearance_m': scene_min, 'self_distance_m': self_min}


def run_peers(
    planner: MotionPlanner, key: tuple[frozenset[str], str], result: PlanResult
) -> dict[str, dict]:
    """Every peer on the EE path of one feasible check, judged by :class:`IndependentCheck`."""
    relocated, object_id = key
    removed = set(relocated) | {object_id}
    scene = SceneWorld(planner.planning_scene(object_id, relocated))
    check = IndependentCheck(planner.scenario, removed)
    path = [pin.XYZQUATToSE3(row) for row in result.ee_path[1:]]
    q0 = result.joint_trajectory[0]
    c = planner.config
    out = {}
    for name in PEERS:
        extra = {'references': result.joint_trajectory[1:]} if name == 'stpik' else {}
        run = PEER_FUNCTIONS[name](Jaco2Model(), c, q0, path, scene, **extra)
        tracked = (
            len(run.q) == len(path)
            and run.position_error <= c.position_tolerance_m + 1e-9
            and run.orientation_error <= c.orientation_tolerance_rad + 1e-9
        )
        # STPIK stops at its first violation: then limits and clearance are not judged (None).
        status = check(run.q) if len(run.q) else {}
        limits_ok = status.get('limits_ok')
        clear = (
            status['scene_clearance_m'] > c.obstacle_min_distance_m
            and status['self_distance_m'] > c.self_min_distance_m
            if status
            else None
        )
        out[name] = {
            'tracked': tracked,
            'limits_ok': limits_ok,
            'collision_free': clear,
            'success': tracked and bool(limits_ok),
            'success_with_clearance': tracked and bool(limits_ok) and bool(clear),
            'seconds': run.seconds,
            'waypoints': len(path),
            'position_error_m': run.position_error,
            'orientation_error_rad': run.orientation_error,
            'scene_clearance_m': status.get('scene_clearance_m'),
            'self_distance_m': status.get('self_distance_m'),
            'message': run.message,
        }
    return out
