"""Pytest fixtures shared by the unit tests that build motion planners (no ROS import): the
autouse ``unhurried_planner``, ``robot``, ``free_scene`` and ``boxed_scene``.

Imported by the ``conftest.py`` of ``stpik_motion_planner/test`` and ``qtree_benchmarks/test``
(a fixture imported into a conftest is registered there); only tests import this module.
"""

from __future__ import annotations

import pytest
from jaco2_description.model import Jaco2Model
from qtree_scene.scene import Scenario
from qtree_scene.testing import boxed_scenario, free_scenario

from stpik_motion_planner.config import PlannerConfig

UNHURRIED_TIME_LIMIT_S = 120.0  # per check, for planners built with the default config [s]


@pytest.fixture(autouse=True)
def unhurried_planner(monkeypatch: pytest.MonkeyPatch) -> None:
    """Planners built with the default config get 120 s, not 5 s, per check.

    Unit tests check answers, not speed (the benchmarks measure it): on a loaded 2-core machine
    (CI beside other jobs, load 7.8) the 5 s default turned feasible checks into TIMEOUT
    (``test_fix13_the_carry_keeps_the_object_near_upright``,
    ``test_blocker_sweeps_cover_the_top_approaches``). Tests of the deadline set
    ``time_limit_s`` themselves.
    """
    defaults = PlannerConfig.__init__.__kwdefaults__
    assert defaults is not None and 'time_limit_s' in defaults
    monkeypatch.setitem(defaults, 'time_limit_s', UNHURRIED_TIME_LIMIT_S)


@pytest.fixture(scope='session')
def robot() -> Jaco2Model:
    """One shared robot model (building it takes a few ms)."""
    return Jaco2Model()


@pytest.fixture(scope='session')
def free_scene() -> Scenario:
    """The target alone, 0.65 m in front of the robot."""
    return free_scenario()


@pytest.fixture(scope='session')
def boxed_scene() -> Scenario:
    """The target boxed in on every side by six obstacles 8 cm away."""
    return boxed_scenario()
