"""Mechanical joint-limit avoidance (Sect. 4, task 1): one set-based row per limited joint."""

from __future__ import annotations

import numpy as np

from stpik_motion_planner.tasks.task import Kinematics, SetBasedTask


class JointLimitTask(SetBasedTask):
    """σ_i = q_i, valid in [lower_i + margin, upper_i − margin]; J_i = e_iᵀ."""

    name = 'joint_limits'

    def __init__(self, lower: np.ndarray, upper: np.ndarray, margin: float, gain: float = 0.5):
        """Args:
        lower: lower limits [rad], shape (7,).
        upper: upper limits [rad], shape (7,).
        margin: activation margin inside the limits [rad].
        gain: K·dt of the activated rows.
        """
        super().__init__(gain)
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.margin = margin
        self._eye = np.eye(len(self.lower))
        self._low, self._high = self.lower + margin, self.upper - margin  # thresholds [rad]
        self._labels = tuple(f'joint_{i + 1}' for i in range(len(self.lower)))

    def may_activate(self, k: Kinematics) -> bool:
        """Whether a joint is outside [lower + margin, upper − margin]."""
        q = k.q
        return bool((q < self._low).any() or (q > self._high).any())

    def evaluate(self, k: Kinematics):
        """σ = q (7,), J = I (7, 7), thresholds at the limits ∓ margin."""
        return (
            np.asarray(k.q, dtype=float),
            self._eye,
            self._low,
            self._high,
            self._labels,
        )
