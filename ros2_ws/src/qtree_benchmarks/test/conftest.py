"""Shared fixtures of the benchmark unit tests (no ROS import)."""

from __future__ import annotations

import pytest
from jaco2_description.model import Jaco2Model
from qtree_scene.scene import Scenario
from qtree_scene.testing import boxed_scenario, free_scenario
from stpik_motion_planner.testing import unhurried_planner  # noqa: F401 (autouse fixture)


@pytest.fixture(scope='session')
def robot() -> Jaco2Model:
    """One shared robot model."""
    return Jaco2Model()


@pytest.fixture(scope='session')
def free_scene() -> Scenario:
    """The target alone, 0.65 m in front of the robot."""
    return free_scenario()


@pytest.fixture(scope='session')
def boxed_scene() -> Scenario:
    """The target boxed in on every side by six obstacles 8 cm away."""
    return boxed_scenario()
