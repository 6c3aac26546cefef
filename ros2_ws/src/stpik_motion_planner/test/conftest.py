"""Shared fixtures of the motion-planner unit tests (no ROS import); ``robot``, ``free_scene``,
``boxed_scene`` and the autouse ``unhurried_planner`` live in :mod:`stpik_motion_planner.testing`
(shared with ``qtree_benchmarks/test``).
"""

from __future__ import annotations

import pytest
from qtree_scene.testing import cylinder, scenario
from stpik_motion_planner.testing import (  # noqa: F401 (fixtures)
    boxed_scene,
    free_scene,
    robot,
    unhurried_planner,
)


@pytest.fixture(scope='session')
def make_cylinder():
    """Factory fixture: :func:`cylinder`."""
    return cylinder


@pytest.fixture(scope='session')
def make_scenario():
    """Factory fixture: :func:`scenario`."""
    return scenario
