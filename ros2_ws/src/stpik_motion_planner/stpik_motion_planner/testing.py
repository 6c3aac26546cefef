"""Pytest fixtures shared by the unit tests that build motion planners (no ROS import).

Imported by the ``conftest.py`` of ``stpik_motion_planner/test`` and ``qtree_benchmarks/test``
(a fixture imported into a conftest is registered there); only tests import this module.
"""

from __future__ import annotations

import pytest

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
