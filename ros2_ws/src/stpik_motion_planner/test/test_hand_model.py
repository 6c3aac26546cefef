"""The open hand of the URDF: slot and grasp constants, the sampler's corridor and probes."""

from __future__ import annotations

import fcl
import numpy as np
import pinocchio as pin
import pytest
from jaco2_description.model import HAND_OPENING_M
from qtree_scene import placement
from qtree_scene.scene import ObjectSpec
from scipy.spatial import ConvexHull
from stpik_motion_planner.cartesian_path import CartesianSampler, grasp_rotation
from stpik_motion_planner.collision import ProbeSet, SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.hand_model import HandModel, finger_opening, open_hand_box
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason


def test_slot_layout_constants_contain_the_open_hand(robot):
    lower, upper = open_hand_box(robot)
    assert max(abs(lower[0]), upper[0]) <= placement.HAND_HALF_WIDTH_M  # across the fingers
    assert upper[2] <= placement.HAND_AHEAD_M  # fingertips beyond the EE origin
    assert -lower[2] <= placement.HAND_BEHIND_M + 1e-9  # palm behind it
    assert 0.19 < upper[0] - lower[0] < 0.21  # the open hand spans about 0.20 m


def test_grasp_opening_is_inside_the_open_fingertips(robot):
    opening = finger_opening(robot)
    assert 0.08 < opening < 0.11
    assert opening - 0.005 >= HAND_OPENING_M


# --- the hand model of the Cartesian sampler (issue #13 item 3) ---------------------------------


@pytest.fixture(scope='module')
def hand(robot):
    return HandModel(robot, PlannerConfig().pregrasp_standoff_m)


def _sampler(hand, make_scenario, *objects):
    scene = [o for o in make_scenario(*objects).objects]
    return CartesianSampler(SceneWorld(scene), PlannerConfig(), hand)


def _old_box_free(sampler, grasp):
    """Today's corridor before #13 item 3: a 0.11 m square box, 0.40 m behind the grasp."""
    back = PlannerConfig().pregrasp_standoff_m + 0.30
    axis = grasp.rotation[:, 2]
    geometry = fcl.Box(0.11, 0.11, back)
    body = fcl.CollisionObject(
        geometry, fcl.Transform(grasp.rotation, grasp.translation - axis * back / 2)
    )
    return not sampler.scene.clearance(body, geometry, PlannerConfig().obstacle_min_distance_m)


def _grasp(x, y, z, yaw=0.0):
    return pin.SE3(grasp_rotation(yaw), np.array([x, y, z]))


def test_hand_model_is_the_urdf_hand(hand):
    assert len(hand.parts) == 8  # palm, 3 proximal + 3 distal finger links, coaxial wrist link
    assert 0.100 < hand.half_width_m < 0.106  # open fingers: the hand is about 0.20 m wide
    assert hand.ball_radius == pytest.approx(0.0465)  # palm box half thickness
    wrist = hand.parts['link_6']
    assert np.max(np.hypot(wrist[:, 0], wrist[:, 1])) == pytest.approx(0.032)
    assert wrist[:, 2].min() < -0.29  # the wrist link reaches 0.295 m behind the EE


def test_sweep_contains_the_hand_at_every_pose_of_the_approach(hand):
    """The hull of the two ends contains every intermediate pose (no hand point escapes)."""
    for name, points in hand.parts.items():
        hull = ConvexHull(np.vstack([points, points - [0.0, 0.0, hand.standoff_m]]))
        for t in np.linspace(0.0, 1.0, 11):
            moved = points - [0.0, 0.0, t * hand.standoff_m]
            inside = hull.equations[:, :3] @ moved.T + hull.equations[:, 3:4]
            assert np.all(inside <= 1e-9), (name, t)


def test_palm_ball_lies_inside_the_palm_in_every_orientation(hand):
    palm = hand.parts['j2s7s300_link_7']
    low, high = palm.min(axis=0), palm.max(axis=0)
    assert np.all(hand.ball_centre - hand.ball_radius >= low - 1e-9)
    assert np.all(hand.ball_centre + hand.ball_radius <= high + 1e-9)


def test_corridor_narrower_than_the_hand_but_wider_than_the_old_box_is_blocked(
    hand, make_scenario, make_cylinder
):
    # Two cylinders (r 0.03) at ±0.11 m beside the approach, 3 cm behind the grasp: a gap of
    # 0.16 m between their surfaces, wider than the old 0.11 m box, narrower than the 0.20 m hand.
    posts = [make_cylinder(f'P{i}', 0.62, s * 0.11) for i, s in enumerate((-1, 1))]
    sampler = _sampler(hand, make_scenario, *posts)
    grasp = _grasp(0.65, 0.0, 0.07)
    assert _old_box_free(sampler, grasp)  # the corridor test before: called free
    assert sampler.corridor_blockers(grasp) == ['P0', 'P1']
    assert not sampler.poses_free([grasp])  # the fingers at the grasp itself hit them


def test_corridor_wider_than_the_hand_is_free(hand, make_scenario, make_cylinder):
    # Surfaces 0.125 m from the axis: the open fingers (0.104 m) + the corridor's margin to
    # movable bodies (15 mm: STPIK's 25 mm activation less its 10 mm tolerance, #29) pass.
    posts = [make_cylinder(f'P{i}', 0.62, s * 0.155) for i, s in enumerate((-1, 1))]
    sampler = _sampler(hand, make_scenario, *posts)
    grasp = _grasp(0.65, 0.0, 0.07)
    assert sampler.corridor_blockers(grasp) == []
    assert sampler.poses_free([grasp])


def test_palm_behind_the_fingers_is_narrower(hand, make_scenario, make_cylinder):
    # 0.2 m behind the grasp only the palm and the wrist link (≤ 0.054 m) pass: posts at ±0.10
    # (surfaces 0.07 m from the axis) are clear there, but would block the fingers.
    posts = [make_cylinder(f'P{i}', 0.45, s * 0.10) for i, s in enumerate((-1, 1))]
    sampler = _sampler(hand, make_scenario, *posts)
    assert sampler.corridor_blockers(_grasp(0.65, 0.0, 0.07)) == []
    assert sampler.corridor_blockers(_grasp(0.50, 0.0, 0.07)) == ['P0', 'P1']


def test_short_object_with_a_free_approach_is_graspable(make_scenario, make_cylinder, robot):
    short = make_cylinder('T', 0.65, 0.0, 'target', h=0.08)  # the generator's shortest
    result = MotionPlanner(make_scenario(short), model=robot).check('T', [])
    assert result.feasible, result.message


def test_occluded_object_is_no_cartesian_path_naming_the_blockers(
    make_scenario, make_cylinder, robot
):
    # Posts 0.16 m apart just in front of the target on every approach yaw tried: the old
    # corridor passed between them and STPIK found the collision; now the sampler says why.
    target = make_cylinder('T', 0.65, 0.0, 'target')
    posts = [make_cylinder(f'P{i}', 0.60, s * 0.11) for i, s in enumerate((-1, 1))]
    config = PlannerConfig(approach_directions=1)
    result = MotionPlanner(make_scenario(target, *posts), config, model=robot).check('T', [])
    assert not result.feasible and result.reason == Reason.NO_CARTESIAN_PATH
    assert 'blocked by P0, P1' in result.message


def test_grasp_keeps_the_palm_off_a_deep_box(hand, make_scenario, robot):
    """A box 8 cm deep along the approach: the EE stops short of its axis (it reached it)."""
    box = ObjectSpec('T', 'target', 'box', (0.55, 0.1, 0.05), yaw=0.4, size=(0.06, 0.08, 0.10))
    planner = MotionPlanner(make_scenario(box), model=robot)
    yaw = -0.22
    room = planner.geometry._palm_room(box, yaw)
    assert room < -0.01
    can = ObjectSpec('c', 'obstacle', 'cylinder', (0, 0, 0), 0.0, 0.03, 0.1)
    assert planner.geometry._palm_room(can, 0) > 0
    sampler = _sampler(hand, make_scenario, box)
    palm = ProbeSet(
        {'palm': hand.at_pose['j2s7s300_link_7']},
        {'palm': hand.at_pose_spheres['j2s7s300_link_7']},
    )
    axis = grasp_rotation(yaw)[:, 2]
    at_axis = _grasp(0.55, 0.1, 0.07, yaw)
    backed = pin.SE3(at_axis.rotation, at_axis.translation + room * axis)
    assert sampler._hits(palm, at_axis) == ['T']  # the EE on the axis: palm inside the box
    assert sampler._hits(palm, backed) == []


def test_grasp_height_constants_bound_the_hand(hand):
    """The grasp height keeps the real hand (|y| ≤ 0.047 m, EE y up) off the table."""
    from stpik_motion_planner.geometric_planner import HAND_BELOW_EE_M, HAND_HALF_HEIGHT_M

    lowest = max(float(np.max(np.abs(p[:, 1]))) for p in hand.parts.values())
    assert lowest <= HAND_HALF_HEIGHT_M <= HAND_BELOW_EE_M


def test_grasp_width_is_the_width_across_the_fingers_at_the_approach():
    """#30: a 60 x 140 mm box was graspable by its narrow side at any approach yaw."""
    import math

    from stpik_motion_planner.hand_model import grasp_width

    box = ObjectSpec('B', 'obstacle', 'box', (0.6, 0.0, 0.07), size=(0.06, 0.14, 0.14))
    assert grasp_width(box, 0.0) == pytest.approx(0.14)  # approach along x: fingers along y
    assert grasp_width(box, math.pi / 2) == pytest.approx(0.06)
    turned = ObjectSpec('B', 'obstacle', 'box', (0.6, 0.0, 0.07), yaw=math.pi / 4,
                        size=(0.06, 0.06, 0.14))  # fmt: skip
    assert grasp_width(turned, 0.0) == pytest.approx(0.06 * math.sqrt(2))  # across the diagonal
    can = ObjectSpec('C', 'obstacle', 'cylinder', (0.6, 0.0, 0.07), radius=0.03, height=0.12)
    assert grasp_width(can, 1.234) == pytest.approx(0.06)


def test_a_box_turned_45_degrees_is_not_grasped_across_its_diagonal(make_scenario, robot):
    """#30: a 70 mm square box turned 45° is 99 mm across the fingers of every approach facing
    away from the base (within 0.45 rad of it): wider than the 82 mm the hand closes on, though
    its side (70 mm) fits. The planner answered feasible before."""
    import math

    box = ObjectSpec('T', 'target', 'box', (0.6, 0.0, 0.07), yaw=math.pi / 4,
                     size=(0.07, 0.07, 0.14))  # fmt: skip
    planner = MotionPlanner(make_scenario(box), model=robot)
    near = [y for y in (0.0, 0.2, -0.2, 0.4, -0.4)]
    result = planner.plan('T', [], yaws=near)
    assert not result.feasible and result.reason == Reason.OBJECT_TOO_BIG, result.message
    assert 'across the fingers' in result.message
    square = planner.plan('T', [], yaws=[math.pi / 4])  # across its side: 70 mm
    assert square.reason != Reason.OBJECT_TOO_BIG
