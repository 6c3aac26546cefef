"""Shared fixtures of the task-planner unit tests (no ROS import)."""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace

import pytest

# The RetrieveTarget goal's defaults (qtree_msgs/action/RetrieveTarget.action).
GOAL_DEFAULTS = dict(
    policy='H-EG',
    max_episodes=5000,
    seed=0,
    alpha=0.5,
    gamma=0.9,
    epsilon0=1.0,
    epsilon_min=1e-4,
    beta=1e-3,
    steady_episodes=50,
    execute=False,
    feedback_every=10,
    max_replans=3,
)


@pytest.fixture
def make_goal() -> Callable[..., SimpleNamespace]:
    """``make_goal(**changes)``: a goal as the node receives it, the defaults with ``changes``."""
    return lambda **changes: SimpleNamespace(**{**GOAL_DEFAULTS, **changes})
