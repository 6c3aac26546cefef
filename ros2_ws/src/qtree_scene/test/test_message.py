"""Scene messages ↔ scene types (qtree_scene.message, both directions): round trips, bad input."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_msgs.msg import ObjectState
from qtree_scene import message as scene_message
from qtree_scene.exceptions import ScenarioError
from qtree_scene.generator import generate_clutter
from qtree_scene.message import MAX_OBJECTS, parse_scene_msg, scenario_from_msg, scene_msg
from qtree_scene.scenario import load_scenario, parse_scenario, scenario_to_dict
from shape_msgs.msg import SolidPrimitive


def _same_objects(a: Any, b: Any) -> None:
    assert [o.id for o in a.objects] == [o.id for o in b.objects]
    for x, y in zip(a.objects, b.objects, strict=True):
        assert (x.role, x.shape) == (y.role, y.shape)
        assert x.position == pytest.approx(y.position, abs=1e-12)
        assert math.remainder(x.yaw - y.yaw, math.tau) == pytest.approx(0.0, abs=1e-12)
        assert (x.radius, x.height) == pytest.approx((y.radius, y.height))
        assert x.size == pytest.approx(y.size)
    assert a.drop_zone_center == pytest.approx(b.drop_zone_center)
    assert a.drop_zone_size == pytest.approx(b.drop_zone_size)


def test_constants_match_the_messages() -> None:
    assert scene_message.PRIMITIVE_BOX == SolidPrimitive.BOX
    assert scene_message.PRIMITIVE_CYLINDER == SolidPrimitive.CYLINDER
    assert SolidPrimitive.CYLINDER_HEIGHT == 0 and SolidPrimitive.CYLINDER_RADIUS == 1
    assert scene_message.ROLE_CODES == {
        'target': ObjectState.ROLE_TARGET,
        'obstacle': ObjectState.ROLE_OBSTACLE,
        'static': ObjectState.ROLE_STATIC,
    }
    assert scene_message.STATUS_CODES == {
        'in_clutter': ObjectState.STATUS_IN_CLUTTER,
        'grasped': ObjectState.STATUS_GRASPED,
        'relocated': ObjectState.STATUS_RELOCATED,
    }


@pytest.mark.parametrize('name', ['s1', 's2', 's3'])
def test_scenario_files_round_trip(name: str) -> None:
    scenario = load_scenario(name)
    msg = scene_msg(scenario)
    table = next(o for o in msg.objects if o.id == 'table')
    assert table.shape.type == SolidPrimitive.BOX and table.role == ObjectState.ROLE_STATIC
    target = next(o for o in msg.objects if o.role == ObjectState.ROLE_TARGET)
    assert target.shape.type == SolidPrimitive.CYLINDER
    assert list(target.shape.dimensions) == [scenario.target.height, scenario.target.radius]
    parsed = parse_scene_msg(msg)
    _same_objects(parsed, scenario)
    assert parsed.name == scenario.name


@settings(max_examples=25, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(n=st.integers(0, 20), seed=st.integers(0, 10_000), yaw=st.floats(-3.1, 3.1))
def test_generated_scenes_round_trip(n: int, seed: int, yaw: float) -> None:
    data = scenario_to_dict(generate_clutter(n, 0.1, seed))
    data['objects'].append(
        {'id': 'B', 'role': 'static', 'shape': 'box', 'xy': [0.0, -0.5], 'size': [0.1, 0.05, 0.2],
         'yaw': yaw}
    )  # fmt: skip
    scenario = parse_scenario(data)
    _same_objects(parse_scene_msg(scene_msg(scenario)), scenario)


def test_relocated_objects_keep_their_clutter_pose() -> None:
    scenario = load_scenario('s1')
    moved = scenario.obstacles[0]
    msg = scene_msg(
        scenario,
        poses={moved.id: ((0.0, 0.5, 0.3), (0, 0, 0, 1))},
        statuses={moved.id: 'relocated'},
    )
    original = {o.id: o for o in scenario.objects}
    _same_objects(scenario_from_msg(msg, original=original), scenario)
    assert scenario_from_msg(msg).object(moved.id).position == (0.0, 0.5, 0.3)  # first seen


def _s1(edit: Callable[[Any], Any]) -> Any:
    msg = scene_msg(load_scenario('s1'))
    edit(msg)
    return msg


def _obj(msg: Any, object_id: str) -> Any:
    return next(o for o in msg.objects if o.id == object_id)


def _set(path: str, value: Any, object_id: str = 'O1') -> Callable[[Any], None]:
    def edit(msg: Any) -> None:
        *parents, leaf = path.split('.')
        target = _obj(msg, object_id)
        for name in parents:
            target = getattr(target, name)
        setattr(target, leaf, value)

    return edit


def _thousands(msg: Any) -> None:
    obstacle = _obj(msg, 'O1')
    for i in range(5000):
        msg.objects.append(
            ObjectState(id=f'X{i}', role=1, shape=obstacle.shape, pose=obstacle.pose)
        )


S1_INDEX = {o.id: i for i, o in enumerate(scene_msg(load_scenario('s1')).objects)}
O1 = f'objects[{S1_INDEX["O1"]}]'
BAD = [
    ('NaN pose', _set('pose.position.x', math.nan), f'{O1}.pose.position.x', "'O1'", 'finite'),
    ('inf pose', _set('pose.orientation.z', math.inf), f'{O1}.pose.orientation.z', "'O1'",
     'finite'),
    ('unknown primitive', _set('shape.type', SolidPrimitive.SPHERE), f'{O1}.shape.type', "'O1'",
     'unknown primitive type 2'),
    ('no primitive type', _set('shape.type', 0), f'{O1}.shape.type', "'O1'",
     'unknown primitive type 0'),
    ('negative radius', _set('shape.dimensions', [0.1, -0.03]), f'{O1}.shape.dimensions[1]',
     "'O1' radius", 'must be > 0, got -0.03'),
    ('zero box edge', _set('shape.dimensions', [1.2, 0.0, 0.05], 'table'),
     f'objects[{S1_INDEX["table"]}].shape.dimensions[1]', "'table' y", 'must be > 0'),
    ('3 cylinder dimensions', _set('shape.dimensions', [0.1, 0.03, 0.1]), f'{O1}.shape.dimensions',
     "'O1'", 'needs 2 dimensions'),
    ('duplicate ids', _set('id', 'O2'), f'objects[{S1_INDEX["O2"]}].id', "'O2'",
     f'duplicate id \'O2\' (also {O1})'),
    ('no target', _set('role', ObjectState.ROLE_OBSTACLE, 'T'), 'objects', '',
     'exactly one object must have role target, found 0'),
    ('two targets', _set('role', ObjectState.ROLE_TARGET), 'objects', '', 'found 2'),
    ('unknown role', _set('role', 7), f'{O1}.role', "'O1'", 'unknown role 7'),
    ('unknown status', _set('status', 9), f'{O1}.status', "'O1'", 'unknown status 9'),
    ('relocated status', _set('status', ObjectState.STATUS_RELOCATED), f'{O1}.status', "'O1'",
     'STATUS_IN_CLUTTER'),
    ('empty id', _set('id', ' '), f'{O1}.id', '', 'non-empty string'),
    ('huge id', _set('id', 'x' * 10_000), f'{O1}.id', '', 'at most 256'),
    ('thousands of objects', _thousands, 'objects', '', f'at most {MAX_OBJECTS}'),
]  # fmt: skip


def _tilt(msg: Any) -> None:
    q = _obj(msg, 'O1').pose.orientation
    q.x, q.y, q.z, q.w = math.sin(0.1), 0.0, 0.0, math.cos(0.1)


def _zero_quaternion(msg: Any) -> None:
    q = _obj(msg, 'O1').pose.orientation
    q.x = q.y = q.z = q.w = 0.0


def _overlap(msg: Any, moved: str = 'O1', onto: str = 'O2') -> None:
    a, b = _obj(msg, moved).pose.position, _obj(msg, onto).pose.position
    a.x, a.y = b.x, b.y


def _floating(msg: Any) -> None:
    _obj(msg, 'O1').pose.position.z += 0.2


def _frame(msg: Any) -> None:
    msg.header.frame_id = 'camera'


def _no_table(msg: Any) -> None:
    msg.objects = [o for o in msg.objects if o.id != 'table']


def _attached(msg: Any) -> None:
    msg.attached_id = 'O1'


def _rotated_base(msg: Any) -> None:
    msg.robot_base.position.x = 0.1


def _negative_zone(msg: Any) -> None:
    msg.drop_zone_size.y = -0.3


BAD += [
    ('tilted object', _tilt, f'{O1}.pose.orientation', "'O1'", 'tilted 0.200 rad'),
    ('zero quaternion', _zero_quaternion, f'{O1}.pose.orientation', "'O1'", 'unit quaternion'),
    ('overlap', _overlap, f'objects[{S1_INDEX["O2"]}].pose.position', "'O2' overlaps 'O1'", ''),
    ('floating', _floating, f'{O1}.pose.position.z', "'O1'", 'stand on the table top'),
    ('another frame', _frame, 'header.frame_id', '', "got 'camera'"),
    ('no table', _no_table, 'objects', "'table'", 'STATIC box'),
    ('attached', _attached, 'attached_id', '', 'must be empty'),
    ('moved base', _rotated_base, 'robot_base.position', '', 'robot base frame'),
    ('negative drop zone', _negative_zone, 'drop_zone_size.y', '', 'must be > 0'),
]


@pytest.mark.parametrize(
    ('edit', 'field', 'names', 'problem'), [b[1:] for b in BAD], ids=[b[0] for b in BAD]
)
def test_bad_scene_is_rejected_naming_object_and_field(
    edit: Callable[[Any], None], field: str, names: str, problem: str
) -> None:
    with pytest.raises(ScenarioError) as info:
        parse_scene_msg(_s1(edit))
    err = info.value
    assert str(err).startswith('SetScene: ')
    assert err.field == field, str(err)
    assert names in err.problem and problem in err.problem, str(err)
    assert len(str(err)) < 300


def test_same_messages_as_the_yaml_validator() -> None:
    """Geometry rules come from validate_scenario: the problem text is the YAML file's."""
    data = scenario_to_dict(load_scenario('s1'))
    data['objects'][1]['xy'] = data['objects'][2]['xy']
    with pytest.raises(ScenarioError) as from_yaml:
        parse_scenario(data)
    scenario_index = {o['id']: i for i, o in enumerate(data['objects'])}
    assert scenario_index == {k: v for k, v in S1_INDEX.items() if k != 'table'}
    ids = [o['id'] for o in data['objects'][1:3]]
    with pytest.raises(ScenarioError) as from_msg:
        parse_scene_msg(_s1(lambda m: _overlap(m, *ids)))
    assert from_msg.value.problem == from_yaml.value.problem
    assert from_yaml.value.field.endswith('.xy') and from_msg.value.field.endswith(
        '.pose.position'
    )


def test_lenient_reader_accepts_what_the_simulator_publishes_mid_run() -> None:
    scenario = load_scenario('s2')
    moved = scenario.obstacles[0].id
    msg = scene_msg(
        scenario,
        poses={moved: ((0.0, 0.5, 0.3), (0.1, 0.0, 0.0, math.sqrt(0.99)))},  # carried, tilted
        statuses={moved: 'grasped'},
        attached_id=moved,
    )
    assert scenario_from_msg(msg).object(moved).position == (0.0, 0.5, 0.3)
    with pytest.raises(ScenarioError, match=r'STATUS_IN_CLUTTER|must be empty'):
        parse_scene_msg(msg)
