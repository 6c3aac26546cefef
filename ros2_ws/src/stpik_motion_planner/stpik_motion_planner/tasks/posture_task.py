"""Posture task: the lowest priority, below the paper's four tasks (our addition).

It pulls the joints toward a reference posture (the home configuration) inside the null space of
every other task, so redundancy is not spent winding the continuous joints toward their ±2π
bounds. It never changes what the higher-priority tasks achieve (eq. 6 projection).
"""

from __future__ import annotations

import numpy as np

from stpik_motion_planner.tasks.task import Kinematics, Task, TaskRows


class PostureTask(Task):
    """σ = q, σ_d = ``reference`` [rad] (7,); J = I."""

    name = 'posture'

    def __init__(self, reference: np.ndarray, gain: float = 0.05) -> None:
        super().__init__(gain)
        self.reference = np.asarray(reference, dtype=float)
        self._eye = np.eye(len(self.reference))
        self._labels = tuple(f'q{i + 1}' for i in range(len(self.reference)))

    def compute(self, k: Kinematics) -> TaskRows:
        """Rows (I (7, 7), K (q_ref − q))."""
        return TaskRows(self._eye, self.gain * (self.reference - k.q), self._labels)
