"""Grasp choices that make the planner generalise: short and front-row objects, boxes, reach."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.cartesian_path import grasp_rotation
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import IkNotConverged
from stpik_motion_planner.grasp_choice import (
    HAND_BELOW_EE_M,
    candidate_yaws,
    carry_height,
    converge_first,
    grasp_height,
    pregrasp_seeds,
    turned_joint,
)
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.reference import verify_motion
from stpik_motion_planner.stpik import Stpik


def _cyl(h: float, x: float = 0.6, y: float = 0.0, name: str = 'T', role: str = 'target'):
    return ObjectSpec(name, role, 'cylinder', (x, y, h / 2), radius=0.03, height=h)


def test_grasp_height_keeps_the_hand_off_the_table() -> None:
    c = PlannerConfig()
    tall = grasp_height(_cyl(0.25), c.obstacle_activation_m, c.obstacle_min_distance_m)
    assert tall == pytest.approx(0.125)  # mid-height
    mid = grasp_height(_cyl(0.14), c.obstacle_activation_m, c.obstacle_min_distance_m)
    assert mid - HAND_BELOW_EE_M >= c.obstacle_activation_m  # the hand's lowest point
    assert mid <= 0.14 - 0.015
    short = grasp_height(_cyl(0.08), c.obstacle_activation_m, c.obstacle_min_distance_m)
    assert short - HAND_BELOW_EE_M > c.obstacle_min_distance_m and short < 0.08


def test_carry_height_clears_objects_on_the_way_not_far_ones(make_scenario) -> None:
    """The drop zone is at (0, 0.5): O1 stands on the way, O2 on the other side."""
    target = _cyl(0.10)
    on_the_way = _cyl(0.20, x=0.4, y=0.2, name='O1', role='obstacle')
    far = _cyl(0.25, x=0.45, y=-0.4, name='O2', role='obstacle')
    scene = make_scenario(target, on_the_way, far)
    z = carry_height(scene, target, 0.07, 0.04, HAND_BELOW_EE_M)
    assert z == pytest.approx(0.20 + 0.04 + 0.07)  # the carried bottom 4 cm over O1's top


def test_turned_joint_keeps_room_to_the_limits() -> None:
    lo, hi = -2 * math.pi, 2 * math.pi
    assert turned_joint(6.0, 4.71, lo, hi) == pytest.approx(6.0 - 2 * math.pi)
    assert turned_joint(4.0, 4.71, lo, hi) == pytest.approx(4.0)


def test_candidate_yaws_are_wider_than_the_configured_ones() -> None:
    c = PlannerConfig()
    yaws = candidate_yaws(np.array([0.5, 0.0, 0.05]), c)
    assert len(yaws) == c.approach_directions + 2
    widest = (c.approach_directions + 2) // 2  # alternating ±step, ±2·step, ...
    assert max(abs(y) for y in yaws) == pytest.approx(widest * c.approach_yaw_step_rad)


def test_out_of_reach_pregrasp_is_rejected_at_once(robot) -> None:
    stpik = Stpik(robot, PlannerConfig())
    far = pin.SE3(grasp_rotation(0.0), np.array([1.4, 0.0, 0.1]))
    with pytest.raises(IkNotConverged):
        converge_first(stpik, pregrasp_seeds(stpik, far, 4.71), far, SceneWorld([]), np.inf)


@pytest.mark.parametrize(
    'obj',
    [
        _cyl(0.08),  # short: failed before (hand half height, not lowest point, kept off table)
        _cyl(0.14, x=0.38, y=0.1),  # front row: failed before (radial approach only)
        _cyl(0.12, x=0.55, y=-0.35),  # to the right: joint 1 / joint 7 near ±2π before
        ObjectSpec('T', 'target', 'box', (0.55, 0.1, 0.05), yaw=0.4, size=(0.06, 0.08, 0.10)),
    ],
    ids=['short', 'front_row', 'right', 'box'],
)
def test_free_objects_are_graspable_and_verify(obj, make_scenario, robot) -> None:
    scene = make_scenario(obj)
    planner = MotionPlanner(scene, PlannerConfig(time_limit_s=60.0), model=robot)
    result = planner.check('T', [])
    assert result.feasible, result.message
    assert verify_motion(scene, [], 'T', result, robot, step_rad=0.05) == (True, '')


def test_verifier_rejects_a_motion_through_an_object(make_scenario, robot) -> None:
    free = make_scenario(_cyl(0.14))
    result = MotionPlanner(free, PlannerConfig(time_limit_s=60.0), model=robot).check('T', [])
    assert result.feasible, result.message
    yaw = result.approach_yaw
    x, y = 0.6 - 0.09 * math.cos(yaw), -0.09 * math.sin(yaw)  # on the approach, 9 cm before
    blocked = make_scenario(_cyl(0.14), _cyl(0.2, x=x, y=y, name='O1', role='obstacle'))
    valid, reason = verify_motion(blocked, [], 'T', result, robot, step_rad=0.05)
    assert not valid and 'hits the scene' in reason
    assert verify_motion(blocked, ['O1'], 'T', result, robot, 0.05) == (True, '')
