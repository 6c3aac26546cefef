"""Property-based fuzzing of the scenario loader and of the motion-planner core (no ROS graph).

Properties:
- ``parse_scenario`` / ``load_scenario`` on any YAML structure or text either return a valid
  ``Scenario`` or raise ``ScenarioError`` naming the offending field (a global problem, such as a
  top level that is not a mapping or unreadable YAML, may name no field); never another exception.
- ``generate_clutter`` on any arguments returns a valid scene or raises ``ScenarioError``.
- ``MotionPlanner.check`` on any object id and relocated-id list returns a ``PlanResult`` whose
  reason is one of ``Reason`` (1xx for a malformed request, else 0 / 2xx / 301), ``feasible`` iff
  ``SUCCESS``, with a message; never an exception.

Examples are bounded (``max_examples``, ``deadline``) and derandomised so CI is reproducible.
"""

from __future__ import annotations

import copy
import functools
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

REPO_ROOT = Path(__file__).resolve().parents[1]
S1_YAML = REPO_ROOT / 'ros2_ws/src/qtree_scene/qtree_scene/scenarios/s1.yaml'
FUZZ = settings(
    max_examples=150,
    deadline=2000,  # [ms] per example
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)

# --- random YAML values ------------------------------------------------------------------------
NUMBERS = st.one_of(
    st.integers(min_value=-(10**3), max_value=10**3),
    st.sampled_from([0, -1, 10**20, 10**400, -(10**400)]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-320, 1e308, math.nan, math.inf, -math.inf]),
)
WORDS = st.sampled_from(
    ['', ' ', 'T', 'O1', 'table', 'target', 'obstacle', 'static', 'cylinder', 'box', 'x']
)
SCALARS = st.one_of(st.none(), st.booleans(), NUMBERS, WORDS, st.text(max_size=8))
KEYS = st.one_of(
    st.sampled_from(
        ['name', 'objects', 'table', 'drop_zone', 'home', 'id', 'role', 'shape', 'xy', 'radius']
    ),
    st.text(min_size=1, max_size=6),  # the empty key has its own test below
    st.integers(-3, 3),
)
VALUES = st.recursive(
    SCALARS,
    lambda children: st.one_of(
        st.lists(children, max_size=8), st.dictionaries(KEYS, children, max_size=6)
    ),
    max_leaves=25,
)


@functools.cache
def s1_mapping() -> dict:
    return yaml.safe_load(S1_YAML.read_text())


def _paths(data: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key / index path inside ``data`` (the root excluded)."""
    found = []
    items = data.items() if isinstance(data, dict) else enumerate(data)
    for key, value in items:
        found.append((*prefix, key))
        if isinstance(value, (dict, list)):
            found += _paths(value, (*prefix, key))
    return found


@st.composite
def mutated_s1(draw: st.DrawFn) -> dict:
    """s1 with 1..3 items replaced by random values, deleted, or a random key added."""
    data = copy.deepcopy(s1_mapping())
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        if not paths:
            break
        *head, last = draw(st.sampled_from(paths))
        parent = data
        for key in head:
            parent = parent[key]
        action = draw(st.sampled_from(['replace', 'replace', 'delete', 'add']))
        if action == 'replace':
            parent[last] = draw(VALUES)
        elif action == 'delete':
            del parent[last]
        elif isinstance(parent, dict):
            parent[draw(KEYS)] = draw(VALUES)
        else:
            parent.append(draw(VALUES))
    return data


def _assert_valid_or_named(data: Any, source: str = 'fuzz') -> None:
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.scenario import parse_scenario
    from qtree_scene.scene import Scenario

    try:
        scenario = parse_scenario(data, source=source)
    except ScenarioError as err:
        assert err.problem, 'a ScenarioError must say what is wrong'
        if isinstance(data, dict):
            assert err.field, f'no field named for {data!r}: {err}'
        return
    assert isinstance(scenario, Scenario)
    assert sum(o.role == 'target' for o in scenario.objects) == 1
    numbers = [v for o in scenario.objects for v in (*o.position, o.radius, o.height, *o.size)]
    assert all(math.isfinite(v) for v in numbers)


@FUZZ
@given(data=VALUES)
def test_parse_scenario_random_structures(data: Any) -> None:
    _assert_valid_or_named(data)


@FUZZ
@given(data=mutated_s1())
def test_parse_scenario_mutated_s1(data: dict) -> None:
    _assert_valid_or_named(data)


@pytest.mark.parametrize('where', ['top level', 'object'])
def test_unknown_empty_key_is_named(where: str) -> None:
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.scenario import parse_scenario

    data = copy.deepcopy(s1_mapping())
    (data if where == 'top level' else data['objects'][0])[''] = 1
    with pytest.raises(ScenarioError) as info:
        parse_scenario(data, source='fuzz')
    assert 'unknown key' in info.value.problem
    assert info.value.field not in ('', 'objects[0].'), f'the empty key is not shown: {info.value}'


@settings(FUZZ, max_examples=60)
@given(data=st.one_of(mutated_s1(), VALUES))
def test_load_scenario_yaml_files(tmp_path_factory: pytest.TempPathFactory, data: Any) -> None:
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.scenario import load_scenario

    path = tmp_path_factory.mktemp('fuzz') / 'scenario.yaml'
    path.write_text(yaml.safe_dump(data))
    try:
        load_scenario(str(path))
    except ScenarioError as err:
        assert str(path) in str(err), 'the message must name the file'


@settings(FUZZ, max_examples=60)
@given(raw=st.binary(max_size=200) | st.text(max_size=200).map(str.encode))
def test_load_scenario_random_bytes(tmp_path_factory: pytest.TempPathFactory, raw: bytes) -> None:
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.scenario import load_scenario

    path = tmp_path_factory.mktemp('fuzz') / 'scenario.yaml'
    path.write_bytes(raw)
    with pytest.raises(ScenarioError):
        load_scenario(str(path))


@settings(FUZZ, max_examples=40, deadline=5000)
@given(
    n_objects=st.one_of(st.integers(-2, 25), st.sampled_from([True, 1.5])),
    density=st.one_of(st.floats(-1, 1), st.sampled_from([math.nan, math.inf, 0.0, 0.4])),
    seed=st.integers(0, 2**32 - 1),
)
def test_generate_clutter_valid_or_scenario_error(n_objects: Any, density: float, seed: int):
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.generator import generate_clutter
    from qtree_scene.scenario import validate_scenario

    try:
        scenario = generate_clutter(n_objects, density, seed)
    except ScenarioError as err:
        assert err.field in {'n_objects', 'density', 'radius_range'}, err
        return
    validate_scenario(scenario)
    assert len(scenario.obstacles) == n_objects


# --- RelocateObject request fields against the in-process MotionPlanner -----------------------
@functools.cache
def planner() -> Any:
    from qtree_scene.scenario import load_scenario
    from stpik_motion_planner.planner import MotionPlanner

    return MotionPlanner(load_scenario('s1'))


S1_IDS = ['T', 'O1', 'O2', 'O3', 'O4', 'O5']
IDS = st.one_of(
    st.sampled_from(S1_IDS),
    st.sampled_from(['', ' ', 'table', 'o1', 'O1 ', 'T\x00', 'ghost', 'O' * 1000]),
    st.text(max_size=10),
)


@settings(FUZZ, max_examples=120, deadline=10_000)
@given(object_id=IDS, relocated=st.lists(IDS, max_size=8))
def test_motion_planner_check_never_raises(object_id: str, relocated: list[str]) -> None:
    from stpik_motion_planner.result import PlanResult, Reason

    result = planner().check(object_id, relocated)
    assert isinstance(result, PlanResult)
    assert isinstance(result.reason, Reason)
    assert result.feasible == (result.reason == Reason.SUCCESS)
    assert result.message
    valid = (
        object_id in S1_IDS
        and all(r in S1_IDS for r in relocated)
        and len(set(relocated)) == len(relocated)
        and object_id not in relocated
        and 'T' not in relocated
    )
    if valid:
        assert result.reason in {0, *range(201, 210), 301}, result.message
    else:
        assert 100 < result.reason < 200, (object_id, relocated, result.message)
    if result.feasible:
        assert result.joint_trajectory.shape[1] == 7 and len(result.times) > 1
        assert 0 <= result.grasp_index < result.release_index < len(result.times)


@settings(FUZZ, max_examples=40)
@given(
    object_id=st.one_of(st.none(), st.integers(), st.binary(max_size=4), IDS),
    relocated=st.one_of(
        st.lists(st.one_of(st.none(), st.integers(), IDS), max_size=4), st.text(max_size=4)
    ),
)
def test_motion_planner_check_wrong_types(object_id: Any, relocated: Any) -> None:
    from stpik_motion_planner.result import PlanResult

    result = planner().check(object_id, relocated)
    assert isinstance(result, PlanResult) and result.message
