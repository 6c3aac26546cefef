"""Shared fixtures of the benchmark unit tests (no ROS import): those of
:mod:`stpik_motion_planner.testing` (a fixture imported into a conftest is registered there).
"""

from __future__ import annotations

from stpik_motion_planner.testing import (  # noqa: F401 (fixtures)
    boxed_scene,
    free_scene,
    robot,
    unhurried_planner,
)
