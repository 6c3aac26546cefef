"""Eq. (6) solver and STPIK convergence."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from hypothesis import given, settings
from hypothesis import strategies as st
from stpik_motion_planner.cartesian_path import grasp_rotation
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.stpik import (
    READY,
    Stpik,
    damped_pinv,
    pinv_pair,
    solve_hierarchy,
    truncated_pinv,
)
from stpik_motion_planner.tasks import TaskRows


@settings(max_examples=30, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(st.lists(st.floats(-2, 2), min_size=14, max_size=14))
def test_hierarchy_keeps_the_first_task_exact(values):
    rng = np.random.default_rng(abs(hash(tuple(values))) % 2**32)
    J1 = rng.normal(size=(2, 7))
    J2 = rng.normal(size=(6, 7))
    x1, x2 = np.array(values[:2]), np.array(values[2:8])
    dq = solve_hierarchy(
        [TaskRows(J1, x1, ('a', 'b')), TaskRows(J2, x2, tuple('cdefgh'))],
        7,
        damping=1e-9,
        threshold=1e-9,
    )
    assert np.allclose(J1 @ dq, x1, atol=1e-8)
    # Lower task: best possible in the null space of the first.
    N = np.eye(7) - np.linalg.pinv(J1) @ J1
    best = np.linalg.pinv(J1) @ x1 + np.linalg.pinv(J2 @ N) @ (x2 - J2 @ np.linalg.pinv(J1) @ x1)
    assert np.allclose(dq, best, atol=1e-6)


@settings(max_examples=30, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 1e-2))
def test_one_svd_gives_both_pseudo_inverses_bit_identically(seed, scale):
    """pinv_pair (one SVD) equals damped_pinv and truncated_pinv exactly, also where damping
    acts (singular value ``scale`` below the threshold)."""
    rng = np.random.default_rng(seed)
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V, _ = np.linalg.qr(rng.normal(size=(7, 7)))
    J = U @ np.diag([1.0, 0.8, 0.5, 0.3, 0.1, scale]) @ V[:6]
    damped, truncated = pinv_pair(J, 0.02, 0.02)
    assert np.array_equal(damped, damped_pinv(J, 0.02, 0.02))
    assert np.array_equal(truncated, truncated_pinv(J))


def test_damped_pinv_is_exact_away_from_singularities_and_bounded_near_them():
    A = np.diag([1.0, 0.5, 1e-6])
    P = damped_pinv(A, damping=0.05, threshold=0.01)
    assert np.allclose(P[:2, :2], np.diag([1.0, 2.0]))
    assert abs(P[2, 2]) < 1e-2


def test_converges_on_a_reachable_side_grasp(robot):
    stpik = Stpik(robot, PlannerConfig())
    target = pin.SE3(grasp_rotation(0.2), np.array([0.55, 0.1, 0.09]))
    q = stpik.converge(READY, target, SceneWorld([]))
    reached = robot.ee_pose(q)
    assert np.linalg.norm(reached.translation - target.translation) < 0.005
    assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) < 0.025
    assert np.all(q >= robot.limits.lower) and np.all(q <= robot.limits.upper)
