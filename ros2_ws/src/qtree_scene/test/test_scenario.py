"""Tests of qtree_scene.scenario / generator / footprint: loading, validation, generation."""

from __future__ import annotations

import copy
import math
import re
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_scene.exceptions import ScenarioError
from qtree_scene.footprint import Footprint, overlap
from qtree_scene.generator import generate_clutter
from qtree_scene.scenario import (
    TABLE_ID,
    dump_scenario,
    list_scenarios,
    load_scenario,
    parse_scenario,
    resolve_scenario,
    validate_scenario,
)

GOOD: dict[str, Any] = {
    'name': 'tiny',
    'table': {'center_xy': [0.35, 0.0], 'size': [1.2, 1.4, 0.05]},
    'drop_zone': {'center_xy': [0.0, 0.5], 'size': [0.3, 0.3, 0.3]},
    'objects': [
        {'id': 'T', 'role': 'target', 'shape': 'cylinder', 'xy': [0.7, 0.0], 'radius': 0.03,
         'height': 0.16},
        {'id': 'O1', 'role': 'obstacle', 'shape': 'cylinder', 'xy': [0.55, 0.0], 'radius': 0.03,
         'height': 0.12},
        {'id': 'B', 'role': 'static', 'shape': 'box', 'xy': [0.6, -0.3], 'size': [0.1, 0.2, 0.3],
         'yaw': 0.3},
    ],
}  # fmt: skip


def _bad(mutate: Any) -> dict[str, Any]:
    data = copy.deepcopy(GOOD)
    mutate(data)
    return data


@pytest.mark.parametrize(('name', 'n_obstacles'), [('s1', 5), ('s2', 10), ('s3', 15)])
def test_installed_scenarios_load(name: str, n_obstacles: int) -> None:
    scenario = load_scenario(name)
    assert scenario.name == name
    assert len(scenario.obstacles) == n_obstacles
    assert scenario.movable_ids[-1] == scenario.target.id == 'T'
    table = scenario.object(TABLE_ID)
    assert table.role == 'static' and table.top_z == pytest.approx(0.0)
    # the target stands behind an obstacle straight in front of it (seen from the base)
    target_distance = math.hypot(*scenario.target.position[:2])
    assert any(
        math.hypot(*o.position[:2]) < target_distance - 0.05 and abs(o.position[1]) < 0.05
        for o in scenario.obstacles
    )
    x_min, x_max = table.position[0] - table.size[0] / 2, table.position[0] + table.size[0] / 2
    for obj in scenario.obstacles:
        assert x_min <= obj.position[0] <= x_max and abs(obj.position[1]) <= 0.6
        assert obj.position[2] == pytest.approx(obj.height / 2)
    assert abs(scenario.drop_zone_center[1]) >= 0.4
    assert scenario.source.endswith(f'{name}.yaml')


def test_list_and_resolve() -> None:
    assert {'s1', 's2', 's3'} <= set(list_scenarios())
    with pytest.raises(ScenarioError, match='no such scenario'):
        resolve_scenario('s9')


def test_parse_good_and_round_trip(tmp_path: Any) -> None:
    scenario = parse_scenario(copy.deepcopy(GOOD), source='good')
    assert scenario.object('B').position == pytest.approx((0.6, -0.3, 0.15))
    assert scenario.object('T').position == pytest.approx((0.7, 0.0, 0.08))
    assert scenario.drop_zone_center == pytest.approx((0.0, 0.5, 0.15))
    path = tmp_path / 'tiny.yaml'
    path.write_text(dump_scenario(scenario))
    assert load_scenario(str(path)) == scenario


@pytest.mark.parametrize(
    ('mutate', 'field', 'problem'),
    [
        (lambda d: d.update(colour='red'), 'colour', 'unknown key'),
        (lambda d: d['objects'][0].update(mass=1.0), r'objects\[0\].mass', 'unknown key'),
        (lambda d: d['table'].update(height=1.0), 'table.height', 'unknown key'),
        (lambda d: d.pop('drop_zone'), 'drop_zone', 'missing'),
        (lambda d: d['objects'][1].pop('xy'), r'objects\[1\].xy', 'missing'),
        (lambda d: d['objects'][0].pop('radius'), r'objects\[0\].radius', 'missing'),
        (lambda d: d['objects'][0].update(size=[1, 1, 1]), r'objects\[0\].size', 'not allowed'),
        (lambda d: d['objects'][1].update(id='T'), r'objects\[1\].id', 'duplicate'),
        (lambda d: d['objects'][1].update(id='table'), r'objects\[1\].id', 'reserved'),
        (lambda d: d['objects'][0].update(radius=math.nan), r'objects\[0\].radius', 'finite'),
        (
            lambda d: d['objects'][1]['xy'].__setitem__(0, math.inf),
            r'objects\[1\].xy\[0\]',
            'finite',
        ),
        (lambda d: d['objects'][0].update(height=0.0), r'objects\[0\].height', '> 0'),
        (
            lambda d: d['objects'][2].update(size=[0.1, -0.2, 0.3]),
            r'objects\[2\].size\[1\]',
            '> 0',
        ),
        (lambda d: d['table'].update(size=[1, 1, 0]), r'table.size\[2\]', '> 0'),
        (lambda d: d['objects'][1].update(xy=[0.68, 0.03]), r'objects\[1\].xy', 'overlaps'),
        (lambda d: d['objects'][2].update(xy=[0.7, 0.1]), r'objects\[2\].xy', 'overlaps'),
        (lambda d: d['objects'][1].update(xy=[0.1, 0.1]), r'objects\[1\]', 'keep-out'),
        (lambda d: d['objects'][1].update(xy=[0.05, 0.55]), r'objects\[1\].xy', 'drop zone'),
        (lambda d: d['objects'][1].update(xy=[2.0, 0.0]), r'objects\[1\]', 'not on the table'),
        (lambda d: d['objects'][0].update(role='obstacle'), 'objects', 'found 0'),
        (lambda d: d['objects'][1].update(role='target'), 'objects', 'found 2'),
        (lambda d: d['objects'][1].update(role='goal'), r'objects\[1\].role', 'must be'),
        (lambda d: d['objects'][1].update(shape='sphere'), r'objects\[1\].shape', 'must be'),
        (lambda d: d.update(home=[0.0] * 7), r'home\[1\]', 'joint limits'),
        (lambda d: d.update(home=[1.0] * 6), 'home', 'list of 7'),
        (lambda d: d.update(objects=[]), 'objects', 'non-empty'),
        (lambda d: d.update(name=''), 'name', 'non-empty'),
        (lambda d: d['objects'][0].update(radius='big'), r'objects\[0\].radius', 'number'),
    ],
)
def test_bad_input_rejected_with_field(mutate: Any, field: str, problem: str) -> None:
    with pytest.raises(ScenarioError, match=rf'^bad.yaml: {field}.*{problem}') as info:
        parse_scenario(_bad(mutate), source='bad.yaml')
    assert info.value.source == 'bad.yaml'


def test_bad_files(tmp_path: Any) -> None:
    path = tmp_path / 'broken.yaml'
    path.write_text('name: [unclosed\n')
    with pytest.raises(ScenarioError, match=r'broken\.yaml: cannot read YAML'):
        load_scenario(str(path))
    path.write_text('- just a list\n')
    with pytest.raises(ScenarioError, match='top level must be a mapping'):
        load_scenario(str(path))


def test_footprint_overlap_cases() -> None:
    c1 = Footprint((0.0, 0.0), radius=0.1)
    c2 = Footprint((0.25, 0.0), radius=0.1)
    assert not overlap(c1, c2) and overlap(c1, c2, gap=0.06)
    rect = Footprint((0.0, 0.0), yaw=math.pi / 4, half_size=(0.1, 0.1))
    # The rotated square reaches 0.1·√2 along x; a circle of radius 0.05 at x = 0.2 misses it.
    assert not overlap(rect, Footprint((0.2, 0.0), radius=0.05))
    assert overlap(rect, Footprint((0.18, 0.0), radius=0.05))
    assert overlap(rect, Footprint((0.25, 0.0), yaw=0.0, half_size=(0.12, 0.05)))
    assert not overlap(rect, Footprint((0.3, 0.0), yaw=0.0, half_size=(0.12, 0.05)))


@settings(max_examples=40, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(
    n=st.integers(min_value=0, max_value=20),
    density=st.floats(min_value=0.02, max_value=0.3),
    seed=st.integers(min_value=0, max_value=2**31),
)
def test_generated_scenes_validate_and_reproduce(n: int, density: float, seed: int) -> None:
    scenario = generate_clutter(n, density, seed)
    assert len(scenario.obstacles) == n
    assert scenario == generate_clutter(n, density, seed)
    # Round trip through the YAML form re-runs the whole validation.
    assert parse_scenario(yaml.safe_load(dump_scenario(scenario))) == scenario
    distances = [math.hypot(*o.position[:2]) for o in scenario.obstacles]
    assert distances == sorted(distances)
    assert [o.id for o in scenario.obstacles] == [f'O{i}' for i in range(1, n + 1)]


def test_generator_seed_changes_scene_and_bad_arguments() -> None:
    a, b = generate_clutter(10, 0.2, 1), generate_clutter(10, 0.2, 2)
    assert not np.allclose(a.target.position, b.target.position)
    with pytest.raises(ScenarioError, match='density'):
        generate_clutter(5, 0.9, 0)
    with pytest.raises(ScenarioError, match='n_objects'):
        generate_clutter(-1, 0.2, 0)


BAD_VALUES = [  # (mutation, field, problem): every type, not only the expected one, is named
    (lambda d: d['objects'][0].update(shape=['cylinder']), 'objects[0].shape',
     'expected a string, got list'),
    (lambda d: d['objects'][0].update(shape={'cylinder': 1}), 'objects[0].shape',
     'expected a string, got dict'),
    (lambda d: d['objects'][1].update(role=['obstacle']), 'objects[1].role',
     'expected a string, got list'),
    (lambda d: d['objects'][1].update(role=None), 'objects[1].role',
     'expected a string, got NoneType'),
    (lambda d: d['objects'][1].update(id=7), 'objects[1].id', 'expected a string, got int'),
    (lambda d: d.update(name={'a': 1}), 'name', 'expected a string, got dict'),
    (lambda d: d.update(description=['x']), 'description', 'expected a string, got list'),
    (lambda d: d['objects'][0].update(radius=10**400), 'objects[0].radius',
     'too large for a float'),
    (lambda d: d['objects'][2].update(yaw=-(10**400)), 'objects[2].yaw', 'too large for a float'),
    (lambda d: d.update(home=[10**400] + [0.0] * 6), 'home[0]', 'too large for a float'),
    (lambda d: d['table'].update(size=[10**400, 1, 1]), 'table.size[0]', 'too large for a float'),
    (lambda d: d.update(robot_keepout_radius=10**400), 'robot_keepout_radius',
     'too large for a float'),
    (lambda d: d['objects'][0].update(height=True), 'objects[0].height',
     'expected a number, got bool'),
    (lambda d: d['objects'][0].update(radius=[0.03]), 'objects[0].radius',
     'expected a number, got list'),
    (lambda d: d['objects'][1].update(xy={'x': 0.5}), 'objects[1].xy', 'must be a list of 2'),
    (lambda d: d.update({'': 1}), "['']", "unknown key ''"),
    (lambda d: d['objects'][0].update({'': 1}), "objects[0]['']", "unknown key ''"),
    (lambda d: d['table'].update({3: 1}), 'table[3]', 'unknown key 3'),
]  # fmt: skip


@pytest.mark.parametrize(('mutate', 'field', 'problem'), BAD_VALUES)
def test_malformed_value_of_any_type_is_named(mutate: Any, field: str, problem: str) -> None:
    with pytest.raises(ScenarioError) as info:
        parse_scenario(_bad(mutate), source='bad.yaml')
    assert (info.value.source, info.value.field) == ('bad.yaml', field)
    assert problem in info.value.problem, str(info.value)
    assert len(str(info.value)) < 300


def test_huge_values_give_short_messages() -> None:
    for value in ('x' * 100_000, list(range(100_000)), [10**5000], 10**4000):
        with pytest.raises(ScenarioError, match=r'objects\[0\].shape') as info:
            parse_scenario(_bad(lambda d, v=value: d['objects'][0].update(shape=v)))
        assert len(str(info.value)) < 200


@pytest.mark.parametrize(
    ('text', 'problem'),
    [
        ('objects:\n  - shape: [cylinder]\n', 'objects[0].shape'),  # via load_scenario's checks
        ('[' * 50_000, 'nested too deeply'),
        ('name: 2001-02-30\n', 'day is out of range'),
    ],
)
def test_load_scenario_bad_files_name_the_file(tmp_path: Any, text: str, problem: str) -> None:
    data = copy.deepcopy(GOOD)
    path = tmp_path / 'bad.yaml'
    if text.startswith('objects'):
        data['objects'][0]['shape'] = ['cylinder']
        text = yaml.safe_dump(data)
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    assert str(info.value).startswith(f'{path}: ') and problem in str(info.value)


@pytest.mark.parametrize('name', [7, None, '~no_such_user_qtree/s.yaml', 'a\x00b', 'x' * 5000])
def test_resolve_bad_names(name: Any) -> None:
    with pytest.raises(ScenarioError):
        resolve_scenario(name)


@pytest.mark.parametrize('where', ['name', 'id'])
def test_huge_names_and_ids_are_rejected_shortly(where: str) -> None:
    def mutate(data: dict[str, Any]) -> None:
        if where == 'name':
            data['name'] = 'n' * 10_000
        else:
            data['objects'][1]['id'] = 'O' * 10_000

    with pytest.raises(ScenarioError, match='at most 256 characters, got 10000') as err:
        parse_scenario(_bad(mutate), source='huge.yaml')
    assert len(str(err.value)) < 200  # a 10 000-character name was echoed in /scene (#18)


def test_a_huge_source_is_clipped_in_the_message() -> None:
    with pytest.raises(ScenarioError) as err:
        resolve_scenario('/no/such/' + 'd' * 10_000)
    assert len(str(err.value)) < 500


@pytest.mark.parametrize(
    ('change', 'field'),
    [
        ({'radius': math.nan}, 'objects[1].radius'),
        ({'height': -0.1}, 'objects[1].height'),
        ({'position': (0.6, math.inf, 0.05)}, 'objects[1].pose'),
        ({'yaw': math.nan}, 'objects[1].pose'),
        ({'shape': 'cone'}, 'objects[1].shape'),
    ],
)
def test_a_scenario_built_in_code_gets_the_number_checks_of_the_parsers(
    change: dict, field: str
) -> None:
    """#27: one validator for files, messages and code (the motion planner's own copy is
    gone). A NaN radius passed it before: NaN footprints overlap nothing and sit nowhere."""
    import dataclasses

    scenario = load_scenario('s1')
    objects = list(scenario.objects)
    objects[1] = dataclasses.replace(objects[1], **change)
    broken = dataclasses.replace(scenario, objects=tuple(objects))
    for check_layout in (True, False):
        with pytest.raises(ScenarioError, match=re.escape(field)):
            validate_scenario(broken, check_layout=check_layout)


def test_the_planning_check_skips_only_the_layout() -> None:
    """check_layout=False (the motion planner) accepts overlapping objects, never two targets."""
    import dataclasses

    scenario = load_scenario('s1')
    objects = list(scenario.objects)
    objects[2] = dataclasses.replace(objects[2], position=objects[1].position)
    overlapping = dataclasses.replace(scenario, objects=tuple(objects))
    with pytest.raises(ScenarioError, match='overlaps'):
        validate_scenario(overlapping)
    validate_scenario(overlapping, check_layout=False)
    objects[2] = dataclasses.replace(objects[2], role='target')
    with pytest.raises(ScenarioError, match='exactly one object'):
        validate_scenario(
            dataclasses.replace(scenario, objects=tuple(objects)), check_layout=False
        )
