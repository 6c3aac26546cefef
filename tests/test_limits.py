"""Limits: huge requests, a 200-object scene and a 100 000-point trajectory, in time and memory.

One sim + motion planner graph for the module. Each case measures the answer time and the
resident memory (VmRSS from ``/proc/<pid>/status``, summed over the node's process tree) of the
node before and after, and prints the figures (``-s``) for docs/RELIABILITY.md. No node documents
a size limit on these inputs, so the assertions are the bounds a user may expect: an answer in
seconds, RSS growth below 150 MB, the sim publishing /joint_states without a long gap, and
answers (messages, logs) that stay short when the request is huge.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from load_test import rss_mb  # one RSS reader for the load script and these tests
from orchestration import NodeProcess, allocate_domain_id, start_node, stop_all

pytestmark = pytest.mark.timeout(300)

RSS_GROWTH_MB = 150.0  # largest acceptable RSS growth of a node for one huge input [MB]
MESSAGE_CHARS = 2000  # longest acceptable answer message [characters]
MAX_STATE_GAP_S = 0.5  # longest acceptable /joint_states silence of the sim (25 periods) [s]


class Limits:
    """Sim (s1) and motion planner on a private domain, and a client node."""

    def __init__(self, domain_id: int, logs: Path) -> None:
        import rclpy
        from qtree_msgs.msg import Scene
        from qtree_msgs.srv import RelocateObject, ResetScene
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from trajectory_msgs.msg import JointTrajectory

        env = dict(
            os.environ, ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST'
        )
        self.sim = start_node(
            'jaco2_sim', 'sim_node', parameters={'sim_rate_hz': 50.0}, env=env, log_dir=logs
        )
        self.mp = start_node('stpik_motion_planner', 'motion_planner_node', env=env, log_dir=logs)
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('limits_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.state_times: list[float] = []  # /joint_states stamps (sim clock) [s]
        self.scene: Any = None
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.node.create_subscription(JointState, '/joint_states', self._on_state, 1000)
        self.node.create_subscription(Scene, '/scene', self._on_scene, latched)
        self.trajectory_pub = self.node.create_publisher(JointTrajectory, '/joint_trajectory', 10)
        self.relocate = self.node.create_client(RelocateObject, '/relocate_object')
        self.reset = self.node.create_client(ResetScene, '/jaco2_sim/reset_scene')

    def _on_state(self, msg: Any) -> None:
        self.state_times.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)

    def _on_scene(self, msg: Any) -> None:
        self.scene = msg

    def spin_until(self, predicate: Any, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            self.executor.spin_once(timeout_sec=0.02)
        return predicate()

    def call(self, client: Any, request: Any, timeout_s: float) -> tuple[Any, float]:
        """(response, seconds) of one service call."""
        assert client.wait_for_service(timeout_sec=20.0)
        start = time.monotonic()
        future = client.call_async(request)
        assert self.spin_until(future.done, timeout_s), f'no answer in {timeout_s} s'
        return future.result(), time.monotonic() - start

    def close(self) -> dict[str, int]:
        import rclpy

        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        return stop_all([self.sim, self.mp])


@pytest.fixture(scope='module')
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Limits]:
    graph = Limits(allocate_domain_id(), tmp_path_factory.mktemp('limits_logs'))
    try:
        graph.sim.wait_for_log('ready', 90.0)
        graph.mp.wait_for_log('ready', 90.0)
        graph.mp.wait_for_log('planner rebuilt', 30.0)
        assert graph.spin_until(lambda: graph.scene is not None and graph.state_times, 20.0)
        yield graph
    finally:
        codes = graph.close()
    assert all(code == 0 for code in codes.values()), codes


def _report(label: str, node: NodeProcess, before_mb: float, seconds: float) -> float:
    after_mb = rss_mb(node.process.pid)
    print(
        f'\n[limits] {label}: {seconds:.2f} s, {node.name} RSS {before_mb:.0f} -> '
        f'{after_mb:.0f} MB (+{after_mb - before_mb:.0f})'
    )
    return after_mb - before_mb


@pytest.mark.parametrize(
    ('label', 'object_id', 'relocated', 'code'),
    [
        ('10 000 unknown ids', 'T', [f'X{i}' for i in range(10_000)], 101),
        ('10 000 copies of one id', 'T', ['O1'] * 10_000, 103),
        ('10 000 empty ids', 'T', [''] * 10_000, 103),
    ],
    ids=['unknown', 'duplicates', 'empty'],
)
def test_huge_relocated_list(graph: Limits, label, object_id, relocated, code) -> None:
    from qtree_msgs.srv import RelocateObject

    before = rss_mb(graph.mp.process.pid)
    mark = len(graph.mp.log_text())
    request = RelocateObject.Request(object_id=object_id, relocated_ids=relocated)
    response, seconds = graph.call(graph.relocate, request, 30.0)
    growth = _report(f'RelocateObject with {label}', graph.mp, before, seconds)
    logged = graph.mp.log_text()[mark:]
    print(f'[limits]   message {len(response.message)} chars, log {len(logged)} chars')
    assert response.reason == code, response.message[:300]
    assert seconds < 5.0 and growth < RSS_GROWTH_MB
    ok, _ = graph.call(graph.relocate, RelocateObject.Request(object_id='O2'), 30.0)
    assert ok.feasible, ok.message
    assert len(response.message) <= MESSAGE_CHARS, (
        f'the answer echoes the request: {len(response.message)} chars'
    )
    assert len(logged) <= 10 * MESSAGE_CHARS, f'one request logged {len(logged)} chars'


def test_scene_with_200_objects(graph: Limits, tmp_path: Path) -> None:
    from qtree_msgs.srv import RelocateObject, ResetScene
    from qtree_scene.generator import generate_clutter
    from qtree_scene.scenario import dump_scenario

    path = tmp_path / 'clutter200.yaml'
    path.write_text(dump_scenario(generate_clutter(200, 0.3, seed=0)))
    sim_before, mp_before = rss_mb(graph.sim.process.pid), rss_mb(graph.mp.process.pid)
    mark = len(graph.mp.log_text())
    response, seconds = graph.call(graph.reset, ResetScene.Request(scenario=str(path)), 30.0)
    assert response.success, response.message
    assert graph.spin_until(lambda: len(graph.scene.objects) == 202, 10.0)
    start = time.monotonic()
    assert graph.spin_until(lambda: 'planner rebuilt' in graph.mp.log_text()[mark:], 30.0)
    rebuilt_s = time.monotonic() - start + seconds
    _report('reset_scene to 200 objects', graph.sim, sim_before, seconds)
    times = {}
    for object_id, relocated in [
        ('O1', []),
        ('O2', ['O1']),
        ('T', []),
        ('T', [f'O{i}' for i in range(1, 201)]),
    ]:
        request = RelocateObject.Request(object_id=object_id, relocated_ids=relocated)
        answer, times[object_id, len(relocated)] = graph.call(graph.relocate, request, 60.0)
        assert answer.reason in {0, *range(201, 210), 301}, answer.message
    growth = _report(
        f'200 objects: planner rebuilt in {rebuilt_s:.2f} s, 4 checks',
        graph.mp,
        mp_before,
        sum(times.values()),
    )
    print(f'[limits]   check times [s]: { {k: round(v, 3) for k, v in times.items()} }')
    assert max(times.values()) < 5.0 + 5.0  # time_limit_s + transport
    assert growth < RSS_GROWTH_MB
    assert graph.call(graph.reset, ResetScene.Request(scenario='s1'), 30.0)[0].success
    assert graph.spin_until(lambda: len(graph.scene.objects) == 7, 10.0)


@pytest.mark.parametrize('n', [10_000, 100_000])
def test_long_trajectory(graph: Limits, n: int) -> None:
    from builtin_interfaces.msg import Duration
    from jaco2_description.model import ARM_JOINTS, HOME
    from qtree_msgs.srv import ResetScene
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    msg = JointTrajectory(joint_names=list(ARM_JOINTS))
    for k in range(n):  # 0.01 s apart: a slow sweep of joint 1 by up to 0.5 rad
        t = 0.01 * (k + 1)
        q = HOME.copy()
        q[0] += 0.5 * math.sin(math.pi * k / n)
        msg.points.append(
            JointTrajectoryPoint(
                positions=q.tolist(),
                time_from_start=Duration(sec=int(t), nanosec=round((t % 1) * 1e9) % 10**9),
            )
        )
    before = rss_mb(graph.sim.process.pid)
    mark = len(graph.sim.log_text())
    count = len(graph.state_times)
    assert graph.spin_until(lambda: graph.trajectory_pub.get_subscription_count() > 0, 20.0)
    start = time.monotonic()
    graph.trajectory_pub.publish(msg)
    # documented limit: sim_node's max_trajectory_points (default 10 000); longer is rejected
    expected = (
        f'following a trajectory of {n} points'
        if n <= 10_000
        else 'more than max_trajectory_points = 10000'
    )
    accepted = graph.spin_until(lambda: expected in graph.sim.log_text()[mark:], 60.0)
    seconds = time.monotonic() - start
    graph.spin_until(lambda: False, 1.0)
    growth = _report(f'trajectory of {n} points', graph.sim, before, seconds)
    gaps = np.diff(graph.state_times[max(count - 1, 0) :])
    largest_gap = float(gaps.max()) if len(gaps) else math.inf
    print(f'[limits]   largest /joint_states gap {largest_gap:.2f} s')
    assert accepted, graph.sim.log_text()[mark:][-2000:]
    assert graph.sim.alive()
    assert growth < RSS_GROWTH_MB
    graph.trajectory_pub.publish(JointTrajectory(joint_names=list(ARM_JOINTS)))  # stop
    assert graph.call(graph.reset, ResetScene.Request(scenario='s1'), 30.0)[0].success
    assert largest_gap < MAX_STATE_GAP_S, f'/joint_states stopped for {largest_gap:.2f} s'
