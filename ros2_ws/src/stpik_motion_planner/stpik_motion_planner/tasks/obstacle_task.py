"""Obstacle avoidance (Sect. 4, task 3) against the remaining objects, the table and statics."""

from __future__ import annotations

import numpy as np

from stpik_motion_planner.tasks.self_collision_task import distance_rows
from stpik_motion_planner.tasks.task import Kinematics, SetBasedTask


class ObstacleTask(SetBasedTask):
    """σ = distance between a robot body and a scene object, valid above ``activation`` [m]."""

    name = 'obstacles'

    def __init__(self, activation: float, gain: float = 0.5) -> None:
        super().__init__(gain)
        self.activation = activation

    def may_activate(self, k: Kinematics) -> bool:
        """Whether a pair is closer than the activation distance."""
        return any(p.distance < self.activation for p in k.scene_pairs)

    def evaluate(self, k: Kinematics):
        """Rows of the (body, object) pairs found closer than the activation distance."""
        # Only pairs below the activation distance can leave the valid set: rows of the others
        # (found up to the step bound's lookahead) would be discarded by :meth:`compute`.
        close = [p for p in k.scene_pairs if p.distance < self.activation]
        sigma, jacobian, labels = distance_rows(k, close, second_is_robot=False)
        lower = np.full(len(sigma), self.activation)
        return sigma, jacobian, lower, np.full(len(sigma), np.inf), labels
