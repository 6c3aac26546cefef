"""Bad-input catalogue: what users' robot software may send, and what each node must answer.

One graph (simulator on s1, motion planner, task planner: ``GRAPH_NODES``, served by the
``client_graph`` fixture of conftest.py) runs for the whole module in a private ROS domain. Each
case sends one bad input and asserts the exact reason code or message fragment, then that the
node it hit is still alive and answering a valid request. A node that dies on a case fails that
case only: the ``graph`` fixture (conftest.py) restarts dead nodes before the next case (the crash
log is kept beside the restart's log and quoted in the failure).

Families: RelocateObject requests, RetrieveTarget goals, node parameters (``ros2 param set``
through ``/<node>/set_parameters``), scenario YAML files (``load_scenario`` and
``/jaco2_sim/reset_scene``), ``/joint_trajectory`` messages to the sim, and MCAP files for
``scripts/replay.py``.
"""

from __future__ import annotations

import importlib.util
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from qtree_node_support.orchestration import allocate_domain_id

pytestmark = pytest.mark.timeout(300)

REPO_ROOT = Path(__file__).resolve().parents[1]
S1_YAML = REPO_ROOT / 'ros2_ws/src/qtree_scene/qtree_scene/scenarios/s1.yaml'
FEASIBLE = 'O2'  # feasible on s1 with nothing relocated (checked in-process by the planner tests)
TARGET = 'T'
HUGE_INT = 10**400  # a YAML integer literal no float can hold
GRAPH_NODES = {  # executable -> (package, ROS node name, start-up parameters); conftest.py
    'sim_node': ('jaco2_sim', 'jaco2_sim', {'scenario': 's1', 'sim_rate_hz': 50.0}),
    'motion_planner_node': ('stpik_motion_planner', 'motion_planner', {}),
    'task_planner_node': (
        'qtree_task_planner',
        'task_planner',
        {'planner_wait_s': 5.0, 'scene_wait_s': 5.0, 'planner_timeout_s': 20.0},
    ),
}


# --- RelocateObject ----------------------------------------------------------------------------
# Codes from RelocateObject.srv and stpik_motion_planner.scene_checks.validate_request: an id that
# is not in the scene is UNKNOWN_OBJECT (also a very long or padded one), a malformed request
# (empty id, duplicates, static object, target among the relocated) is INVALID_REQUEST.
RELOCATE_CASES = [
    ('unknown object', 'no_such_object', [], False, 101, "unknown object 'no_such_object'"),
    ('empty object id', '', [], False, 103, 'object_id must be a non-empty string'),
    ('blank object id', '   ', [], False, 103, 'object_id must be a non-empty string'),
    ('object already relocated', 'O1', ['O1'], False, 102, "'O1' is already relocated"),
    ('target among relocated ids', 'O1', [TARGET], False, 103, 'cannot be among relocated_ids'),
    ('duplicate relocated ids', TARGET, ['O2', 'O2'], False, 103, 'duplicate ids'),
    ('unknown id among relocated', TARGET, ['ghost'], False, 101, "unknown object 'ghost'"),
    ('static table as object', 'table', [], False, 103, "'table' is static"),
    ('static table among relocated', TARGET, ['table'], False, 103, "'table' is static"),
    ('id with trailing blank', 'O1 ', [], False, 101, "unknown object 'O1 '"),
    ('non-ASCII id', 'Ö1', [], False, 101, "unknown object 'Ö1'"),
    ('empty string among relocated', TARGET, [''], False, 103, 'must be non-empty strings'),
    ('5000 unknown relocated ids', TARGET, [f'X{i}' for i in range(5000)], False, 101, "'X0'"),
    ('100 kB object id', 'O' * 100_000, [], False, 101, 'unknown object'),
    ('execute an unknown object', 'ghost', [], True, 101, "unknown object 'ghost'"),
    ('execute an infeasible object', TARGET, [], True, 201, 'no collision-free Cartesian path'),
]


@pytest.mark.parametrize(
    ('object_id', 'relocated', 'execute', 'code', 'fragment'),
    [case[1:] for case in RELOCATE_CASES],
    ids=[case[0] for case in RELOCATE_CASES],
)
def test_relocate_object_bad_request(graph, object_id, relocated, execute, code, fragment) -> None:
    q_before = graph.q.copy()
    response = graph.relocate(object_id, relocated, execute)
    assert not response.feasible
    assert response.reason == code, response.message[:300]
    assert fragment in response.message, response.message[:300]
    assert not response.trajectory.points, 'a rejected request carries no trajectory'
    if execute:  # nothing was sent to the arm
        graph.spin_until(lambda: False, 0.3)
        np.testing.assert_allclose(graph.q, q_before, atol=1e-9)
    graph.assert_alive('motion_planner_node')


# --- RetrieveTarget ----------------------------------------------------------------------------
# qtree_task_planner.goal_checks: every goal is accepted, an invalid one is aborted with
# INVALID_GOAL and a message naming the field.
GOAL_CASES = [
    ('unknown policy', {'policy': 'DQN'}, 'policy'),
    ('empty policy', {'policy': ''}, 'policy'),
    ('alpha zero', {'alpha': 0.0}, 'alpha'),
    ('alpha above one', {'alpha': 1.5}, 'alpha'),
    ('alpha NaN', {'alpha': math.nan}, 'alpha'),
    ('gamma zero', {'gamma': 0.0}, 'gamma'),
    ('gamma above one', {'gamma': 1.01}, 'gamma'),
    ('gamma infinite', {'gamma': math.inf}, 'gamma'),
    ('epsilon_min above epsilon0', {'epsilon0': 0.1, 'epsilon_min': 0.5}, 'epsilon_min'),
    ('epsilon0 zero', {'epsilon0': 0.0}, 'epsilon0'),
    ('epsilon_min NaN', {'epsilon_min': math.nan}, 'epsilon_min'),
    ('max_episodes zero', {'max_episodes': 0}, 'max_episodes'),
    ('max_episodes negative', {'max_episodes': -5}, 'max_episodes'),
    ('beta zero', {'beta': 0.0}, 'beta'),
    ('beta NaN', {'beta': math.nan}, 'beta'),
    ('beta inf', {'beta': math.inf}, 'beta'),
    ('steady_episodes zero', {'steady_episodes': 0}, 'steady_episodes'),
    ('feedback_every zero', {'feedback_every': 0}, 'feedback_every'),
    ('feedback_every negative', {'feedback_every': -3}, 'feedback_every'),
    ('seed negative', {'seed': -1}, 'seed'),
]


@pytest.mark.parametrize(
    ('fields', 'named'), [c[1:] for c in GOAL_CASES], ids=[c[0] for c in GOAL_CASES]
)
def test_retrieve_target_bad_goal(graph, fields, named) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget

    status, result = graph.goal(**fields)
    assert status == GoalStatus.STATUS_ABORTED
    assert not result.success
    assert result.error_code == RetrieveTarget.Result.INVALID_GOAL, (
        f'error_code={result.error_code} message={result.message!r}'
    )
    assert named in result.message, result.message
    graph.assert_alive('task_planner_node')


def test_retrieve_target_second_goal_while_busy(graph) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget

    assert graph.action.wait_for_server(timeout_sec=20.0)
    long_goal = RetrieveTarget.Goal(
        policy='LRND', max_episodes=1_000_000, steady_episodes=1_000_000, feedback_every=1
    )
    feedback: list[Any] = []
    first = graph.wait(graph.action.send_goal_async(long_goal, feedback_callback=feedback.append))
    assert graph.spin_until(lambda: bool(feedback), 30.0), 'the first goal never trained'
    status, result = graph.goal()
    assert status == GoalStatus.STATUS_ABORTED
    assert result.error_code == RetrieveTarget.Result.INVALID_GOAL and 'busy' in result.message
    graph.wait(first.cancel_goal_async())
    response = graph.wait(first.get_result_async(), 30.0)
    assert response.result.error_code == RetrieveTarget.Result.CANCELED
    graph.assert_alive('task_planner_node')


# --- Parameters (``ros2 param set`` through the parameter services) ----------------------------
_BAD_SHAPE = 'FILE:shape'  # a scenario file whose objects[0].shape is a list
_BAD_RADIUS = 'FILE:radius'  # a scenario file whose objects[0].radius is 10**400
PARAMETER_CASES = [
    ('sim rate zero', 'sim_node', 'sim_rate_hz', 0.0, 'out of range'),
    ('sim rate above 1000 Hz', 'sim_node', 'sim_rate_hz', 5000.0, 'out of range'),
    ('sim rate wrong type', 'sim_node', 'sim_rate_hz', 'fast', 'Wrong parameter type'),
    ('robot_description read-only', 'sim_node', 'robot_description', '<robot/>', 'read-only'),
    ('scenario unknown', 'sim_node', 'scenario', 'no_such_scenario', 'no such scenario'),
    ('scenario file, shape a list', 'sim_node', 'scenario', _BAD_SHAPE, 'objects[0].shape'),
    ('scenario file, huge radius', 'sim_node', 'scenario', _BAD_RADIUS, 'objects[0].radius'),
    ('initial_configuration 3 values', 'sim_node', 'initial_configuration', [1.0, 2.0, 3.0], '7'),
    ('initial_configuration NaN', 'sim_node', 'initial_configuration', [math.nan] * 7, 'finite'),
    ('finger angle after start', 'sim_node', 'finger_angle_rad', 0.5, 'fixed at start'),
    ('planner time limit negative', 'motion_planner_node', 'time_limit_s', -1.0, 'out of range'),
    ('planner seed as float', 'motion_planner_node', 'seed', 1.5, 'Wrong parameter type'),
    (
        'planner activation below failure distance',
        'motion_planner_node',
        'obstacle_min_distance_m',
        0.05,
        'obstacle_activation_m',
    ),
    ('planner execution timeout 0', 'motion_planner_node', 'execution_timeout_s', 0.0, 'range'),
    ('undeclared parameter', 'motion_planner_node', 'no_such_parameter', 1.0, 'undeclared'),
    ('grasp family unknown', 'motion_planner_node', 'grasp_families', ['side', 'up'], "'up'"),
    ('grasp families empty', 'motion_planner_node', 'grasp_families', [''], 'unknown grasp'),
    ('grasp families repeated', 'motion_planner_node', 'grasp_families', ['top', 'top'], 'rep'),
    ('grasp families a number', 'motion_planner_node', 'grasp_families', 3.0, 'Wrong parameter'),
    ('task planner timeout 0', 'task_planner_node', 'planner_timeout_s', 0.0, 'range'),
    ('task planner timeout NaN', 'task_planner_node', 'scene_wait_s', math.nan, 'range'),
]


@pytest.mark.parametrize(
    ('executable', 'name', 'value', 'fragment'),
    [c[1:] for c in PARAMETER_CASES],
    ids=[c[0] for c in PARAMETER_CASES],
)
def test_bad_parameter_is_rejected(graph, tmp_path, executable, name, value, fragment) -> None:
    from rcl_interfaces.srv import GetParameters, SetParameters
    from rclpy.parameter import Parameter

    if value == _BAD_SHAPE:
        value = str(_write_yaml(tmp_path, _s1_with(('objects', 0, 'shape'), ['cylinder'])))
    elif value == _BAD_RADIUS:
        value = str(_write_yaml(tmp_path, _s1_with(('objects', 0, 'radius'), HUGE_INT)))
    node_name = GRAPH_NODES[executable][1]
    setter = graph.node.create_client(SetParameters, f'/{node_name}/set_parameters')
    getter = graph.node.create_client(GetParameters, f'/{node_name}/get_parameters')
    before = graph.call(getter, GetParameters.Request(names=[name])).values
    request = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
    response = graph.call(setter, request, 30.0, executable)
    assert len(response.results) == 1
    assert not response.results[0].successful
    assert fragment in response.results[0].reason, response.results[0].reason
    after = graph.call(getter, GetParameters.Request(names=[name])).values
    assert after == before, 'a rejected value must leave the parameter unchanged'
    graph.node.destroy_client(setter)
    graph.node.destroy_client(getter)
    graph.assert_alive(executable)


# --- Scenario files: load_scenario (in-process) and /jaco2_sim/reset_scene ---------------------
def _s1_with(path: tuple, value: Any) -> dict:
    """The s1 mapping with the item at ``path`` (keys / indices) set to ``value``."""
    data = yaml.safe_load(S1_YAML.read_text())
    *head, last = path
    item = data
    for key in head:
        item = item[key]
    item[last] = value
    return data


def _s1_without(key: str) -> dict:
    data = yaml.safe_load(S1_YAML.read_text())
    del data[key]
    return data


def _write_yaml(directory: Path, content: Any, name: str = 'bad.yaml') -> Path:
    path = directory / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, str):
        path.write_text(content)
    else:
        path.write_text(yaml.safe_dump(content))
    return path


SCENARIO_CASES = [  # (id, file content or a special name, fragment of the ScenarioError message)
    ('unknown installed name', 'NAME:no_such_scenario', 'no such scenario or file'),
    ('missing file', 'PATH:missing.yaml', 'no such scenario or file'),
    ('directory', 'PATH:.', 'no such scenario or file'),
    ('YAML syntax error', 'name: broken\nobjects: [}\n', 'cannot read YAML'),
    ('not UTF-8', b'\xff\xfe\x00garbage\x81', 'cannot read YAML'),
    ('empty file', '', 'top level must be a mapping'),
    ('top level list', '- 1\n- 2\n', 'top level must be a mapping'),
    ('objects missing', _s1_without('objects'), 'objects: missing'),
    ('objects empty', _s1_with(('objects',), []), 'objects: must be a non-empty list'),
    ('two targets', _s1_with(('objects', 1, 'role'), 'target'), 'exactly one object'),
    ('no target', _s1_with(('objects', 0, 'role'), 'obstacle'), 'exactly one object'),
    ('duplicate ids', _s1_with(('objects', 1, 'id'), 'T'), "duplicate id 'T'"),
    ('id reserved for the table', _s1_with(('objects', 1, 'id'), 'table'), 'reserved'),
    ('overlapping objects', _s1_with(('objects', 1, 'xy'), [0.8, 0.0]), 'overlaps'),
    ('NaN radius', _s1_with(('objects', 0, 'radius'), math.nan), 'objects[0].radius'),
    ('negative height', _s1_with(('objects', 0, 'height'), -0.1), 'objects[0].height'),
    ('unknown key', _s1_with(('objects', 0, 'colour'), 'red'), 'objects[0].colour'),
    ('object off the table', _s1_with(('objects', 0, 'xy'), [5.0, 0.0]), 'not on the table'),
    ('home beyond a joint limit', _s1_with(('home', 1), 0.1), 'home[1]'),
    ('radius as text', _s1_with(('objects', 0, 'radius'), 'big'), 'objects[0].radius'),
    ('shape as a list', _s1_with(('objects', 0, 'shape'), ['cylinder']), 'objects[0].shape'),
    ('radius a huge integer', _s1_with(('objects', 0, 'radius'), HUGE_INT), 'objects[0].radius'),
    ('home a huge integer', _s1_with(('home', 0), HUGE_INT), 'home[0]'),
]


def _scenario_argument(directory: Path, content: Any) -> str:
    if isinstance(content, str) and content.startswith('NAME:'):
        return content[5:]
    if isinstance(content, str) and content.startswith('PATH:'):
        return str(directory / content[5:])
    return str(_write_yaml(directory, content))


@pytest.mark.parametrize(
    ('content', 'fragment'), [c[1:] for c in SCENARIO_CASES], ids=[c[0] for c in SCENARIO_CASES]
)
def test_load_scenario_rejects(tmp_path, content, fragment) -> None:
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.scenario import load_scenario

    with pytest.raises(ScenarioError) as info:
        load_scenario(_scenario_argument(tmp_path, content))
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    ('content', 'fragment'), [c[1:] for c in SCENARIO_CASES], ids=[c[0] for c in SCENARIO_CASES]
)
def test_reset_scene_rejects(graph, tmp_path, content, fragment) -> None:
    response = graph.reset(_scenario_argument(tmp_path, content))
    assert not response.success
    assert fragment in response.message, response.message
    graph.spin_until(lambda: False, 0.2)
    assert graph.scene_name == 's1', 'a rejected scenario must leave the scene unchanged'
    graph.assert_alive('sim_node')


# --- /joint_trajectory messages to the sim -----------------------------------------------------
def _trajectory(points: list[tuple[float, list[float], list[float]]], names: list[str]) -> Any:
    from builtin_interfaces.msg import Duration
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    msg = JointTrajectory(joint_names=names)
    for t, positions, velocities in points:
        sec = math.floor(t)
        msg.points.append(
            JointTrajectoryPoint(
                positions=positions,
                velocities=velocities,
                time_from_start=Duration(sec=sec, nanosec=int((t - sec) * 1e9)),
            )
        )
    return msg


def _home_plus(**joint_values: float) -> list[float]:
    from jaco2_description.model import HOME

    q = [float(v) for v in HOME]
    for key, value in joint_values.items():
        q[int(key[1:]) - 1] = value
    return q


def _arm() -> list[str]:
    from jaco2_description.model import ARM_JOINTS

    return list(ARM_JOINTS)


NAN, INF = math.nan, math.inf
TRAJECTORY_CASES = {  # id: (names, points, log fragment)
    'NaN position': (None, [(1.0, _home_plus(j1=NAN), [])], 'non-finite'),
    'infinite position': (None, [(1.0, _home_plus(j3=INF), [])], 'non-finite'),
    'NaN velocity': (None, [(1.0, _home_plus(), [NAN] * 7)], 'velocities: non-finite'),
    'finger joint name': ('finger', [(1.0, _home_plus(), [])], 'joint names must be'),
    'six joint names': ('six', [(1.0, _home_plus()[:6], [])], 'joint names must be'),
    'duplicate joint name': ('duplicate', [(1.0, _home_plus(), [])], 'joint names must be'),
    'no joint names': ('none', [(1.0, _home_plus(), [])], 'joint names must be'),
    'six positions for seven joints': (None, [(1.0, _home_plus()[:6], [])], 'positions: shape'),
    'ragged points': (
        None,
        [(1.0, _home_plus(), []), (2.0, _home_plus()[:5], [])],
        'positions: not numeric',
    ),
    'times not increasing': (
        None,
        [(1.0, _home_plus(), []), (1.0, _home_plus(), [])],
        'strictly increasing',
    ),
    'negative time': (None, [(-1.0, _home_plus(), [])], 'times must be'),
    'velocities on some points only': (
        None,
        [(1.0, _home_plus(), [0.0] * 7), (2.0, _home_plus(), [])],
        'on every point or on none',
    ),
}


def _names(kind: str | None) -> list[str]:
    arm = _arm()
    return {
        None: arm,
        'finger': [*arm[:6], 'j2s7s300_joint_finger_1'],
        'six': arm[:6],
        'duplicate': [*arm[:6], arm[0]],
        'none': [],
    }[kind]


@pytest.mark.parametrize('case', list(TRAJECTORY_CASES))
def test_bad_trajectory_is_rejected_and_sim_keeps_publishing(graph, case) -> None:
    names, points, fragment = TRAJECTORY_CASES[case]
    assert graph.reset('s1').success  # home, no reference
    graph.spin_until(lambda: False, 0.2)
    q_before, count, mark = graph.q.copy(), graph.states, graph.log_mark('sim_node')
    graph.trajectory_pub.publish(_trajectory(points, _names(names)))
    text = graph.wait_log('sim_node', mark, fragment)
    assert 'trajectory rejected' in text
    assert graph.spin_until(lambda: graph.states >= count + 25, 5.0), 'the sim stopped publishing'
    np.testing.assert_allclose(graph.q, q_before, atol=1e-9, err_msg='a rejected trajectory moved')
    graph.assert_alive('sim_node')


@pytest.mark.parametrize('value', [0.3, -1e300], ids=['slightly below', 'minus 1e300'])
def test_trajectory_beyond_joint_limits_is_clamped(graph, value) -> None:
    from jaco2_description.model import arm_limits

    assert graph.reset('s1').success
    mark = graph.log_mark('sim_node')
    graph.trajectory_pub.publish(_trajectory([(0.5, _home_plus(j4=value), [])], _arm()))
    graph.wait_log('sim_node', mark, 'clamped')
    goal = np.array(_home_plus(j4=float(arm_limits().lower[3])))
    assert graph.spin_until(lambda: np.max(np.abs(graph.q - goal)) < 1e-3, 5.0), graph.q
    assert np.all(np.isfinite(graph.q))
    graph.assert_alive('sim_node')


# --- MCAP files for scripts/replay.py ----------------------------------------------------------
FIXTURES = REPO_ROOT / 'ros2_ws/src/qtree_recorder/test/replay_fixtures.py'


def _good_log(path: Path) -> bytes:
    name = 'qtree_recorder_replay_fixtures'
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, FIXTURES)
        sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    sys.modules[name].write_run(path, joint_states=200, chunk_size=2048)
    return path.read_bytes()


def _corrupt_chunk(good: bytes) -> bytes:
    cut = int(len(good) * 0.3)  # inside the chunks (the summary starts past 60 %)
    return good[:cut] + b'\x00' * 64 + good[cut + 64 :]


MAGIC = b'\x89MCAP0\r\n'
REPLAY_CASES = [  # (id, file content or None = missing or DIR, mode, message fragment)
    ('missing file', None, '--summary', 'no such file'),
    ('missing file, publish', None, '--publish', 'no such file'),
    ('directory', 'DIR', '--summary', 'no such file'),
    ('empty file', b'', '--summary', 'not an MCAP file'),
    ('empty file, rerun', b'', '--rerun', 'not an MCAP file'),
    ('text file', b'just some notes\n', '--summary', 'not an MCAP file'),
    ('magic only', MAGIC, '--summary', 'truncated before the first complete chunk'),
    ('magic then garbage', MAGIC + bytes(range(66, 126)) * 50, '--summary', 'invalid record'),
    ('cut after 40 bytes', 'CUT40', '--summary', 'truncated before the first complete chunk'),
    ('zeroed chunk', 'CORRUPT', '--summary', 'at byte'),  # invalid record or damaged chunk
]


@pytest.mark.parametrize(
    ('content', 'mode', 'fragment'),
    [c[1:] for c in REPLAY_CASES],
    ids=[c[0] for c in REPLAY_CASES],
)
def test_replay_bad_file_one_clean_line(tmp_path, content, mode, fragment) -> None:
    path = tmp_path / 'log.mcap'
    if content == 'DIR':
        path.mkdir()
    elif content in ('CUT40', 'CORRUPT'):
        good = _good_log(tmp_path / 'good.mcap')
        path.write_bytes(good[:40] if content == 'CUT40' else _corrupt_chunk(good))
    elif content is not None:
        path.write_bytes(content)
    rrd = tmp_path / 'out.rrd'
    extra = ['--rrd', str(rrd)] if mode == '--rerun' else []
    env = dict(os.environ, RERUN_ANALYTICS='0', ROS_DOMAIN_ID=str(allocate_domain_id()))
    result = subprocess.run(
        [sys.executable, str(REPO_ROOT / 'scripts/replay.py'), str(path), mode, *extra],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert result.returncode == 2, result.stdout + result.stderr
    assert 'Traceback' not in result.stdout + result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith('replay.py: error: ') and fragment in lines[0], lines[0]
    assert not rrd.exists()
