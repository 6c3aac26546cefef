"""Eq. (8) reward values."""

from qtree_task_planner.rewards import reward


def test_obstacle_relocated_is_zero() -> None:
    assert reward('O1', 'T', feasible=True) == 0.0


def test_infeasible_obstacle_and_target_are_minus_one() -> None:
    assert reward('O1', 'T', feasible=False) == -1.0
    assert reward('T', 'T', feasible=False) == -1.0


def test_target_relocated_is_hundred() -> None:
    assert reward('T', 'T', feasible=True) == 100.0
