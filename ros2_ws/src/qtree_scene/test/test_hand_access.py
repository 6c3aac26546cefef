"""The 2-D swept-hand model: approach order, what blocks an approach and what does not."""

from __future__ import annotations

import math

import pytest
from qtree_scene.footprint import Footprint
from qtree_scene.hand_access import (
    APPROACH_DIRECTIONS,
    HAND_REACH_M,
    approach_yaws,
    blocked_yaws,
    free_yaws,
    swept_hand,
)

TARGET = (0.55, 0.0)  # on the x axis: the radial approach has yaw 0 [m]


def test_yaws_start_radial_then_alternate() -> None:
    yaws = approach_yaws((0.5, 0.5))
    assert len(yaws) == APPROACH_DIRECTIONS
    assert yaws[:3] == pytest.approx([math.pi / 4, math.pi / 4 + 0.2, math.pi / 4 - 0.2])
    assert max(yaws) - min(yaws) == pytest.approx(3.2)


def test_an_object_in_front_blocks_the_radial_approach_only() -> None:
    front = Footprint((0.40, 0.0), radius=0.03)  # between the base and the target
    blocked = blocked_yaws(TARGET, approach_yaws(TARGET), front)
    assert 0.0 in blocked
    assert 1.6 not in blocked and -1.6 not in blocked  # approaches from the side pass it
    assert len(free_yaws(TARGET, [front])) == APPROACH_DIRECTIONS - len(blocked)


def test_an_object_behind_the_fingertips_blocks_nothing_radial() -> None:
    # Fingertips end 0.024 m beyond the object axis, grown by the 0.01 m margin.
    behind = Footprint((0.55 + 0.034 + 0.001 + 0.03, 0.0), radius=0.03)
    assert 0.0 not in blocked_yaws(TARGET, [0.0], behind)
    touching = Footprint((0.55 + 0.034 - 0.001 + 0.03, 0.0), radius=0.03)
    assert 0.0 in blocked_yaws(TARGET, [0.0], touching)


def test_a_neighbour_beside_meets_the_open_fingers() -> None:
    beside = Footprint((0.55, 0.105 + 0.01 + 0.025), radius=0.03)  # 5 mm inside the margin
    assert 0.0 in blocked_yaws(TARGET, [0.0], beside)
    clear = Footprint((0.55, 0.105 + 0.01 + 0.035), radius=0.03)
    assert 0.0 not in blocked_yaws(TARGET, [0.0], clear)


def test_nothing_beyond_the_hand_reach_is_tested() -> None:
    far = Footprint((0.55 + HAND_REACH_M + 0.031, 0.0), radius=0.03)
    assert blocked_yaws(TARGET, approach_yaws(TARGET), far) == set()
    for yaw in approach_yaws(TARGET):
        for part in swept_hand(TARGET, yaw):
            corners = part.corners()
            assert max(math.dist(TARGET, c) for c in corners) <= HAND_REACH_M + 1e-9


def test_surrounded_object_has_no_free_approach() -> None:
    ring = [
        Footprint((0.55 + 0.08 * math.cos(a), 0.08 * math.sin(a)), radius=0.03)
        for a in [k * math.pi / 4 for k in range(8)]
    ]
    assert free_yaws(TARGET, ring) == []
