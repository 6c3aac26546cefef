"""Limits: huge requests, a 200-object scene and a 100 000-point trajectory, in time and memory.

One sim + motion planner graph for the module (``GRAPH_NODES``; the ``graph`` fixture of
conftest.py). Each case measures the answer time and the resident memory (VmRSS from
``/proc/<pid>/status``, summed over the node's process tree) of the node before and after, and
prints the figures (``-s``) for docs/RELIABILITY.md. No node documents a size limit on these
inputs, so the assertions are the bounds a user may expect: an answer in seconds, RSS growth
below 150 MB, the sim publishing /joint_states without a long gap, and answers (messages, logs)
that stay short when the request is huge.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest
from qtree_benchmarks.cli.load_test import (
    rss_mb,  # one RSS reader for the load script and these tests
)
from qtree_node_support.orchestration import NodeProcess

if TYPE_CHECKING:
    from conftest import ClientGraph

pytestmark = pytest.mark.timeout(300)

RSS_GROWTH_MB = 150.0  # largest acceptable RSS growth of a node for one huge input [MB]
MESSAGE_CHARS = 2000  # longest acceptable answer message [characters]
MAX_STATE_GAP_S = 0.5  # longest acceptable /joint_states silence of the sim (25 periods) [s]


GRAPH_NODES = {  # executable -> (package, ROS node name, start-up parameters); conftest.py
    'sim_node': ('jaco2_sim', 'jaco2_sim', {'sim_rate_hz': 50.0}),
    'motion_planner_node': ('stpik_motion_planner', 'motion_planner', {}),
}
SIM, PLANNER = 'sim_node', 'motion_planner_node'


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
def test_huge_relocated_list(graph: ClientGraph, label, object_id, relocated, code) -> None:
    from qtree_msgs.srv import RelocateObject

    before = rss_mb(graph.nodes[PLANNER].process.pid)
    mark = len(graph.nodes[PLANNER].log_text())
    request = RelocateObject.Request(object_id=object_id, relocated_ids=relocated)
    response, seconds = graph.timed_call(graph.relocate_client, request, 30.0)
    growth = _report(f'RelocateObject with {label}', graph.nodes[PLANNER], before, seconds)
    logged = graph.nodes[PLANNER].log_text()[mark:]
    print(f'[limits]   message {len(response.message)} chars, log {len(logged)} chars')
    assert response.reason == code, response.message[:300]
    assert seconds < 5.0 and growth < RSS_GROWTH_MB
    ok, _ = graph.timed_call(graph.relocate_client, RelocateObject.Request(object_id='O2'), 30.0)
    assert ok.feasible, ok.message
    assert len(response.message) <= MESSAGE_CHARS, (
        f'the answer echoes the request: {len(response.message)} chars'
    )
    assert len(logged) <= 10 * MESSAGE_CHARS, f'one request logged {len(logged)} chars'


def test_scene_with_200_objects(graph: ClientGraph, tmp_path: Path) -> None:
    from qtree_msgs.srv import RelocateObject, ResetScene
    from qtree_scene.generator import generate_clutter
    from qtree_scene.scenario import dump_scenario

    path = tmp_path / 'clutter200.yaml'
    path.write_text(dump_scenario(generate_clutter(200, 0.3, seed=0)))
    sim_before, mp_before = (
        rss_mb(graph.nodes[SIM].process.pid),
        rss_mb(graph.nodes[PLANNER].process.pid),
    )
    mark = len(graph.nodes[PLANNER].log_text())
    response, seconds = graph.timed_call(
        graph.reset_client, ResetScene.Request(scenario=str(path)), 30.0
    )
    assert response.success, response.message
    assert graph.spin_until(lambda: len(graph.scene.objects) == 202, 10.0)
    start = time.monotonic()
    assert graph.spin_until(
        lambda: 'planner rebuilt' in graph.nodes[PLANNER].log_text()[mark:], 30.0
    )
    rebuilt_s = time.monotonic() - start + seconds
    _report('reset_scene to 200 objects', graph.nodes[SIM], sim_before, seconds)
    times = {}
    for object_id, relocated in [
        ('O1', []),
        ('O2', ['O1']),
        ('T', []),
        ('T', [f'O{i}' for i in range(1, 201)]),
    ]:
        request = RelocateObject.Request(object_id=object_id, relocated_ids=relocated)
        answer, times[object_id, len(relocated)] = graph.timed_call(
            graph.relocate_client, request, 60.0
        )
        assert answer.reason in {0, *range(201, 210), 301}, answer.message
    growth = _report(
        f'200 objects: planner rebuilt in {rebuilt_s:.2f} s, 4 checks',
        graph.nodes[PLANNER],
        mp_before,
        sum(times.values()),
    )
    print(f'[limits]   check times [s]: { {k: round(v, 3) for k, v in times.items()} }')
    assert max(times.values()) < 5.0 + 5.0  # time_limit_s + transport
    assert growth < RSS_GROWTH_MB
    assert graph.timed_call(graph.reset_client, ResetScene.Request(scenario='s1'), 30.0)[0].success
    assert graph.spin_until(lambda: len(graph.scene.objects) == 7, 10.0)


@pytest.mark.parametrize('n', [10_000, 100_000])
def test_long_trajectory(graph: ClientGraph, n: int) -> None:
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
    before = rss_mb(graph.nodes[SIM].process.pid)
    mark = len(graph.nodes[SIM].log_text())
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
    accepted = graph.spin_until(lambda: expected in graph.nodes[SIM].log_text()[mark:], 60.0)
    seconds = time.monotonic() - start
    graph.spin_until(lambda: False, 1.0)
    growth = _report(f'trajectory of {n} points', graph.nodes[SIM], before, seconds)
    gaps = np.diff(graph.state_times[max(count - 1, 0) :])
    largest_gap = float(gaps.max()) if len(gaps) else math.inf
    print(f'[limits]   largest /joint_states gap {largest_gap:.2f} s')
    assert accepted, graph.nodes[SIM].log_text()[mark:][-2000:]
    assert graph.nodes[SIM].alive()
    assert growth < RSS_GROWTH_MB
    graph.trajectory_pub.publish(JointTrajectory(joint_names=list(ARM_JOINTS)))  # stop
    assert graph.timed_call(graph.reset_client, ResetScene.Request(scenario='s1'), 30.0)[0].success
    assert largest_gap < MAX_STATE_GAP_S, f'/joint_states stopped for {largest_gap:.2f} s'
