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
from collections.abc import Sequence

import numpy as np
import pinocchio as pin
from jaco2_description.model import EE_FRAME, Jaco2Model

from stpik_motion_planner.collision import RobotBodies, SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import (
    IkNotConverged,
    JointLimitViolated,
    PlanningTimeout,
    SceneCollision,
    SelfCollision,
)
from stpik_motion_planner.grasp_choice import turned_joint
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

LOOSE_FACTOR = 3.0  # tolerance multiplier on intermediate path samples [-]
# Posture of a low side grasp straight ahead (EE at about (0.6, 0, 0.08) m, approach along +x)
# with wide joint-limit and self-hit margins, found offline by multi-start IK [rad]. Turning
# joint 1 by -ψ turns it to azimuth ψ; the posture task pulls the arm toward that posture.
READY = np.array([5.5, 1.37, -2.08, 1.11, 2.65, 4.53, 5.06])


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


def solve_hierarchy(levels: Sequence[TaskRows], n: int, damping: float, threshold: float):
    """Eq. (6): q̇_i = q̇_{i−1} + (J_i N_{i−1})^† (K_i σ̃_i − J_i q̇_{i−1}), N_i = N_{i−1} − (J_i N_{i−1})^† J_i N_{i−1}.

    Args:
        levels: tasks in priority order (highest first), rows (J_i, K_i σ̃_i).
        n: number of joints.
        damping: pseudo-inverse damping.
        threshold: singular value where damping starts.

    Returns:
        Joint step q̇ (already multiplied by dt) [rad], shape (n,).
    """  # noqa: E501
    dq = np.zeros(n)
    N = np.eye(n)
    for rows in levels:
        if rows.dim == 0:
            continue
        JN = rows.jacobian @ N
        pinv = damped_pinv(JN, damping, threshold)
        dq = dq + pinv @ (rows.error - rows.jacobian @ dq)
        N = N - pinv @ JN
    return dq


class Stpik:
    """STPIK tracker of one robot model against a scene.

    Attributes:
        collision_time: wall time spent in FCL queries since the last :meth:`reset_timers` [s].
    """

    def __init__(self, robot: Jaco2Model, config: PlannerConfig) -> None:
        self.config = config
        self.model = robot.model
        self.data = self.model.createData()
        self.geometry_model = robot.geometry_model
        self.geometry_data = pin.GeometryData(self.geometry_model)
        self.lower = np.asarray(robot.limits.lower, dtype=float)
        self.upper = np.asarray(robot.limits.upper, dtype=float)
        self.bodies = RobotBodies(self.geometry_model, robot.collision_links)
        self.ee_frame = self.model.getFrameId(EE_FRAME)
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
        self.collision_time = 0.0

    def ready_posture(self, position: np.ndarray, q1: float) -> np.ndarray:
        """:data:`READY` turned to the azimuth of ``position`` [m], joint 1 nearest ``q1``."""
        reference = READY.copy()
        turned = READY[0] - math.atan2(position[1], position[0])
        reference[0] = turned_joint(turned, q1, self.lower[0], self.upper[0])
        return reference

    def reset_timers(self) -> None:
        """Zero :attr:`collision_time`."""
        self.collision_time = 0.0

    def kinematics(self, q: np.ndarray, scene: SceneWorld) -> Kinematics:
        """Forward kinematics, Jacobians and close pairs at ``q`` [rad] (7,)."""
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        pin.updateGeometryPlacements(
            self.model, self.data, self.geometry_model, self.geometry_data
        )
        world_ee = self.data.oMf[self.ee_frame]
        start = time.perf_counter()
        self.bodies.place(self.geometry_data.oMg, world_ee)
        self_pairs = self.bodies.self_proximities(self.config.self_activation_m)
        scene_pairs = self.bodies.scene_proximities(scene, self.config.obstacle_activation_m)
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
        """One STPIK step at ``k``: joint step [rad] (7,) and the activated set-based tasks."""
        c = self.config
        ee = self.ee.compute(k)
        posture = self.posture.compute(k)
        dq_free = solve_hierarchy([ee, posture], 7, c.damping, c.singular_threshold)
        levels, active = [], []
        for task in (self.joint_limits, self.self_hit, self.obstacles):
            rows = task.compute(k)
            if rows.dim == 0:
                continue
            # Keep a row only if the lower-priority solution drives σ further out of its set.
            keep = (rows.jacobian @ dq_free) * rows.error <= 0.0
            if np.any(keep):
                levels.append(
                    TaskRows(
                        rows.jacobian[keep], rows.error[keep], tuple(np.asarray(rows.labels)[keep])
                    )
                )
                active.append(task.name)
        if not levels:
            return dq_free, active
        dq = solve_hierarchy([*levels, ee, posture], 7, c.damping, c.singular_threshold)
        return dq, active

    def track(
        self,
        q: np.ndarray,
        samples: Sequence[pin.SE3],
        scene: SceneWorld,
        tight: Sequence[bool],
        deadline: float = np.inf,
    ) -> np.ndarray:
        """Follow ``samples`` (EE poses, world frame) from ``q``; joint angles per sample.

        Args:
            q: start configuration [rad], shape (7,).
            samples: EE poses to reach one after the other.
            scene: objects to avoid.
            tight: per sample, True to require the full tolerance (else ×3, see LOOSE_FACTOR).
            deadline: ``time.perf_counter()`` value past which :class:`PlanningTimeout` is raised.

        Returns:
            Joint angles reached at each sample [rad], shape (len(samples), 7).

        Raises:
            JointLimitViolated, SelfCollision, SceneCollision, IkNotConverged, PlanningTimeout.
        """
        c = self.config
        q = np.array(q, dtype=float)
        self.posture.reference = q.copy()
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
        k = self.kinematics(q, scene)
        active: list[str] = []
        for _ in range(iterations):
            if time.perf_counter() > deadline:
                raise PlanningTimeout.past(deadline, c.time_limit_s)
            if _within(
                pose_error(target, k.world_ee),
                c.position_tolerance_m / 2,
                c.orientation_tolerance_rad / 2,
            ):
                break
            q, k, active = self._step(q, k, scene)
        self._check(k, -1, target, 1.0, active)
        return q

    def _step(
        self, q: np.ndarray, k: Kinematics, scene: SceneWorld
    ) -> tuple[np.ndarray, Kinematics, list[str]]:
        """One eq. (6) step from ``q`` [rad], clamped to ``max_joint_step_rad`` on every joint.

        Returns:
            The new joint angles [rad] (7,), their kinematics, the names of the active tasks.
        """
        dq, active = self.solve(k)
        largest = float(np.max(np.abs(dq)))
        if largest > self.config.max_joint_step_rad:
            dq *= self.config.max_joint_step_rad / largest
        q = q + dq
        return q, self.kinematics(q, scene), active

    def transit(
        self, q_a: np.ndarray, q_b: np.ndarray, scene: SceneWorld, deadline: float = np.inf
    ) -> np.ndarray:
        """Free-space joint-space move from ``q_a`` to ``q_b`` [rad], checked at each sample.

        Samples are spaced ≤ ``step_rad`` on every joint; at each one the self-hit and scene
        distances must stay above their failure margins.

        Returns:
            Samples after ``q_a`` up to ``q_b`` [rad], shape (n, 7).

        Raises:
            SelfCollision, SceneCollision, PlanningTimeout.
        """
        c = self.config
        n = max(1, math.ceil(float(np.max(np.abs(q_b - q_a))) / c.step_rad))
        out = np.array([q_a + (q_b - q_a) * t for t in np.arange(1, n + 1) / n])
        for q in out:
            if time.perf_counter() > deadline:
                raise PlanningTimeout.past(deadline, c.time_limit_s)
            k = self.kinematics(q, scene)
            for p in k.self_pairs:
                if p.distance <= c.self_min_distance_m:
                    raise SelfCollision(p.name_a, p.name_b, p.distance)
            for p in k.scene_pairs:
                if p.distance <= c.obstacle_min_distance_m:
                    raise SceneCollision(p.name_a, p.name_b, p.distance)
        return out

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
        # Tracking failed: name the set-based task that held the arm back, if any.
        if 'obstacles' in active and k.scene_pairs:
            p = min(k.scene_pairs, key=lambda p: p.distance)
            raise SceneCollision(p.name_a, p.name_b, p.distance)
        if 'self_hit' in active and k.self_pairs:
            p = min(k.self_pairs, key=lambda p: p.distance)
            raise SelfCollision(p.name_a, p.name_b, p.distance)
        if 'joint_limits' in active:
            margin = np.minimum(k.q - self.lower, self.upper - k.q)
            j = int(np.argmin(margin))
            raise JointLimitViolated(j, float(k.q[j]), self.lower[j], self.upper[j])
        raise IkNotConverged(
            index, float(np.linalg.norm(error[:3])), float(np.linalg.norm(error[3:]))
        )


def _within(error: np.ndarray, tol_m: float, tol_rad: float) -> bool:
    return bool(
        np.dot(error[:3], error[:3]) <= tol_m**2 and np.dot(error[3:], error[3:]) <= tol_rad**2
    )
