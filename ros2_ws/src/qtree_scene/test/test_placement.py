"""qtree_scene.placement: slots that never interfere whatever the order, envelopes of a set."""

from __future__ import annotations

import math

import numpy as np
import pytest
from qtree_scene.generator import generate_clutter
from qtree_scene.placement import (
    HAND_HALF_WIDTH_M,
    MAX_SLOTS,
    RING_MAX_M,
    RING_MIN_M,
    SNAP_RADIUS_M,
    _hand_hits,
    capacity,
    drop_slots,
    footprint_radius,
    occupied_envelopes,
    settle_pose,
    slot_position,
)
from qtree_scene.scenario import load_scenario

SCENES = ['s1', 's2', 's3']


@pytest.mark.parametrize('name', SCENES)
def test_placing_in_slot_k_never_touches_slots_before_it(name):
    scenario = load_scenario(name)
    slots = drop_slots(scenario)
    r = max(footprint_radius(o) for o in scenario.objects if o.role != 'static')
    assert len(slots) >= {'s1': 5, 's2': 6, 's3': 6}[name]  # room beyond the optimal level
    for k, slot in enumerate(slots):
        assert slot.index == k
        for earlier in slots[:k]:
            assert not _hand_hits(np.array(slot.xy), slot.yaw, np.array(earlier.xy), r)
        # Distinct slots stand at least the hand's half width + an object apart sideways or
        # one object diameter radially.
        for other in slots[:k]:
            assert math.dist(slot.xy, other.xy) > 2 * r


@pytest.mark.parametrize('name', SCENES)
def test_no_slot_hand_footprint_meets_an_object_in_the_clutter(name):
    scenario = load_scenario(name)
    table = scenario.object('table')
    for slot in drop_slots(scenario):
        for obj in scenario.objects:
            if obj.role == 'static':
                continue
            assert not _hand_hits(
                np.array(slot.xy), slot.yaw, np.array(obj.position[:2]), footprint_radius(obj)
            ), (slot, obj.id)
        assert abs(slot.xy[0] - table.position[0]) < table.size[0] / 2
        assert abs(slot.xy[1] - table.position[1]) < table.size[1] / 2


def test_slot_position_stands_on_the_table_and_bad_index_is_refused():
    scenario = load_scenario('s1')
    obj = scenario.object('O2')
    centre = slot_position(scenario, 0, obj)
    assert centre[2] == pytest.approx(obj.height / 2)
    with pytest.raises(IndexError, match='slots'):
        slot_position(scenario, len(drop_slots(scenario)), obj)


def test_envelopes_depend_on_the_set_only_and_contain_its_objects():
    scenario = load_scenario('s1')
    a = occupied_envelopes(scenario, ['O1', 'O4', 'O2'])
    b = occupied_envelopes(scenario, {'O2', 'O1', 'O4'})
    assert a == b and [e.id for e in a] == ['slot_0', 'slot_1', 'slot_2']
    tallest = max(scenario.object(i).height for i in ('O1', 'O2', 'O4'))
    for env in a:
        assert env.height >= tallest and env.radius >= 0.03
        assert env.position[2] == pytest.approx(env.height / 2)
    assert occupied_envelopes(scenario, []) == []


def test_settle_snaps_near_the_slot_only():
    scenario = load_scenario('s1')
    obj = scenario.object('O3')
    centre = slot_position(scenario, 2, obj)
    settled = settle_pose(scenario, 2, obj, centre + np.array([0.02, -0.01, 0.015]), 0.3)
    assert settled is not None
    np.testing.assert_allclose(settled[0], centre)
    far = centre + np.array([SNAP_RADIUS_M + 0.01, 0.0, 0.0])
    assert settle_pose(scenario, 2, obj, far, 0.0) is None
    assert settle_pose(scenario, 99, obj, centre, 0.0) is None


@pytest.mark.parametrize('args', [(10, 0.3, 1), (30, 0.3, 1), (30, 0.35, 3), (30, 0.1, 1)])
def test_generated_scenes_have_room_for_30_relocations(args):  # and more: no cap (#29)
    """30 distinct, non-overlapping slots in reach, clear of the clutter and of each other's hand.

    Before #13 item 2 a 30-object scene had 3-5 slots (table edge 0.25 m behind the base, every
    other ring candidate inside a neighbour's hand footprint).
    """
    scenario = generate_clutter(*args)
    slots = drop_slots(scenario)
    assert len(slots) == capacity(scenario) >= 30 and len(slots) < MAX_SLOTS
    r = max(footprint_radius(o) for o in scenario.objects if o.role != 'static')
    table = scenario.object('table')
    for k, slot in enumerate(slots):
        xy = np.array(slot.xy)
        assert RING_MIN_M - 1e-9 <= np.hypot(*xy) <= RING_MAX_M + 1e-9  # in reach
        assert abs(xy[0] - table.position[0]) + r <= table.size[0] / 2  # on the table
        assert abs(xy[1] - table.position[1]) + r <= table.size[1] / 2
        for earlier in slots[:k]:  # placing into slot k never touches an earlier slot
            assert math.dist(slot.xy, earlier.xy) > 2 * r  # distinct, not overlapping
            assert not _hand_hits(xy, slot.yaw, np.array(earlier.xy), r)
        for obj in scenario.obstacles:  # nor an object of the clutter
            gap = HAND_HALF_WIDTH_M + footprint_radius(obj)
            assert math.dist(slot.xy, obj.position[:2]) > gap
            assert not _hand_hits(xy, slot.yaw, np.array(obj.position[:2]), footprint_radius(obj))


@pytest.mark.parametrize(('name', 'before'), [('s1', 12), ('s2', 9), ('s3', 9)])
def test_ring_neighbours_stand_one_hand_width_apart(name, before):
    """Every ring candidate is usable (the chord step rejected every other one: 12/9/9 slots)."""
    slots = drop_slots(load_scenario(name))
    assert len(slots) >= before + 6
    gaps = []
    for slot in slots:
        rho = np.hypot(*slot.xy)
        same = [o for o in slots if o is not slot and abs(np.hypot(*o.xy) - rho) < 1e-6]
        gaps += [rho * abs(math.sin(math.remainder(o.yaw - slot.yaw, math.tau))) for o in same]
    assert min(gaps) < 2 * HAND_HALF_WIDTH_M  # next candidates, not every other one


def test_a_50_object_scene_holds_more_than_30_relocations():
    """#29 point 11: at most 30 slots made a 50-object scene unclearable by design."""
    from qtree_scene.generator import generate_clutter

    assert capacity(generate_clutter(50, 0.3, 1)) > 30
