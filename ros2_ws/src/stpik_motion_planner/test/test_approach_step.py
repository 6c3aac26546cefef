"""Approach yaws every 0.2 rad (#14): clearable clutter leaves narrow approach windows.

``generate_clutter(10, 0.15, 1009)``: O8 stands with its free approaches between the old 0.4 rad
steps. With 9 yaws every 0.4 rad the planner answered SCENE_COLLISION (the palm grazes O3 at
+0.4 rad) where the 17 yaws every 0.2 rad find a verified motion; the false-infeasible benchmark
found 17 such answers in 233 (``benchmarks/results/false_infeasible.md``).
"""

from __future__ import annotations

import math

import pytest
from qtree_scene.generator import generate_clutter
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner

SCENE = generate_clutter(10, 0.15, 1009)


@pytest.fixture(scope='module')
def planner(robot) -> MotionPlanner:
    return MotionPlanner(SCENE, model=robot)


def test_the_default_planner_finds_the_narrow_window(planner) -> None:
    result = planner.plan('O8', [])
    assert result.feasible, result.message
    obj = SCENE.object('O8')
    offset = result.approach_yaw - math.atan2(obj.position[1], obj.position[0])
    assert round(offset / 0.2) % 2 == 1  # an approach the 0.4 rad step never tried


def test_the_old_step_misses_it(robot) -> None:
    coarse = PlannerConfig(approach_directions=9, approach_yaw_step_rad=0.4)
    result = MotionPlanner(SCENE, coarse, model=robot).plan('O8', [])
    assert not result.feasible
