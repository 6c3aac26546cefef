"""Packed household layouts of the generator (#30 item 3)."""

from __future__ import annotations

import math

import pytest
from qtree_scene.exceptions import ScenarioError
from qtree_scene.footprint import footprint_of
from qtree_scene.generator import generate_clutter
from qtree_scene.household import HOUSEHOLD
from qtree_scene.layouts import overlaps_any
from qtree_scene.packed_layouts import CLUTTER_REACH_M, PACKED_LAYOUTS, TARGET_REACH_M


def _gap(fp, others) -> float:
    low, high = 0.0, 0.1
    for _ in range(16):
        middle = (low + high) / 2
        low, high = (low, middle) if overlaps_any(fp, others, middle) else (middle, high)
    return low


@pytest.mark.parametrize('layout', PACKED_LAYOUTS)
@pytest.mark.parametrize('n', [6, 10])
def test_packed_scenes_are_packed_household_clutter_around_a_reachable_target(layout, n):
    for seed in range(2):
        scene = generate_clutter(n, 0.2, seed, layout=layout)
        assert scene == generate_clutter(n, 0.2, seed, layout=layout)  # deterministic
        movable = [o for o in scene.objects if o.role != 'static']
        assert len(movable) == n + 1 and scene.name == f'{layout}_{n}_{seed}'
        fps = [footprint_of(o) for o in movable]
        gaps = [_gap(f, fps[:i] + fps[i + 1 :]) for i, f in enumerate(fps)]
        assert min(gaps) >= 0.0099  # never closer than 1 cm
        assert gaps[-1] <= 0.027  # the target (last) has a neighbour within 2.5 cm
        target = scene.target
        assert TARGET_REACH_M[0] <= math.hypot(*target.position[:2]) <= TARGET_REACH_M[1]
        for o in movable:
            assert CLUTTER_REACH_M[0] <= math.hypot(*o.position[:2]) <= CLUTTER_REACH_M[1]
            if o.shape == 'cylinder':
                assert any(k[0] == 'cylinder' and k[1] == o.radius for k in HOUSEHOLD.values())


def test_an_unknown_layout_names_the_field():
    with pytest.raises(ScenarioError, match='layout'):
        generate_clutter(6, 0.2, 0, layout='packed_pile')
