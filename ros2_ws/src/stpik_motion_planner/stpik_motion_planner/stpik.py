"""Set-based Task-Priority Inverse Kinematics: eq. (6) with set-based activation. No ROS import.

Hierarchy (paper Sect. 4, highest priority first): (1) mechanical joint limits, (2) self-hit
avoidance, (3) obstacle avoidance, (4) end-effector position and orientation, then (ours) a
posture task in the remaining null space (see :mod:`.tasks.posture_task`). Tasks 1–3 are
set-based (Di Lillo et al.): a row enters the hierarchy, as an equality task holding σ at the
crossed activation threshold, only when σ is outside its valid range AND the solution without it
would push σ further out. :meth:`Stpik.track` follows a sampled Cartesian path with this
closed-loop IK and raises the typed exception of the first violated constraint.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from jaco2_description.model import EE_FRAME, Jaco2Model, continuous_joints

from stpik_motion_planner.collision import RobotBodies, SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import (
    IkNotConverged,
    JointLimitViolated,
    PlanningTimeout,
    SceneCollision,
    SelfCollision,
)
from stpik_motion_planner.kernels import chain_placements, solve_levels
from stpik_motion_planner.tasks import (
    EePoseTask,
    JointLimitTask,
    Kinematics,
    ObstacleTask,
    PostureTask,
    SelfCollisionTask,
    TaskRows,
)
from stpik_motion_planner.tasks.ee_pose_task import pose_error

STEP_TIMES_KEPT = 200_000  # most recent per-step timings kept in Stpik.step_times [-]
LOOSE_FACTOR = 3.0  # tolerance multiplier on intermediate path samples [-]
LOOKAHEAD_M = 0.05  # pairs are found up to this beyond their activation distance [m]
# converge stops when the error (position [m] + STALL_RAD_TO_M · orientation [rad]) is above
# STALL_RATIO times its value STALL_WINDOW iterations earlier.
STALL_WINDOW = 5
STALL_RATIO = 0.95
STALL_RAD_TO_M = 0.1
# Posture of a low side grasp straight ahead (EE at about (0.6, 0, 0.08) m, approach along +x)
# with wide joint-limit and self-hit margins, found offline by multi-start IK [rad]. Turning
# joint 1 by -ψ turns it to azimuth ψ; the posture task pulls the arm toward that posture.
READY = np.array([5.5, 1.37, -2.08, 1.11, 2.65, 4.53, 5.06])
# The same for a top grasp (#30): EE pointing down at (0.55, 0, 0.25) m, the largest joint-limit
# margin of 300 random-seed IK solutions (0.73 rad); from it, turned like READY, STPIK reaches
# 160 of 180 top-grasp poses x 0.35-0.65 m, |y| <= 0.3 m, z 0.1-0.3 m, yaw ±1.5 rad [rad].
READY_TOP = np.array([3.14, 3.79, 0.05, 1.93, 6.24, 4.42, 3.18])


def damped_pinv(A: np.ndarray, damping: float, threshold: float) -> np.ndarray:
    """Pseudo-inverse of A (m, n) → (n, m), damped only near singularities.

    Singular values s below ``threshold`` are inverted as s / (s² + λ²) with
    λ² = damping² (1 − (s / threshold)²) (variable damping, Nakamura & Hanafusa).
    """
    if A.size == 0:
        return np.zeros((A.shape[1], A.shape[0]))
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    lam2 = np.where(threshold > S, damping**2 * (1.0 - (S / threshold) ** 2), 0.0)
    denom = S**2 + lam2
    s_inv = np.divide(S, denom, out=np.zeros_like(S), where=denom > 1e-12)
    return (Vt.T * s_inv) @ U.T


RANK_TOLERANCE = 1e-6  # singular values below this are rank loss in the null-space projector [-]


def pinv_pair(
    A: np.ndarray, damping: float, threshold: float, tolerance: float = RANK_TOLERANCE
) -> tuple[np.ndarray, np.ndarray]:
    """(:func:`damped_pinv`, :func:`truncated_pinv`) of A (m, n), both (n, m), from ONE SVD.

    Bit-identical to calling the two functions (same decomposition, same arithmetic).
    """
    if A.size == 0:
        zero = np.zeros((A.shape[1], A.shape[0]))
        return zero, zero.copy()
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    lam2 = np.where(threshold > S, damping**2 * (1.0 - (S / threshold) ** 2), 0.0)
    denom = S**2 + lam2
    s_damped = np.divide(S, denom, out=np.zeros_like(S), where=denom > 1e-12)
    s_truncated = np.divide(1.0, S, out=np.zeros_like(S), where=tolerance <= S)
    V = Vt.T
    return (V * s_damped) @ U.T, (V * s_truncated) @ U.T


def truncated_pinv(A: np.ndarray, tolerance: float = RANK_TOLERANCE) -> np.ndarray:
    """Undamped pseudo-inverse of A (m, n) → (n, m), singular values < ``tolerance`` dropped."""
    if A.size == 0:
        return np.zeros((A.shape[1], A.shape[0]))
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    s_inv = np.divide(1.0, S, out=np.zeros_like(S), where=tolerance <= S)
    return (Vt.T * s_inv) @ U.T


def solve_hierarchy(levels: Sequence[TaskRows], n: int, damping: float, threshold: float):
    """Eq. (6): q̇_i = q̇_{i−1} + (J_i N_{i−1})^†_λ (K_i σ̃_i − J_i q̇_{i−1}), N_i = N_{i−1} − (J_i N_{i−1})^+ J_i N_{i−1}.

    The velocity term uses the damped pseudo-inverse ^†_λ (:func:`damped_pinv`); the null-space
    projector uses the undamped, rank-truncated ^+ (:func:`truncated_pinv`), so N_i is an exact
    projector and a lower level never changes what a higher one achieves (strict priority), even
    where damping acts. Computed by :func:`.kernels.solve_levels` (one compiled call, #28).

    Args:
        levels: tasks in priority order (highest first), rows (J_i, K_i σ̃_i).
        n: number of joints.
        damping: pseudo-inverse damping.
        threshold: singular value where damping starts.

    Returns:
        Joint step q̇ (already multiplied by dt) [rad], shape (n,).
    """  # noqa: E501
    used = [rows for rows in levels if rows.dim]
    if not used:
        return np.zeros(n)
    dims = [rows.dim for rows in used]
    starts = np.zeros(len(used) + 1, dtype=np.int64)
    starts[1:] = np.cumsum(dims)
    jacobian = np.empty((int(starts[-1]), n))
    error = np.empty(int(starts[-1]))
    for rows, begin, end in zip(used, starts[:-1], starts[1:], strict=True):
        jacobian[begin:end] = rows.jacobian
        error[begin:end] = rows.error
    return solve_levels(jacobian, error, starts, damping, threshold, RANK_TOLERANCE)


class Stpik:
    """STPIK tracker of one robot model against a scene.

    Attributes:
        collision_time: wall time spent in FCL queries since the last :meth:`reset_timers` [s].
        step_times: per :meth:`_step`: (solve, kinematics, collision) wall times [s].
    """

    def __init__(self, robot: Jaco2Model, config: PlannerConfig) -> None:
        self.config = config
        self.model = robot.model
        self.data = self.model.createData()
        self.geometry_model = robot.geometry_model
        self._chain = _serial_chain(self.model, self.geometry_model)
        # Continuous joints (1, 3, 5, 7) have no limit: the model's ±2π is a modelling artefact.
        free = np.asarray(continuous_joints())
        self.lower = np.where(free, -np.inf, np.asarray(robot.limits.lower, dtype=float))
        self.upper = np.where(free, np.inf, np.asarray(robot.limits.upper, dtype=float))
        self.bodies = RobotBodies(
            self.geometry_model, robot.collision_links, robot.self_collision_pairs
        )
        # Per body: parent joint and bounding radius [m], for the Cartesian step bound.
        self._body_joint = np.array([g.parentJoint for g in self.geometry_model.geometryObjects])
        self._body_radius = np.array(
            [_bounding_radius(g.geometry) for g in self.geometry_model.geometryObjects]
        )
        self._joints_attached = np.r_[self._body_joint, 7]  # with the carried object
        self._radii_attached = np.r_[self._body_radius, 0.0]  # last: set by body_reach
        self._moved: dict[int, np.ndarray] = {}  # body_reach's (7, G) masks by body count
        self._body_index = {name: i for i, name in enumerate(robot.collision_links)}
        self._body_index['attached'] = len(robot.collision_links)
        self.ee_frame = self.model.getFrameId(EE_FRAME)
        frame = self.model.frames[self.ee_frame]
        self._ee_joint = int(frame.parentJoint)
        self._ee_in_joint = np.array(frame.placement.homogeneous)
        self._frames = np.tile(np.eye(4), (self.model.njoints, 1, 1))  # oMi of the last place
        self.body_joint = {
            name: g.parentJoint
            for name, g in zip(
                robot.collision_links, self.geometry_model.geometryObjects, strict=True
            )
        }
        self.body_joint['attached'] = self.model.frames[self.ee_frame].parentJoint
        c = config
        self.joint_limits = JointLimitTask(
            self.lower, self.upper, c.joint_limit_activation_rad, c.set_gain
        )
        self.self_hit = SelfCollisionTask(c.self_activation_m, c.set_gain)
        self.obstacles = ObstacleTask(c.obstacle_activation_m, c.set_gain)
        self.ee = EePoseTask(gain=c.ee_gain)
        self.posture = PostureTask(READY, c.posture_gain)  # reference: see ready_posture
        # Buffers of :meth:`_solve_base` (EE rows 0-5, posture rows 6-12) and its constants.
        self._base_jacobian = np.empty((13, 7))
        self._base_error = np.empty(13)
        self._base_starts = np.array([0, 6, 13], dtype=np.int64)
        self.collision_time = 0.0
        # Per STPIK step (:meth:`_step`): (solve + step bound, kinematics without collision,
        # collision) wall times [s], the latest STEP_TIMES_KEPT (benchmarks read and clear it).
        self.step_times: deque[tuple[float, float, float]] = deque(maxlen=STEP_TIMES_KEPT)

    def ready_posture(
        self, position: np.ndarray, q1: float, ready: np.ndarray = READY
    ) -> np.ndarray:
        """``ready`` (:data:`READY`, or :data:`READY_TOP` for a top grasp) turned to the azimuth
        of ``position`` [m], joint 1 nearest ``q1``.
        """
        reference = np.array(ready, dtype=float)
        turned = reference[0] - math.atan2(position[1], position[0])
        turned += 2 * math.pi * round((q1 - turned) / (2 * math.pi))
        reference[0] = turned
        return reference

    def nearest_turn(self, q: np.ndarray, near: np.ndarray) -> np.ndarray:
        """``q`` [rad] (7,) with each continuous joint turned by whole turns (2π) to lie within
        π of ``near`` [rad] (7,): the same arm pose, reached from ``near`` by the shortest
        joint line (#29: a carry transit wound joint 7 by 4π and flipped the carried object).
        """
        q = np.array(q, dtype=float)
        free = np.isinf(self.lower)
        q[free] += 2 * math.pi * np.round((near[free] - q[free]) / (2 * math.pi))
        return q

    def reset_timers(self) -> None:
        """Zero :attr:`collision_time`."""
        self.collision_time = 0.0

    def kinematics(
        self, q: np.ndarray, scene: SceneWorld, lookahead: float = LOOKAHEAD_M
    ) -> Kinematics:
        """Forward kinematics, Jacobians and pairs closer than activation + ``lookahead`` [m]."""
        pin.computeJointJacobians(self.model, self.data, q)
        world_ee = pin.updateFramePlacement(self.model, self.data, self.ee_frame)
        self.place_bodies(q)
        start = time.perf_counter()
        # Pairs up to LOOKAHEAD_M beyond activation: tasks use those inside it, the step bound
        # (:meth:`_step`) keeps the others from crossing the failure margin in one step.
        self_pairs = self.bodies.self_proximities(self.config.self_activation_m + lookahead)
        scene_pairs = self.bodies.scene_proximities(
            scene, self.config.obstacle_activation_m + lookahead
        )
        self.collision_time += time.perf_counter() - start
        return Kinematics(
            q,
            self.model,
            self.data,
            pin.SE3(world_ee),
            self.ee_frame,
            self.body_joint,
            self_pairs,
            scene_pairs,
        )

    def solve(self, k: Kinematics) -> tuple[np.ndarray, list[str]]:
        """One STPIK step at ``k``: joint step [rad] (7,) and the activated set-based tasks.

        Set-based activation (Di Lillo et al.): a row outside its valid set enters the hierarchy
        when the current solution drives σ further out. Rows are added one round at a time and
        the solution recomputed after each round, until no remaining row is pushed out by the
        solution that includes every activated row (fix of a single test against the solution
        without set-based tasks, which a later activation could invalidate).
        """
        c = self.config
        ee = self.ee.compute(k)
        posture = self.posture.compute(k)
        dq = self._solve_base(ee, posture)
        candidates = []
        for task in self._may_activate(k):
            rows = task.compute(k)
            if rows.dim:
                candidates.append((task.name, rows, np.zeros(rows.dim, dtype=bool)))
        while candidates:
            added = False
            for _, rows, chosen in candidates:
                out = ((rows.jacobian @ dq) * rows.error <= 0.0) & ~chosen
                if out.any():
                    chosen |= out
                    added = True
            if not added:
                break
            levels = [
                TaskRows(
                    r.jacobian[m],
                    r.error[m],
                    tuple(label for label, keep in zip(r.labels, m.tolist(), strict=True) if keep),
                )
                for _, r, m in candidates
                if m.any()
            ]
            dq = solve_hierarchy([*levels, ee, posture], 7, c.damping, c.singular_threshold)
        active = [name for name, _, m in candidates if m.any()]
        return dq, active

    def _solve_base(self, ee: TaskRows, posture: TaskRows) -> np.ndarray:
        """``solve_hierarchy([ee, posture], 7, ...)`` without its per-call assembly (#28): the
        rows are copied into buffers allocated once, with the level starts (0, 6, 13) fixed.
        Same arrays into the same kernel, so the same step bit for bit.
        """
        c = self.config
        jacobian, error = self._base_jacobian, self._base_error
        if ee.jacobian.shape != (6, 7) or posture.jacobian.shape != (7, 7):
            return solve_hierarchy([ee, posture], 7, c.damping, c.singular_threshold)
        jacobian[:6] = ee.jacobian
        jacobian[6:] = posture.jacobian
        error[:6] = ee.error
        error[6:] = posture.error
        return solve_levels(
            jacobian, error, self._base_starts, c.damping, c.singular_threshold, RANK_TOLERANCE
        )

    def _may_activate(self, k: Kinematics) -> list:
        """The set-based tasks that can give a row at ``k`` (:meth:`SetBasedTask.may_activate`),
        so that the usual step, with none outside its valid set, computes no task rows.
        """
        return [t for t in (self.joint_limits, self.self_hit, self.obstacles) if t.may_activate(k)]

    def step(
        self,
        q: np.ndarray,
        target: pin.SE3,
        scene: SceneWorld,
        reference: np.ndarray | None = None,
    ) -> tuple[np.ndarray, list[str]]:
        """Public single step of eq. (6) with the set-based hierarchy (for closed-loop use).

        Args:
            q: current joint angles [rad], shape (7,).
            target: desired EE pose in the world frame.
            scene: objects to avoid (the carried object: :attr:`bodies` ``attach``).
            reference: posture reference [rad] (7,) of the lowest task (default: keep the last).

        Returns:
            The next joint angles [rad] (7,) (step bounded as in :meth:`_step`) and the names of
            the activated set-based tasks.
        """
        q = np.array(q, dtype=float)
        self.ee.target = target
        if reference is not None:
            self.posture.reference = np.asarray(reference, dtype=float).copy()
        q_next, _, active = self._step(q, self.kinematics(q, scene), scene)
        return q_next, active

    def track(
        self,
        q: np.ndarray,
        samples: Sequence[pin.SE3],
        scene: SceneWorld,
        tight: Sequence[bool],
        deadline: float = np.inf,
        reference: np.ndarray | None = None,
    ) -> np.ndarray:
        """Follow ``samples`` (EE poses, world frame) from ``q``; joint angles per sample.

        Args:
            q: start configuration [rad], shape (7,).
            samples: EE poses to reach one after the other.
            scene: objects to avoid.
            tight: per sample, True to require the full tolerance (else ×3, see LOOSE_FACTOR).
            deadline: ``time.perf_counter()`` value past which :class:`PlanningTimeout` is raised.
            reference: posture reference [rad] (7,), e.g. the plan's configuration at the end of
                the leg (default: the start ``q``, which keeps the start's arm family).

        Returns:
            Joint angles reached at each sample [rad], shape (len(samples), 7).

        Raises:
            JointLimitViolated, SelfCollision, SceneCollision, IkNotConverged, PlanningTimeout.
        """
        c = self.config
        q = np.array(q, dtype=float)
        self.posture.reference = (q if reference is None else np.asarray(reference)).copy()
        out = np.empty((len(samples), 7))
        k = self.kinematics(q, scene)
        for index, (target, strict) in enumerate(zip(samples, tight, strict=True)):
            if time.perf_counter() > deadline:
                raise PlanningTimeout.past(deadline, c.time_limit_s)
            factor = 1.0 if strict else LOOSE_FACTOR
            self.ee.target = target
            active: list[str] = []
            for _ in range(c.max_iterations):
                error = pose_error(target, k.world_ee)
                if _within(
                    error, c.position_tolerance_m * factor, c.orientation_tolerance_rad * factor
                ):
                    break
                q, k, active = self._step(q, k, scene)
            self._check(k, index, target, factor, active)
            out[index] = q
        return out

    def converge(
        self,
        seed: np.ndarray,
        target: pin.SE3,
        scene: SceneWorld,
        iterations: int = 40,
        deadline: float = np.inf,
    ) -> np.ndarray:
        """STPIK from ``seed`` [rad] (7,) until the EE reaches ``target`` (full tolerance).

        The posture task pulls toward the seed, so the solution stays in the seed's family.

        Raises:
            JointLimitViolated, SelfCollision, SceneCollision, IkNotConverged, PlanningTimeout.
        """
        c = self.config
        q = np.array(seed, dtype=float)
        self.ee.target = target
        self.posture.reference = q.copy()
        # converge is an IK solve: only its end point is used (the motion to it is a checked
        # transit), so its iterations are not step-bounded; bounded ones (tried for #29) were held
        # by the obstacle task on the way and lost s2's O8 window. An end point inside a margin
        # is the seed's failure, IK_NOT_CONVERGED (then the restarts), not a scene collision.
        k = self.kinematics(q, scene, lookahead=0.0)
        active: list[str] = []
        history: list[float] = []
        for _ in range(iterations):
            if time.perf_counter() > deadline:
                raise PlanningTimeout.past(deadline, c.time_limit_s)
            error = pose_error(target, k.world_ee)
            if _within(error, c.position_tolerance_m / 2, c.orientation_tolerance_rad / 2):
                break
            # Stalled: the weighted error shrank by less than STALL_RATIO over STALL_WINDOW steps.
            history.append(
                float(np.linalg.norm(error[:3]) + STALL_RAD_TO_M * np.linalg.norm(error[3:]))
            )
            if (
                len(history) > STALL_WINDOW
                and history[-1] > STALL_RATIO * history[-1 - STALL_WINDOW]
            ):
                break
            q, k, active = self._step(q, k, scene, bounded=False)
        try:
            self._check(k, -1, target, 1.0, active)
        except (SelfCollision, SceneCollision) as err:  # an IK end point, not a motion (#29)
            error = pose_error(target, k.world_ee)
            residual_m, residual_rad = np.linalg.norm(error[:3]), np.linalg.norm(error[3:])
            detail = f'the IK solution from this seed is in collision: {err}'
            raise IkNotConverged(-1, float(residual_m), float(residual_rad), detail) from None
        return q

    def _step(
        self, q: np.ndarray, k: Kinematics, scene: SceneWorld, bounded: bool = True
    ) -> tuple[np.ndarray, Kinematics, list[str]]:
        """One eq. (6) step from ``q`` [rad], clamped to ``max_joint_step_rad`` on every joint and
        (``bounded``) scaled by :meth:`step_scale` so that no clear pair crosses its margin.

        Returns:
            The new joint angles [rad] (7,), their kinematics, the names of the active tasks.
        """
        t0 = time.perf_counter()
        collision0 = self.collision_time
        dq, active = self.solve(k)
        largest = float(np.abs(dq).max())
        if largest > self.config.max_joint_step_rad:
            dq *= self.config.max_joint_step_rad / largest
        if bounded:
            dq *= self.step_scale(k, dq)
        q = q + dq
        t1 = time.perf_counter()
        k_next = self.kinematics(q, scene, LOOKAHEAD_M if bounded else 0.0)
        collision = self.collision_time - collision0
        self.step_times.append((t1 - t0, time.perf_counter() - t1 - collision, collision))
        return q, k_next, active

    def body_reach(self, k: Kinematics) -> tuple[np.ndarray, np.ndarray]:
        """R_{j,g} [m] (7, G) and each body's joint (G,): largest distance from joint j's axis
        to a point of body g moved by it (0 where joint j does not move g); the carried object
        is the last body when attached.

        To first order a step dq moves no point of body g farther than Σ_j |dq_j| R_{j,g}.
        """
        frames = self._frames[1:8]  # joints 1..7 at k (placed by kinematics) (7, 4, 4)
        origins = frames[:, :3, 3]  # (7, 3)
        axes = frames[:, :3, 2]  # RZ joints (7, 3)
        joints, radii = self._body_joint, self._body_radius
        centres = self.bodies.centres[: len(joints)]  # (G, 3), placed by kinematics
        if self.bodies.attached is not None:
            centres = self.bodies.centres
            # np.r_[joints, 7] and np.r_[radii, attached radius], in buffers made once (#28)
            joints, radii = self._joints_attached, self._radii_attached
            radii[-1] = self.bodies.attached_radius
        offset = centres[None] - origins[:, None]  # (7, G, 3)
        along = np.einsum('jgk,jk->jg', offset, axes)
        # np.linalg.norm(·, axis=2) of a real array is sqrt(add.reduce(x * x, axis=2)): the
        # same operations without its argument handling (#28)
        off_axis = offset - along[..., None] * axes[:, None]
        to_axis = np.sqrt(np.add.reduce(off_axis * off_axis, axis=2))
        distance = to_axis + radii[None]
        moved = self._moved.get(len(joints))
        if moved is None:  # depends on the bodies only (with / without the carried object)
            moved = self._moved[len(joints)] = joints[None] >= np.arange(1, 8)[:, None]
        return np.where(moved, distance, 0.0), joints

    def step_scale(self, k: Kinematics, dq: np.ndarray) -> float:
        """Factor in (0, 1] so that no inactive pair crosses its failure margin in one step.

        Bounds (Cartesian, from :meth:`body_reach`): a pair not found is at least activation +
        LOOKAHEAD_M apart, so no body point may move more than LOOKAHEAD_M + activation −
        failure margin; a found pair outside its activation distance d may lose at most d −
        failure margin, counting the robot body's motion against a scene object and only the
        joints between the two links for a self pair. Active pairs are held by their rows.
        """
        c = self.config
        reach, joints = self.body_reach(k)
        step = np.abs(dq)
        body_motion = step @ reach  # (G,) [m]
        scale = 1.0
        # Each bound: scale = min(scale, max(allowed, 1e-4) / motion) where motion > 1e-12
        # (one inline test per pair, no closure; Python floats, the values of float(numpy)).
        motion = float(body_motion.max())
        if motion > 1e-12:
            allowed = LOOKAHEAD_M + min(
                c.obstacle_activation_m - c.obstacle_min_distance_m,
                c.self_activation_m - c.self_min_distance_m,
            )
            scale = min(scale, max(allowed, 1e-4) / motion)
        index = self._body_index
        if k.scene_pairs:
            motions = body_motion.tolist()
            activation, margin = c.obstacle_activation_m, c.obstacle_min_distance_m
            for p in k.scene_pairs:
                if p.distance >= activation:
                    motion = motions[index[p.name_a]]
                    if motion > 1e-12:
                        scale = min(scale, max(p.distance - margin, 1e-4) / motion)
        activation, margin = c.self_activation_m, c.self_min_distance_m
        for p in k.self_pairs:
            if p.distance >= activation:
                a, b = index[p.name_a], index[p.name_b]
                if joints[a] > joints[b]:
                    a, b = b, a
                motion = float(step[joints[a] :] @ reach[joints[a] :, b])
                if motion > 1e-12:
                    scale = min(scale, max(p.distance - margin, 1e-4) / motion)
        return scale

    def transit(
        self, q_a: np.ndarray, q_b: np.ndarray, scene: SceneWorld, deadline: float = np.inf
    ) -> np.ndarray:
        """Free-space joint-space move from ``q_a`` to ``q_b`` [rad], checked at each sample.

        Samples are spaced ≤ ``step_rad`` on every joint; at each one the self-hit and scene
        distances must stay at or above their *activation* distances, so that STPIK (whose
        set-based tasks hold pairs there) can follow the move.

        Returns:
            Samples after ``q_a`` up to ``q_b`` [rad], shape (n, 7).

        Raises:
            SelfCollision, SceneCollision, PlanningTimeout.
        """
        c = self.config
        out = joint_segment(q_a, q_b, c.step_rad)
        for q in out:
            if time.perf_counter() > deadline:
                raise PlanningTimeout.past(deadline, c.time_limit_s)
            # Collision checks only: placements without Jacobians (bit-identical to those of
            # kinematics), self pairs first, the scene only when no self pair is too close.
            self.place_bodies(q)
            start = time.perf_counter()
            found = self.bodies.self_proximities(c.self_activation_m)
            if not found:
                hits = self.bodies.scene_proximities(scene, c.obstacle_activation_m)
            self.collision_time += time.perf_counter() - start
            if found:
                p = found[0]
                raise SelfCollision(p.name_a, p.name_b, p.distance)
            if hits:
                p = hits[0]
                raise SceneCollision(p.name_a, p.name_b, p.distance)
        return out

    def place_bodies(self, q: np.ndarray) -> None:
        """Place the collision bodies at ``q`` [rad] (7,), for :meth:`kinematics` and the
        collision-only checks of transits and RRTConnect: one compiled forward-kinematics call
        (:func:`.kernels.chain_placements`, #28), no Pinocchio data touched, so a
        configuration's bodies are placed the same way whichever check asks.
        """
        chain = self._chain
        frames, placements = chain_placements(
            np.ascontiguousarray(q, dtype=float), chain[0], chain[1], chain[2]
        )
        self._frames = frames
        self.bodies.place(placements, frames[self._ee_joint] @ self._ee_in_joint)

    def _check(
        self, k: Kinematics, index: int, target: pin.SE3, factor: float, active: list[str]
    ) -> None:
        c = self.config
        outside = np.flatnonzero((k.q < self.lower - 1e-9) | (k.q > self.upper + 1e-9))
        if outside.size:
            j = int(outside[0])
            raise JointLimitViolated(j, float(k.q[j]), self.lower[j], self.upper[j])
        for p in k.self_pairs:
            if p.distance <= c.self_min_distance_m:
                raise SelfCollision(p.name_a, p.name_b, p.distance)
        for p in k.scene_pairs:
            if p.distance <= c.obstacle_min_distance_m:
                raise SceneCollision(p.name_a, p.name_b, p.distance)
        error = pose_error(target, k.world_ee)
        if _within(error, c.position_tolerance_m * factor, c.orientation_tolerance_rad * factor):
            return
        # Tracking failed with every constraint satisfied: IK_NOT_CONVERGED, naming the set-based
        # task that held the arm back (an active task is not a violated constraint).
        held = []
        if 'obstacles' in active and k.scene_pairs:
            p = min(k.scene_pairs, key=lambda p: p.distance)
            held.append(
                f'obstacle task active ({p.name_a} / {p.name_b} {p.distance * 1e3:.1f} mm)'
            )
        if 'self_hit' in active and k.self_pairs:
            p = min(k.self_pairs, key=lambda p: p.distance)
            held.append(
                f'self-hit task active ({p.name_a} / {p.name_b} {p.distance * 1e3:.1f} mm)'
            )
        if 'joint_limits' in active:
            margin = np.minimum(k.q - self.lower, self.upper - k.q)
            j = int(np.argmin(margin))
            held.append(f'joint-limit task active (joint {j + 1} at {k.q[j]:.3f} rad)')
        raise IkNotConverged(
            index,
            float(np.linalg.norm(error[:3])),
            float(np.linalg.norm(error[3:])),
            '; '.join(held),
        )


def joint_segment(q_a: np.ndarray, q_b: np.ndarray, step_rad: float) -> np.ndarray:
    """Straight joint-space samples after ``q_a`` up to ``q_b`` [rad], shape (n, 7), at most
    ``step_rad`` [rad] apart on every joint.
    """
    n = max(1, math.ceil(float(np.max(np.abs(q_b - q_a))) / step_rad))
    return np.array([q_a + (q_b - q_a) * t for t in np.arange(1, n + 1) / n])


def _serial_chain(
    model: pin.Model, geometry_model: pin.GeometryModel
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(jointPlacement of joints 1 … n (n, 4, 4), parent joint of each geometry (G,), its
    placement in that joint (G, 4, 4)): the arguments of :func:`.kernels.chain_placements`.

    Raises:
        ValueError: the model is not a serial chain of revolute-z joints.
    """
    parents = list(model.parents)
    names = [model.joints[j].shortname() for j in range(1, model.njoints)]
    if parents[1:] != list(range(model.njoints - 1)) or any(n != 'JointModelRZ' for n in names):
        raise ValueError(f'not a serial chain of revolute-z joints: {names}, parents {parents}')
    joints = np.array([model.jointPlacements[j].homogeneous for j in range(1, model.njoints)])
    parent = np.array([g.parentJoint for g in geometry_model.geometryObjects], dtype=np.int64)
    placement = np.array([g.placement.homogeneous for g in geometry_model.geometryObjects])
    return (
        np.ascontiguousarray(joints, dtype=float),
        parent,
        np.ascontiguousarray(placement, dtype=float),
    )


def _bounding_radius(geometry: Any) -> float:
    """Radius [m] of the sphere about a primitive's centre that contains it."""
    if hasattr(geometry, 'halfLength'):
        return math.hypot(float(geometry.radius), float(geometry.halfLength))
    if hasattr(geometry, 'halfSide'):
        return float(np.linalg.norm(geometry.halfSide))
    return float(geometry.radius)


def _within(error: np.ndarray, tol_m: float, tol_rad: float) -> bool:
    return bool(
        np.dot(error[:3], error[:3]) <= tol_m**2 and np.dot(error[3:], error[3:]) <= tol_rad**2
    )
