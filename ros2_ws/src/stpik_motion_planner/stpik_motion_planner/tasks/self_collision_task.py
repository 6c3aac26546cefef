"""Self-hit avoidance (Sect. 4, task 2): one set-based row per close pair of links."""

from __future__ import annotations

import numpy as np

from stpik_motion_planner.tasks.task import Kinematics, SetBasedTask


def distance_rows(k: Kinematics, pairs: list, second_is_robot: bool):
    """σ = d (m,) and J = nᵀ(J_a(p_a) − J_b(p_b)) (m, 7) of close pairs.

    n is the unit vector from p_b to p_a (the direction that increases d); pairs whose witness
    points coincide (deep contact) give no usable direction and are skipped.
    """
    sigma, rows, labels = [], [], []
    for p in pairs:
        delta = p.point_a - p.point_b
        norm = float(np.linalg.norm(delta))
        if norm < 1e-9:
            continue
        n = delta / norm if p.distance >= 0 else -delta / norm
        row = n @ k.point_jacobian(p.name_a, p.point_a)
        if second_is_robot:
            row = row - n @ k.point_jacobian(p.name_b, p.point_b)
        sigma.append(p.distance)
        rows.append(row)
        labels.append(f'{p.name_a}/{p.name_b}')
    jacobian = np.asarray(rows) if rows else np.zeros((0, k.model.nv))
    return np.asarray(sigma, dtype=float), jacobian, tuple(labels)


class SelfCollisionTask(SetBasedTask):
    """σ = distance between two non-adjacent links, valid above ``activation`` [m]."""

    name = 'self_hit'

    def __init__(self, activation: float, gain: float = 0.5) -> None:
        super().__init__(gain)
        self.activation = activation

    def may_activate(self, k: Kinematics) -> bool:
        """Whether a pair is closer than the activation distance."""
        return any(p.distance < self.activation for p in k.self_pairs)

    def evaluate(self, k: Kinematics):
        """Rows of the pairs closer than the activation distance."""
        # Only pairs below the activation distance can leave the valid set: rows of the others
        # (found up to the step bound's lookahead) would be discarded by :meth:`compute`.
        close = [p for p in k.self_pairs if p.distance < self.activation]
        sigma, jacobian, labels = distance_rows(k, close, second_is_robot=True)
        lower = np.full(len(sigma), self.activation)
        return sigma, jacobian, lower, np.full(len(sigma), np.inf), labels
