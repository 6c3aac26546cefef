"""Scene differences (#32): moved, added, removed, reshaped; tolerances; in-clutter filter."""

from __future__ import annotations

import dataclasses
import math

from qtree_scene.changes import (
    changed_ids,
    changes_under_relocation,
    clutter_objects,
    scene_changes,
    standing_objects,
)
from qtree_scene.message import scene_msg
from qtree_scene.scenario import load_scenario


def objects() -> dict:
    return {o.id: o for o in load_scenario('s1').objects}


def test_an_unchanged_scene_has_no_change() -> None:
    assert scene_changes(objects(), objects()) == []


def test_moves_below_the_tolerance_and_cylinder_yaws_are_no_change() -> None:
    after = objects()
    o1 = after['O1']
    after['O1'] = dataclasses.replace(o1, position=(o1.position[0] + 5e-4, *o1.position[1:]))
    after['O2'] = dataclasses.replace(after['O2'], yaw=1.0)
    assert scene_changes(objects(), after) == []


def test_each_kind_of_change_is_named() -> None:
    before, after = objects(), objects()
    o5 = after['O5']
    after['O5'] = dataclasses.replace(o5, position=(0.7, 0.0, o5.position[2]))
    del after['O4']
    after['O2'] = dataclasses.replace(after['O2'], radius=0.04)
    after['X1'] = dataclasses.replace(o5, id='X1')
    changes = scene_changes(before, after)
    assert changes == [
        "'O2' changed shape or role",
        "'O4' removed",
        f"'O5' moved {math.dist(o5.position[:2], (0.7, 0.0)):.3f} m",
        "'X1' added",
    ]
    assert changed_ids(changes) == ['O2', 'O4', 'O5', 'X1']


def test_clutter_objects_leave_out_relocated_grasped_and_ignored_ones() -> None:
    scenario = load_scenario('s1')
    msg = scene_msg(scenario, statuses={'O1': 'relocated', 'O2': 'grasped'})
    ids = set(clutter_objects(msg, ignore={'O3'}))
    assert ids == {o.id for o in scenario.objects} - {'O1', 'O2', 'O3'}


def test_the_object_being_relocated_is_watched_until_it_leaves_the_clutter() -> None:
    """A target moved under its own approach is a change (it was ignored before: the hand went
    on to a grasp where the target no longer was); once grasped (not in the clutter) it is not."""
    before, after = objects(), objects()
    t = after['T']
    after['T'] = dataclasses.replace(t, position=(0.8, -0.1, t.position[2]))
    assert changes_under_relocation(before, after, 'T') == ["'T' moved 0.100 m"]
    del after['T']  # grasped: carried from here on
    assert changes_under_relocation(before, after, 'T') == []
    del after['O4']  # any other object still counts
    assert changes_under_relocation(before, after, 'T') == ["'O4' removed"]


def test_the_object_being_relocated_gone_from_the_scene_is_removed() -> None:
    """Grasped, the object is out of the clutter but still in the scene (no change); gone from
    the message altogether it was removed (before, both read as grasped and the hand went on to
    an empty grasp)."""
    before, after = objects(), objects()
    del after['T']
    assert changes_under_relocation(before, after, 'T', in_scene=True) == []
    assert changes_under_relocation(before, after, 'T', in_scene=False) == ["'T' removed"]


def test_standing_objects_hold_the_placed_ones_but_not_the_moving_one() -> None:
    """#29 point 5: the closed loop's live scene left out objects already placed on their drop
    slots; they stand there and must be cleared. The object being moved is never in it."""
    scenario = load_scenario('s1')
    msg = scene_msg(scenario, statuses={'O1': 'relocated', 'O2': 'grasped', 'O3': 'relocated'})
    ids = set(standing_objects(msg, moving='O2', left_out={'O3', 'O4'}))
    assert 'O1' in ids and 'O3' in ids  # placed: standing on their slots
    assert 'O2' not in ids and 'O4' not in ids  # moving; left out while in the clutter
    assert ids == {o.id for o in scenario.objects} - {'O2', 'O4'}
