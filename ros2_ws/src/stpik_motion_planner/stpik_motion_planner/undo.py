"""Undoing a stopped relocation: the executed path backwards (no ROS import, #32).

When the scene changes under an execution (``SCENE_CHANGED``) or the grasp is refused
(``GRASP_FAILED``) before the object was released, the relocation is **undone**, not finished:
the arm goes back along the part of the plan it executed to the plan's first sample (the home
configuration every plan starts from), and a carried object is put back down where it was
grasped. Why undo: finishing needs a new plan from a configuration the planner never plans from
(its answers and its cache all start at home), through a scene that just changed; the executed
path is the one motion known to have been clear a moment ago, the closed loop still checks it
against the live scene on the way back (so it stops again rather than hit a newcomer), and once
home the task planner re-plans from a state the planner understands. After the release (the
retreat) nothing is undone: the object is placed and the retreat is finished.
"""

from __future__ import annotations

import numpy as np

UNDONE = 'undone: the arm went back along the executed path to the start of the plan'
MIN_DT_S = 1e-3  # samples closer in time are merged in the reversed motion [s]


def reversed_samples(
    times: np.ndarray, joints: np.ndarray, t_from: float, t_to: float
) -> tuple[np.ndarray, np.ndarray]:
    """The planned motion from plan time ``t_from`` back to ``t_to``, re-timed from 0.

    The joints are linear between samples (as :class:`~.closed_loop.PlannedMotion`), so the
    reversed motion passes through the same configurations at the same speeds.

    Args:
        times: sample times of the plan [s], shape (N,), increasing.
        joints: planned joint angles [rad], shape (N, 7).
        t_from: plan time where the arm stopped [s].
        t_to: plan time to go back to [s], ``t_to <= t_from``.

    Returns:
        (times from 0 [s] (M,), joints [rad] (M, 7)), M ≥ 2, from q(t_from) to q(t_to).

    Raises:
        ValueError: ``t_to > t_from``.
    """
    times, joints = np.asarray(times, dtype=float), np.asarray(joints, dtype=float)
    if t_to > t_from:
        raise ValueError(f't_to={t_to} s is after t_from={t_from} s')
    t_from = float(np.clip(t_from, times[0], times[-1]))
    t_to = float(np.clip(t_to, times[0], times[-1]))
    inner = [k for k in range(len(times)) if t_to + MIN_DT_S < times[k] < t_from - MIN_DT_S]
    plan_times = [t_from, *(times[k] for k in reversed(inner)), t_to]
    rows = [_at(times, joints, t) for t in plan_times]
    out_times = t_from - np.array(plan_times)
    if out_times[-1] <= 0.0:  # stopped at the start already: a standstill of one tick
        out_times[-1] = MIN_DT_S
    return out_times, np.array(rows)


def _at(times: np.ndarray, joints: np.ndarray, t: float) -> np.ndarray:
    """q(t), linear between samples [rad] (7,)."""
    return np.array([np.interp(t, times, joints[:, j]) for j in range(joints.shape[1])])
