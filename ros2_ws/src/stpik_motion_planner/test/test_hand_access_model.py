"""The generator's 2-D swept hand (qtree_scene.hand_access) covers the planner's swept hand.

The accessible layout of ``generate_clutter`` promises a free approach where this 2-D model finds
one; it may only be more cautious than the planner's corridor test, never less: each part of the
planner's hand (URDF hulls, :class:`HandModel`), at the grasp and at the pre-grasp, must lie in
one of the 2-D rectangles, and the yaws and standoff must be the planner's.
"""

from __future__ import annotations

import numpy as np
import pytest
from qtree_scene import hand_access
from stpik_motion_planner.cartesian_path import approach_yaws
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.hand_model import HandModel


def test_yaws_and_standoff_are_the_planners() -> None:
    c = PlannerConfig()
    assert c.pregrasp_standoff_m == hand_access.STANDOFF_M
    assert c.approach_directions == hand_access.APPROACH_DIRECTIONS
    assert c.approach_yaw_step_rad == hand_access.YAW_STEP_RAD
    centre = np.array([0.5, -0.2, 0.1])
    expected = approach_yaws(centre, c.approach_directions, c.approach_yaw_step_rad)
    assert hand_access.approach_yaws(centre[:2]) == pytest.approx(expected)


def test_every_hand_part_lies_in_a_2d_rectangle(robot) -> None:
    hand = HandModel(robot, hand_access.STANDOFF_M)
    assert len(hand.parts) >= 8  # palm, six finger links, wrist
    back = np.array([0.0, 0.0, -hand_access.STANDOFF_M])
    for name, points in hand.parts.items():
        swept = np.vstack([points, points + back])  # grasp and pre-grasp ends (EE frame)
        across, along = np.abs(swept[:, 0]), swept[:, 2]  # EE x across, EE z = approach [m]
        inside = [
            bool(
                across.max() <= half_width
                and along.min() >= rear - hand_access.STANDOFF_M
                and along.max() <= front
            )
            for half_width, rear, front in hand_access.HAND_PARTS_M
        ]
        assert any(inside), f'{name} sticks out of the 2-D hand model'
