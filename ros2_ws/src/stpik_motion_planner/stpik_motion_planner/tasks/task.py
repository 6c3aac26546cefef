"""Base classes of the STPIK tasks (Sect. 3.1; Di Lillo et al. set-based tasks). No ROS import.

A task σ(q) ∈ ℝ^m has a Jacobian J = ∂σ/∂q, shape (m, 7). An equality task drives its error
σ̃ = σ_d − σ to zero; a set-based task is valid inside [σ_a,l, σ_a,u] and only enters the
hierarchy (as an equality task holding σ at the crossed threshold) when it leaves that range.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from stpik_motion_planner.collision import Proximity


@dataclass
class Kinematics:
    """Everything tasks need at one configuration, computed once per STPIK iteration.

    Attributes:
        q: joint angles [rad], shape (7,).
        model: Pinocchio model; ``data`` holds joint placements and joint Jacobians at ``q``.
        data: Pinocchio data after ``computeJointJacobians`` and ``updateFramePlacements``.
        world_ee: end-effector pose in the world frame.
        ee_frame: Pinocchio frame index of the end-effector.
        body_joint: Pinocchio joint index carrying each collision body, by body name.
        self_pairs: non-adjacent link pairs closer than the self-hit activation distance.
        scene_pairs: (body, scene object) pairs closer than the obstacle activation distance.
    """

    q: np.ndarray
    model: pin.Model
    data: pin.Data
    world_ee: pin.SE3
    ee_frame: int
    body_joint: dict[str, int]
    self_pairs: list[Proximity] = field(default_factory=list)
    scene_pairs: list[Proximity] = field(default_factory=list)
    _joint_jacobians: dict[int, np.ndarray] = field(default_factory=dict, repr=False)

    def point_jacobian(self, body: str, point: np.ndarray) -> np.ndarray:
        """Jacobian of the world velocity of a point fixed to ``body``, shape (3, 7).

        Args:
            body: collision body name (a link, or ``'attached'`` for the grasped object).
            point: the point in the world frame [m], shape (3,).
        """
        joint = self.body_joint[body]
        J = self._joint_jacobians.get(joint)
        if J is None:  # once per joint and configuration
            J = pin.getJointJacobian(self.model, self.data, joint, pin.LOCAL_WORLD_ALIGNED)
            self._joint_jacobians[joint] = J
        r = point - self.data.oMi[joint].translation
        # v_p = v_o + ω × r = J_v q̇ − [r]× J_ω q̇
        return J[:3] - pin.skew(r) @ J[3:]


@dataclass(frozen=True)
class TaskRows:
    """Rows of one task entering the hierarchy of eq. (6).

    Attributes:
        jacobian: J_i, shape (m, 7).
        error: K_i σ̃_i (already scaled by the gain), shape (m,).
        labels: one name per row (for messages).
    """

    jacobian: np.ndarray
    error: np.ndarray
    labels: tuple[str, ...]

    @property
    def dim(self) -> int:
        """Number of rows m."""
        return len(self.labels)


class Task(ABC):
    """An equality task: drive σ̃ = σ_d − σ to zero with gain ``gain`` (K·dt)."""

    name = 'task'
    set_based = False

    def __init__(self, gain: float = 1.0) -> None:
        self.gain = gain

    @abstractmethod
    def compute(self, k: Kinematics) -> TaskRows:
        """The rows (J, K σ̃) of the task at ``k``."""


class SetBasedTask(Task):
    """A set-based task, valid while σ_a,l ≤ σ ≤ σ_a,u."""

    set_based = True

    @abstractmethod
    def evaluate(
        self, k: Kinematics
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, tuple[str, ...]]:
        """σ (m,), J (m, 7), σ_a,l (m,), σ_a,u (m,) and row labels at ``k``."""

    def may_activate(self, k: Kinematics) -> bool:
        """False only when :meth:`compute` gives no row at ``k`` (a cheap test: the STPIK step
        skips the task then, #28); the default computes it.
        """
        return bool(self.compute(k).dim)

    def compute(self, k: Kinematics) -> TaskRows:
        """Rows outside their activation range, each held at the crossed threshold."""
        sigma, jacobian, lower, upper, labels = self.evaluate(k)
        below, above = sigma < lower, sigma > upper
        rows = np.flatnonzero(below | above)
        if rows.size == 0:  # nothing outside its valid set (the usual case)
            return TaskRows(jacobian[:0], np.zeros(0), ())
        desired = np.where(below, lower, upper)[rows]
        return TaskRows(
            jacobian[rows],
            self.gain * (desired - sigma[rows]),
            tuple(labels[i] for i in rows),
        )
