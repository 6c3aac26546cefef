"""The hand constants used by the slot layout and the grasp check cover the URDF's open hand."""

from __future__ import annotations

from qtree_scene import placement
from stpik_motion_planner.hand_model import finger_opening, open_hand_box
from stpik_motion_planner.planner import HAND_OPENING_M


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
