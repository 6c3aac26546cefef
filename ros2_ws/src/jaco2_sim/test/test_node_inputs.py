"""In-process tests of the sim node's answers to bad scenarios and oversized trajectories.

The node runs in a private rclpy context with discovery off (no graph, nothing spun): the tests
call its service, parameter and subscription callbacks directly.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from jaco2_description.model import ARM_JOINTS, HOME
from qtree_scene.scenario import SCENARIO_DIR

HUGE_INT = 10**400


def _s1() -> dict[str, Any]:
    return yaml.safe_load((SCENARIO_DIR / 's1.yaml').read_text())


def _file(tmp_path: Path, data: dict[str, Any]) -> str:
    path = tmp_path / 'bad.yaml'
    path.write_text(yaml.safe_dump(data))
    return str(path)


@pytest.fixture
def node(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    import rclpy
    from jaco2_sim.sim_node import Jaco2SimNode
    from rclpy.context import Context

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'OFF')
    context = Context()
    rclpy.init(context=context)
    sim = Jaco2SimNode(context=context)
    yield sim
    sim.destroy_node()
    rclpy.try_shutdown(context=context)


def _reset(node: Any, scenario: str) -> Any:
    from qtree_msgs.srv import ResetScene

    return node._on_reset(ResetScene.Request(scenario=scenario), ResetScene.Response())


BAD_FILES = {  # id: (mutation of s1, field named in the answer, problem)
    'shape a list': (lambda d: d['objects'][0].update(shape=['cylinder']), 'objects[0].shape',
                     'expected a string, got list'),
    'role a mapping': (lambda d: d['objects'][1].update(role={'a': 1}), 'objects[1].role',
                       'expected a string, got dict'),
    'radius a huge integer': (lambda d: d['objects'][0].update(radius=HUGE_INT),
                              'objects[0].radius', 'too large for a float'),
    'home a huge integer': (lambda d: d['home'].__setitem__(0, HUGE_INT), 'home[0]',
                            'too large for a float'),
}  # fmt: skip


@pytest.mark.parametrize('case', list(BAD_FILES))
def test_reset_scene_answers_bad_files(node: Any, tmp_path: Path, case: str) -> None:
    mutate, field, problem = BAD_FILES[case]
    data = _s1()
    mutate(data)
    path = _file(tmp_path, data)
    response = _reset(node, path)
    assert not response.success
    assert f'{path}: {field}: ' in response.message and problem in response.message
    assert node.core.scenario.name == 's1'


@pytest.mark.parametrize('case', list(BAD_FILES))
def test_scenario_parameter_rejects_bad_files(node: Any, tmp_path: Path, case: str) -> None:
    from rclpy.parameter import Parameter

    mutate, field, problem = BAD_FILES[case]
    data = _s1()
    mutate(data)
    path = _file(tmp_path, data)
    (result,) = node.set_parameters([Parameter('scenario', value=path)])
    assert not result.successful
    assert f'{path}: {field}: ' in result.reason and problem in result.reason
    assert node.get_parameter('scenario').value == 's1'
    assert node.core.scenario.name == 's1'


def test_unexpected_loader_exception_is_answered(
    node: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    from jaco2_sim import simulation
    from rclpy.parameter import Parameter

    def broken(name: str) -> None:
        raise RuntimeError(f'loader bug on {name}')

    monkeypatch.setattr(simulation, 'load_scenario', broken)
    response = _reset(node, 's2')
    assert not response.success
    assert 'unexpected RuntimeError: loader bug on s2' in response.message
    (result,) = node.set_parameters([Parameter('scenario', value='s3')])
    assert not result.successful and 'RuntimeError' in result.reason
    assert node.core.scenario.name == 's1'
    monkeypatch.undo()
    assert _reset(node, 's2').success and node.core.scenario.name == 's2'


def _raw_trajectory(n: int, velocities: bool = False) -> bytes:
    from builtin_interfaces.msg import Duration
    from rclpy.serialization import serialize_message
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    msg = JointTrajectory(joint_names=list(ARM_JOINTS))
    for k in range(n):
        t = 0.01 * (k + 1)
        msg.points.append(
            JointTrajectoryPoint(
                positions=HOME.tolist(),
                velocities=[0.0] * 7 if velocities else [],
                time_from_start=Duration(sec=int(t), nanosec=round((t % 1) * 1e9) % 10**9),
            )
        )
    return serialize_message(msg)


@pytest.fixture
def rejections(node: Any, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Reasons the node logs for rejected trajectories."""
    seen: list[str] = []
    original = node._reject_trajectory

    def spy(why: str) -> None:
        seen.append(why)
        original(why)

    monkeypatch.setattr(node, '_reject_trajectory', spy)
    return seen


def test_trajectory_point_limit(node: Any, rejections: list[str]) -> None:
    from rclpy.parameter import Parameter

    assert node.get_parameter('max_trajectory_points').value == 10_000
    assert node.set_parameters([Parameter('max_trajectory_points', value=50)])[0].successful
    node._on_raw_trajectory(_raw_trajectory(51))
    assert not node.core.sim.active
    assert rejections == [
        '51 points, more than max_trajectory_points = 50 (split it or raise the parameter)'
    ]
    node._on_raw_trajectory(_raw_trajectory(50, velocities=True))
    assert node.core.sim.active and len(rejections) == 1


@pytest.mark.parametrize('value', [0, 100_001])
def test_trajectory_point_limit_range(node: Any, value: int) -> None:
    from rclpy.parameter import Parameter

    assert not node.set_parameters([Parameter('max_trajectory_points', value=value)])[0].successful
    assert node.get_parameter('max_trajectory_points').value == 10_000


def test_oversized_trajectory_rejected_unread(node: Any, rejections: list[str]) -> None:
    raw = _raw_trajectory(100_000)
    start = time.process_time()
    node._on_raw_trajectory(raw)
    seconds = time.process_time() - start
    assert rejections and 'max_trajectory_points = 10000' in rejections[0]
    assert not node.core.sim.active
    assert seconds < 0.02, f'rejecting took {seconds:.3f} s: the message was deserialised'


def test_trajectory_at_the_limit_is_followed_quickly(node: Any, rejections: list[str]) -> None:
    raw = _raw_trajectory(10_000)
    start = time.process_time()
    node._on_raw_trajectory(raw)
    seconds = time.process_time() - start
    assert node.core.sim.active and not rejections
    assert seconds < 0.5  # about 0.08 s here, mostly rclpy deserialisation


def test_garbage_bytes_are_rejected(node: Any, rejections: list[str]) -> None:
    node._on_raw_trajectory(b'\x00\x01\x00\x00\xff')
    node._on_raw_trajectory(_raw_trajectory(3)[:40])
    assert len(rejections) == 2 and not node.core.sim.active
