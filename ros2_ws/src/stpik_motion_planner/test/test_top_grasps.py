"""Top grasps (#30 item 2): a second grasp family beside the paper's side grasp.

A bottle standing in a packed ring of cans has no side lane for the open hand (about 0.2 m
across the fingers); from above the fingers close on its top, 0.13 m over the cans.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from jaco2_description.model import HAND_OPENING_M
from qtree_scene.placement import TOP_PLACE_REACH_M, drop_slots, top_place_slots
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import InvalidConfig
from stpik_motion_planner.grasps import (
    Approach,
    candidate_approaches,
    check_families,
    rotation,
    side_rotation,
    top_grasp_problem,
    top_rotation,
    top_yaws,
)
from stpik_motion_planner.hand_model import grasp_width
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason
from stpik_motion_planner.verifier import STOP_CLEARANCE_M, Carried, TrajectoryVerifier

CENTRE = (0.55, 0.05)
CAN_R, CAN_H = 0.033, 0.12
GAP_M = 0.015  # packed: 1.5 cm between the cans and the bottle


def _bottle(x: float, y: float, h: float = 0.25, r: float = 0.03) -> ObjectSpec:
    return ObjectSpec('T', 'target', 'cylinder', (x, y, h / 2), radius=r, height=h)


def _ring(x: float, y: float, count: int = 8) -> list[ObjectSpec]:
    distance = 0.03 + GAP_M + CAN_R
    return [
        ObjectSpec(
            f'C{k}',
            'obstacle',
            'cylinder',
            (x + distance * math.cos(a), y + distance * math.sin(a), CAN_H / 2),
            radius=CAN_R,
            height=CAN_H,
        )
        for k, a in enumerate(2 * math.pi * np.arange(count) / count)
    ]


@pytest.fixture(scope='module')
def packed(make_scenario):
    return make_scenario(_bottle(*CENTRE), *_ring(*CENTRE))


@pytest.mark.parametrize('yaw', [0.0, 0.7, -2.1, math.pi])
def test_top_rotation_points_down_and_closes_the_fingers_like_the_side_grasp(yaw):
    top, side = top_rotation(yaw), side_rotation(yaw)
    assert np.linalg.det(top) == pytest.approx(1.0)
    assert top.T @ top == pytest.approx(np.eye(3))
    assert top[:, 2] == pytest.approx([0.0, 0.0, -1.0])  # approach straight down
    assert top[:, 0] == pytest.approx(side[:, 0])  # the same closing direction: grasp_width holds
    assert rotation(Approach('top', yaw)) == pytest.approx(top)
    assert rotation(Approach('side', yaw)) == pytest.approx(side)


def test_top_yaws_span_a_half_turn_across_the_base_direction_first():
    yaws = top_yaws((0.5, 0.5, 0.1))
    assert yaws[0] == pytest.approx(math.pi / 4)
    assert len(yaws) == len(set(np.round(yaws, 9))) == 8
    assert max(yaws) - min(yaws) == pytest.approx(math.pi * 7 / 8)
    both = candidate_approaches((0.5, 0.0, 0.1), ('top', 'side'), [0.0, 0.2])
    assert [a.family for a in both] == ['top'] * 8 + ['side'] * 2  # in the order asked


@pytest.mark.parametrize(
    'families', [(), 'side', ('up',), ('side', 'side'), ['top', 3], None, ('SIDE',)]
)
def test_bad_grasp_families_are_refused_with_their_name(families):
    with pytest.raises(ValueError):
        check_families(families)
    with pytest.raises(InvalidConfig, match='grasp_families'):
        PlannerConfig(grasp_families=families)


def test_the_paper_setting_is_the_default_and_families_keep_their_order():
    assert PlannerConfig().grasp_families == ('side',)
    assert PlannerConfig(grasp_families=['top', 'side']).grasp_families == ('top', 'side')


def test_a_top_grasp_needs_an_object_taller_than_the_open_fingertips_reach(robot, free_scene):
    planner = MotionPlanner(free_scene, model=robot)
    hand = planner.hand
    thin, wide = _bottle(0.5, 0.0, r=0.02), _bottle(0.5, 0.0, r=0.03)
    deep, shallow = (hand.top_grasp_depth(o, 0.0, 0.01) for o in (thin, wide))
    # The fingers narrow toward the palm: the wide bottle stops higher; the palm stays above.
    assert 0.015 < shallow < deep <= hand.palm_front_m - 0.01
    short = ObjectSpec('S', 'obstacle', 'cylinder', (0.5, 0.0, 0.03), radius=0.03, height=0.06)
    assert 'a top grasp needs' in top_grasp_problem(short, shallow, 0.03)
    assert top_grasp_problem(wide, shallow, 0.03) is None
    assert 'between the open fingers' in top_grasp_problem(wide, 0.005, 0.03)


def test_side_and_top_slots_are_disjoint_and_the_top_ones_in_reach(packed):
    side, top = top_place_slots(packed)
    every = drop_slots(packed)
    assert side and side == every[: len(side)]  # the simulator settles slot k of drop_slots
    assert {s.index for s in side}.isdisjoint(s.index for s in top)
    assert min(math.dist(a.xy, b.xy) for a in side for b in top) > 0.1
    assert top and all(math.hypot(*s.xy) <= TOP_PLACE_REACH_M for s in top)


def test_a_bottle_in_a_packed_ring_is_grasped_from_above_only(packed, robot):
    side_only = MotionPlanner(packed, model=robot)
    answer = side_only.check('T', [])
    assert not answer.feasible and answer.reason == Reason.NO_CARTESIAN_PATH, answer.message
    assert answer.grasp_family == ''

    planner = MotionPlanner(packed, PlannerConfig(grasp_families=('side', 'top')), model=robot)
    result = planner.check('T', [])
    assert result.feasible, result.message
    assert result.grasp_family == 'top' and 'top grasp' in result.message
    q = result.joint_trajectory
    grasp = robot.ee_pose(q[result.grasp_index])
    assert grasp.rotation[:, 2] @ np.array([0.0, 0.0, -1.0]) > math.cos(0.06)  # from above
    # The hand closes on the bottle's top, the palm above it.
    assert abs(grasp.translation[2] - 0.25) < 0.05
    assert np.linalg.norm(grasp.translation[:2] - np.array(CENTRE)) < 0.012
    # Width across the fingers measured from the returned trajectory (not the planner's flag).
    closing = grasp.rotation[:, 0]
    yaw = math.atan2(closing[1], closing[0]) - math.pi / 2
    assert grasp_width(packed.object('T'), yaw) <= HAND_OPENING_M
    # An independent verifier proves the stop clearance on every pair, the bottle carried.
    standing = planner.planning_scene('T', [])
    report = TrajectoryVerifier(robot, clearance_m=STOP_CLEARANCE_M).verify(
        q, standing, Carried(packed.object('T'), result.grasp_index, result.release_index)
    )
    assert report.ok, report.summary()
    # Placed on a slot in the hand's top reach, upright.
    release = robot.ee_pose(q[result.release_index])
    assert math.hypot(*release.translation[:2]) <= TOP_PLACE_REACH_M + 0.012
    assert release.rotation[:, 2] @ np.array([0.0, 0.0, -1.0]) > math.cos(0.06)

    cached = planner.check('T', [])  # the set-keyed cache keeps the family
    assert cached.from_cache and cached.grasp_family == 'top'


def test_a_bottle_wider_than_the_opening_is_too_big_for_either_family(make_scenario, robot):
    scene = make_scenario(_bottle(*CENTRE, r=0.042))  # 84 mm across, the hand closes on 82
    planner = MotionPlanner(scene, PlannerConfig(grasp_families=('side', 'top')), model=robot)
    result = planner.check('T', [])
    assert result.reason == Reason.OBJECT_TOO_BIG, result.message


def test_a_wide_bottle_is_taken_shallower_from_above(make_scenario, robot):
    """The open fingers narrow toward the palm: a 68 mm glass goes 16 mm between them (a 60 mm
    bottle 21 mm, every finger 10 mm off it), a 76 mm bottle only 12 mm: not from above."""
    wide = make_scenario(_bottle(*CENTRE, r=0.038), *_ring(*CENTRE))
    planner = MotionPlanner(wide, PlannerConfig(grasp_families=('top',)), model=robot)
    assert 'between the open fingers' in planner.check('T', []).message
    scene = make_scenario(_bottle(*CENTRE, r=0.034), *_ring(*CENTRE))
    planner = MotionPlanner(scene, PlannerConfig(grasp_families=('top',)), model=robot)
    depth = planner.hand.top_grasp_depth(scene.object('T'), 0.0, 0.01)
    assert 0.015 <= depth < planner.hand.top_grasp_depth(_bottle(*CENTRE), 0.0, 0.01)
    result = planner.check('T', [])
    assert result.feasible and result.grasp_family == 'top', result.message


def test_blocker_sweeps_cover_the_top_approaches(make_scenario, robot):
    """A can of the ring's own height: the open fingers reach below the neighbours' tops, so no
    approach works among them; the blocker report comes from side AND top sweeps."""
    can = ObjectSpec('T', 'target', 'cylinder', (*CENTRE, CAN_H / 2), radius=CAN_R, height=CAN_H)
    scene = make_scenario(can, *_ring(*CENTRE))
    planner = MotionPlanner(scene, PlannerConfig(grasp_families=('side', 'top')), model=robot)
    result = planner.check('T', [])
    assert not result.feasible
    sweeps = planner.blockers.sweeps['T']
    assert {s.family for s in sweeps} == {'side', 'top'}
    top_works = [s for s in sweeps if s.family == 'top' and s.works]
    assert top_works, 'the can alone is graspable from above'
    ring = {f'C{k}' for k in range(8)}
    assert set(result.blocking_ids) and set(result.blocking_ids) <= ring
    assert all(set(s.blockers(frozenset(), 0.01)) <= ring for s in top_works)
    assert any(s.blockers(frozenset(), 0.01) for s in top_works)  # the cans block from above
