"""Bursts of 50 concurrent requests from 50 clients: every one is answered (#18).

With rclpy's default service QoS (KEEP_LAST, depth 10) requests and replies beyond the history
depth were dropped silently and their clients waited forever (20 requests at once: 10 answered).
Servers and clients now use ``qtree_node_support.qos.SERVICE_QOS`` (KEEP_ALL, reliable).
"""

from __future__ import annotations

import itertools
from typing import Any

import pytest

pytestmark = pytest.mark.timeout(400)

BURST = 50
ANSWER_S = 120.0  # longest wait for the whole burst on the shared 2-core machine [s]


def _relocate_requests(n: int) -> list[Any]:
    """``n`` distinct requests on s1: plannings (cache misses), cache hits and bad requests."""
    from qtree_msgs.srv import RelocateObject

    obstacles = ['O1', 'O2', 'O3', 'O4', 'O5']
    subsets = [
        list(c) for k in range(len(obstacles) + 1) for c in itertools.combinations(obstacles, k)
    ]
    requests = []
    for i in range(n):
        if i % 5 == 4:
            requests.append(RelocateObject.Request(object_id=f'ghost{i}'))  # 101 at once
        else:
            relocated = subsets[i % len(subsets)]
            requests.append(RelocateObject.Request(object_id='T', relocated_ids=relocated))
    return requests


def _burst(ros_node: Any, clients: list[Any], requests: list[Any]) -> list[Any]:
    """Send one request per client at once (after every client matched); the answers."""
    ros_node.wait_matched(*clients, timeout_s=60.0)
    futures = [c.call_async(r) for c, r in zip(clients, requests, strict=True)]
    ros_node.spin_until(lambda: all(f.done() for f in futures), ANSWER_S)
    lost = [i for i, f in enumerate(futures) if not f.done()]
    assert not lost, f'{len(lost)} of {len(futures)} requests never answered: {lost}'
    return [f.result() for f in futures]


def test_50_relocate_and_50_reset_requests_are_all_answered(launch: Any, ros_node: Any) -> None:
    from qtree_msgs.srv import RelocateObject, ResetScene
    from qtree_node_support.qos import SERVICE_QOS

    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1', 'sim_rate_hz': 50.0})
    mp = launch('stpik_motion_planner', 'motion_planner_node')
    sim.wait_for_log('ready', 90.0)
    mp.wait_for_log('planner rebuilt', 90.0)
    relocate = [
        ros_node.create_client(RelocateObject, '/relocate_object', qos_profile=SERVICE_QOS)
        for _ in range(BURST)
    ]
    answers = _burst(ros_node, relocate, _relocate_requests(BURST))
    codes = {a.reason for a in answers}
    allowed = {0, 101, 201, 202, 203, 204, 205, 301, 303}  # 303: PLANNER_BUSY
    assert codes <= allowed, codes
    assert sum(a.reason == 101 for a in answers) == BURST // 5
    reset = [
        ros_node.create_client(ResetScene, '/jaco2_sim/reset_scene', qos_profile=SERVICE_QOS)
        for _ in range(BURST)
    ]
    answers = _burst(ros_node, reset, [ResetScene.Request(scenario='s1')] * BURST)
    assert all(a.success for a in answers)
    assert sim.alive() and mp.alive()


def test_50_goals_from_50_action_clients_are_all_answered(launch: Any, ros_node: Any) -> None:
    from qtree_msgs.action import RetrieveTarget
    from qtree_node_support.qos import action_client_qos
    from rclpy.action import ActionClient

    tp = launch('qtree_task_planner', 'task_planner_node', parameters={'scene_wait_s': 0.5})
    tp.wait_for_log('ready', 90.0)
    clients = [
        ActionClient(ros_node, RetrieveTarget, '/retrieve_target', **action_client_qos())
        for _ in range(BURST)
    ]
    ros_node.wait_matched(*clients, timeout_s=60.0)
    probe = RetrieveTarget.Goal(policy='__probe__')  # INVALID_GOAL at once
    for client in clients:  # both directions matched: a lost reply is discovery, not the QoS
        ros_node.wait_goal_answering(client, probe)
    sent = [c.send_goal_async(RetrieveTarget.Goal(max_episodes=1)) for c in clients]
    ros_node.spin_until(lambda: all(f.done() for f in sent), ANSWER_S)
    assert sum(f.done() for f in sent) == BURST, 'goal requests lost'
    results = [f.result().get_result_async() for f in sent]
    ros_node.spin_until(lambda: all(f.done() for f in results), ANSWER_S)
    assert sum(f.done() for f in results) == BURST, 'results lost'
    codes = {f.result().result.error_code for f in results}  # no sim: no /scene, or busy
    assert codes <= {
        RetrieveTarget.Result.MOTION_PLANNER_UNAVAILABLE,
        RetrieveTarget.Result.INVALID_GOAL,
    }
    assert tp.alive()
