"""Scene events of the simulator (#32): parsing with named fields, firing, grasp failures."""

from __future__ import annotations

import json

import numpy as np
import pytest
from jaco2_sim.exceptions import SceneEventError, WorldError
from jaco2_sim.scene_events import SceneEvents, parse_events
from jaco2_sim.simulation import Simulation
from qtree_scene.scenario import load_scenario

RATE_HZ = 100.0


@pytest.fixture(scope='module')
def s1():
    return load_scenario('s1')


def events(entries: list[dict], scenario) -> tuple:
    return parse_events(json.dumps(entries), scenario)


def test_empty_text_is_no_event(s1) -> None:
    assert parse_events('', s1) == ()
    assert parse_events('  \n', s1) == ()


def test_every_kind_parses_with_its_trigger(s1) -> None:
    parsed = events(
        [
            {'kind': 'move', 'object': 'O4', 'xy': [0.45, -0.3], 'at_s': 1.5},
            {
                'kind': 'add',
                'object': 'X1',
                'radius': 0.03,
                'height': 0.1,
                'xy': [0.4, -0.4],
                'hand_within_m': 0.2,
                'of': 'T',
            },
            {'kind': 'remove', 'object': 'O5', 'at_s': 0},
            {'kind': 'grasp_failure', 'object': 'O1', 'attempt': 2},
        ],
        s1,
    )
    move, add, remove, grasp = parsed
    assert (move.kind, move.object_id, move.xy, move.at_s) == ('move', 'O4', (0.45, -0.3), 1.5)
    assert add.spec.position == pytest.approx((0.4, -0.4, 0.05))
    assert (add.hand_within_m, add.near) == (0.2, 'T')
    assert remove.at_s == 0.0
    assert (grasp.attempt, grasp.at_s, grasp.hand_within_m) == (2, None, None)
    # YAML works as well as JSON
    yaml_text = '- {kind: remove, object: O5, hand_within_m: 0.1}'
    assert parse_events(yaml_text, s1)[0].near == 'O5'


@pytest.mark.parametrize(
    ('entry', 'field'),
    [
        ({'kind': 'teleport', 'object': 'O1', 'at_s': 1}, 'scene_events[0].kind'),
        ({'kind': 'move', 'object': 'nope', 'xy': [0.5, 0.3], 'at_s': 1}, '[0].object'),
        ({'kind': 'move', 'object': 'table', 'xy': [0.5, 0.3], 'at_s': 1}, '[0].object'),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.5], 'at_s': 1}, '[0].xy'),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.5, float('nan')], 'at_s': 1}, '[0].xy'),
        ({'kind': 'move', 'object': 'O1', 'xy': [10**400, 0.3], 'at_s': 1}, '[0].xy'),
        ({'kind': 'move', 'object': 'O1', 'at_s': 1}, '[0].xy'),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.5, 0.3]}, '[0].at_s'),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.5, 0.3], 'at_s': -1}, '[0].at_s'),
        (
            {'kind': 'move', 'object': 'O1', 'xy': [0.5, 0.3], 'at_s': 1, 'hand_within_m': 1},
            '[0].at_s',
        ),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.5, 0.3], 'hand_within_m': 0}, 'hand_within'),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.5, 0.3], 'at_s': 1, 'colour': 1}, '.colour'),
        ({'kind': 'move', 'object': 'O1', 'xy': [0.8, 0.0], 'at_s': 1}, '[0].xy'),  # on T
        ({'kind': 'move', 'object': 'O1', 'xy': [3.0, 0.0], 'at_s': 1}, '[0].xy'),  # off table
        (
            {
                'kind': 'add',
                'object': 'O1',
                'radius': 0.03,
                'height': 0.1,
                'xy': [0.4, -0.4],
                'at_s': 1,
            },
            '[0].object',
        ),
        (
            {
                'kind': 'add',
                'object': 'X',
                'radius': -0.03,
                'height': 0.1,
                'xy': [0.4, -0.4],
                'at_s': 1,
            },
            '[0].radius',
        ),
        (
            {'kind': 'add', 'object': 'X', 'shape': 'cone', 'xy': [0.4, -0.4], 'at_s': 1},
            '[0].shape',
        ),
        ({'kind': 'grasp_failure', 'object': 'O1', 'attempt': 0}, '[0].attempt'),
        ({'kind': 'grasp_failure', 'object': 'O1', 'at_s': 1}, '[0].at_s'),
    ],
)
def test_a_bad_value_is_refused_naming_its_field(s1, entry: dict, field: str) -> None:
    with pytest.raises(SceneEventError, match=field.replace('[', r'\[').replace(']', r'\]')):
        events([entry], s1)


def test_not_a_list_and_not_yaml_are_refused(s1) -> None:
    with pytest.raises(SceneEventError, match='scene_events: a list'):
        parse_events('{kind: move}', s1)
    with pytest.raises(SceneEventError, match='scene_events: not YAML'):
        parse_events('[{kind: move', s1)


def test_later_events_are_checked_against_the_scene_the_earlier_ones_leave(s1) -> None:
    free = {'kind': 'move', 'object': 'O4', 'xy': [0.45, -0.3], 'at_s': 1}
    onto_the_old_place = {
        'kind': 'move',
        'object': 'O5',
        'xy': list(s1.object('O4').position[:2]),
        'at_s': 2,
    }
    assert len(events([free, onto_the_old_place], s1)) == 2
    with pytest.raises(SceneEventError, match=r'scene_events\[0\]'):
        events([onto_the_old_place], s1)  # O4 still stands there
    removed = {'kind': 'remove', 'object': 'O4', 'at_s': 1}
    with pytest.raises(SceneEventError, match=r'scene_events\[1\].object'):
        events([removed, {**free, 'at_s': 2}], s1)


def test_time_and_hand_triggers_fire_once() -> None:
    scenario = load_scenario('s1')
    armed = SceneEvents(
        events(
            [
                {'kind': 'remove', 'object': 'O5', 'at_s': 1.0},
                {'kind': 'remove', 'object': 'O4', 'hand_within_m': 0.1},
            ],
            scenario,
        )
    )
    armed.arm(10.0)
    centre = lambda _id: np.array([0.5, 0.3, 0.07])  # noqa: E731
    far, near = np.array([0.0, 0.0, 0.5]), np.array([0.5, 0.35, 0.07])
    assert armed.due(10.5, far, centre) == []
    assert [e.object_id for e in armed.due(11.0, far, centre)] == ['O5']
    assert armed.due(12.0, far, centre) == []
    assert armed.watches_hand
    assert [e.object_id for e in armed.due(12.0, near, centre)] == ['O4']
    assert not armed.watches_hand
    assert armed.due(13.0, near, centre) == []
    armed.arm(20.0)  # re-armed: both again
    assert len(armed.due(21.0, near, centre)) == 2


def scene_ids(sim: Simulation) -> set[str]:
    return set(sim.world.objects)


def run(sim: Simulation, seconds: float) -> None:
    for _ in range(round(seconds * RATE_HZ)):
        sim.step()


def test_the_simulation_moves_adds_and_removes_objects_on_time() -> None:
    sim = Simulation('s1', RATE_HZ, 0.2)
    text = json.dumps(
        [
            {'kind': 'move', 'object': 'O4', 'xy': [0.45, -0.3], 'yaw': 0.5, 'at_s': 0.2},
            {
                'kind': 'add',
                'object': 'X1',
                'shape': 'box',
                'size': [0.05, 0.05, 0.1],
                'xy': [0.4, -0.45],
                'at_s': 0.3,
            },
            {'kind': 'remove', 'object': 'O5', 'at_s': 0.4},
        ]
    )
    sim.check_parameter('scene_events', text, {})
    sim.configure_events(text)
    version = sim.world.version
    run(sim, 0.1)
    assert sim.world.version == version and not sim.event_log
    run(sim, 0.15)
    np.testing.assert_allclose(sim.world.state('O4').pose.translation, [0.45, -0.3, 0.07])
    run(sim, 0.3)
    assert 'X1' in scene_ids(sim) and 'O5' not in scene_ids(sim)
    assert [o.id for o in sim.world.scenario.objects][-1] == 'X1'
    assert sim.world.state('X1').pose.translation[2] == pytest.approx(0.05)
    assert len(sim.event_log) == 3 and 'move' in sim.event_log[0]
    sim.reset_scene('')  # back to the scenario; the events are re-armed
    assert 'O5' in scene_ids(sim) and 'X1' not in scene_ids(sim)
    run(sim, 0.5)
    assert 'X1' in scene_ids(sim)


def test_an_event_on_an_object_no_longer_in_the_clutter_is_skipped() -> None:
    sim = Simulation('s1', RATE_HZ, 0.2)
    sim.configure_events(
        json.dumps([{'kind': 'move', 'object': 'O4', 'xy': [0.45, -0.3], 'at_s': 0.05}])
    )
    sim.grasp('O4', True, 0)
    run(sim, 0.1)
    assert 'skipped' in sim.event_log[-1] and 'grasped' in sim.event_log[-1]


def test_the_hand_trigger_uses_the_end_effector() -> None:
    sim = Simulation('s1', RATE_HZ, 0.2)
    hand = sim.robot.ee_pose(sim.sim.q).translation
    distance = float(np.linalg.norm(hand - np.array(sim.scenario.object('O4').position)))
    entry = {'kind': 'remove', 'object': 'O4'}
    sim.configure_events(json.dumps([{**entry, 'hand_within_m': distance - 0.01}]))
    run(sim, 0.05)
    assert 'O4' in scene_ids(sim)
    sim.configure_events(json.dumps([{**entry, 'hand_within_m': distance + 0.01}]))
    run(sim, 0.05)
    assert 'O4' not in scene_ids(sim)


def test_a_grasp_failure_refuses_the_given_attempt_only() -> None:
    sim = Simulation('s1', RATE_HZ, 0.2)
    sim.configure_events(json.dumps([{'kind': 'grasp_failure', 'object': 'O1', 'attempt': 2}]))
    sim.grasp('O1', True, 0)  # attempt 1 succeeds
    sim.grasp('O1', False, 0)  # released in the clutter
    assert sim.world.state('O1').status == 'in_clutter'
    with pytest.raises(WorldError, match=r"grasp of 'O1' failed \(attempt 2, scene_events\[0\]"):
        sim.grasp('O1', True, 0)
    assert sim.world.attached_id is None
    sim.grasp('O1', True, 0)  # attempt 3
    assert sim.world.attached_id == 'O1'


def test_the_parameter_check_refuses_with_the_field(s1) -> None:
    sim = Simulation('s1', RATE_HZ, 0.2)
    bad = json.dumps([{'kind': 'move', 'object': 'O1', 'xy': [0.8, 0.0], 'at_s': 1}])
    with pytest.raises(SceneEventError, match=r"scene_events\[0\].xy: 'O1' overlaps 'T'"):
        sim.check_parameter('scene_events', bad, {})


def test_events_can_be_set_while_the_target_is_held() -> None:
    sim = Simulation('s1', RATE_HZ, 0.2)
    sim.grasp('T', True, 0)  # the target is out of the clutter
    text = json.dumps([{'kind': 'move', 'object': 'O4', 'xy': [0.45, -0.3], 'at_s': 0.0}])
    sim.check_parameter('scene_events', text, {})
    sim.configure_events(text)
    run(sim, 0.05)
    assert sim.event_log and 'move' in sim.event_log[-1], sim.event_log
