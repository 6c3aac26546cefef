"""A loaded motion planner never makes the task planner learn a wrong "infeasible" edge (#18).

Ten other clients keep more requests in flight than the planner queues (MAX_WAITING_PLANS = 8),
all of them new plannings on s3 (15 obstacles: no cache hits), while a RetrieveTarget goal
trains. Busy answers (PLANNER_BUSY) and planning time-outs are asked again with back-off; the
goal ends with a result or aborts with MOTION_PLANNER_UNAVAILABLE after the bound. Either way,
every edge of the learned tree with reward -1 is infeasible when the idle planner is asked again.
Before the fix busy answers came as TIMEOUT and were learned as -1 (5 of 14 "infeasible" edges
were feasible).
"""

from __future__ import annotations

import random
from typing import Any

import pytest

pytestmark = pytest.mark.timeout(600)

LOAD_CLIENTS = 10
OBSTACLES = [f'O{i}' for i in range(1, 16)]


class Load:
    """``LOAD_CLIENTS`` clients, each sending a new uncached planning as soon as answered."""

    def __init__(self, ros_node: Any) -> None:
        from qtree_msgs.srv import RelocateObject
        from qtree_node_support.qos import SERVICE_QOS

        self.rng = random.Random(7)
        self.clients = [
            ros_node.create_client(RelocateObject, '/relocate_object', qos_profile=SERVICE_QOS)
            for _ in range(LOAD_CLIENTS)
        ]
        ros_node.wait_matched(*self.clients)
        self.futures: list[Any] = [None] * LOAD_CLIENTS
        self.busy = self.answered = 0
        self.running = True

    def _request(self) -> Any:
        from qtree_msgs.srv import RelocateObject

        object_id = self.rng.choice(['T', *OBSTACLES])
        others = [o for o in OBSTACLES if o != object_id]
        relocated = self.rng.sample(others, self.rng.randint(1, 7))
        return RelocateObject.Request(object_id=object_id, relocated_ids=relocated)

    def pump(self) -> None:
        """Resend for every answered client (call from the spin loop)."""
        for i, future in enumerate(self.futures):
            if future is not None and not future.done():
                continue
            if future is not None:
                self.answered += 1
                self.busy += future.result().reason == 303
            if self.running:
                self.futures[i] = self.clients[i].call_async(self._request())


def test_loaded_planner_never_yields_a_wrong_infeasible_edge(launch: Any, ros_node: Any) -> None:
    from qtree_msgs.action import RetrieveTarget
    from qtree_msgs.msg import QTree
    from qtree_msgs.srv import RelocateObject
    from rclpy.action import ActionClient
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's3', 'sim_rate_hz': 50.0})
    mp = launch('stpik_motion_planner', 'motion_planner_node')
    tp = launch('qtree_task_planner', 'task_planner_node')
    for node in (sim, mp, tp):
        node.wait_for_log('ready', 90.0)
    mp.wait_for_log('planner rebuilt', 60.0)
    trees: list[Any] = []
    latched = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    ros_node.create_subscription(QTree, '/qtree', trees.append, latched)
    action = ActionClient(ros_node, RetrieveTarget, '/retrieve_target')
    ros_node.wait_matched(action)
    ros_node.wait_action_answering(action)  # a goal sent earlier may be lost
    load = Load(ros_node)
    ros_node.spin_until(lambda: load.pump() or load.busy > 5, 60.0)
    assert load.busy > 5, 'the load did not fill the planner queue'

    goal = RetrieveTarget.Goal(policy='H-EG', seed=1, max_episodes=25, steady_episodes=1000)
    sent = action.send_goal_async(goal)
    assert ros_node.spin_until(lambda: load.pump() or sent.done(), 30.0)
    done = sent.result().get_result_async()
    assert ros_node.spin_until(lambda: load.pump() or done.done(), 400.0), 'no result'
    load.running = False
    ros_node.spin_until(lambda: load.pump() or all(f.done() for f in load.futures), 60.0)
    result = done.result().result
    print(
        f'\n[busy] load: {load.answered} answers, {load.busy} PLANNER_BUSY; goal: '
        f'{result.episodes} episodes, {result.mp_calls} MP calls, '
        f'{result.planner_retries} retries, error_code {result.error_code}: {result.message}'
    )
    Result = RetrieveTarget.Result
    assert result.error_code in {
        Result.SUCCESS,
        Result.NO_SOLUTION,
        Result.MOTION_PLANNER_UNAVAILABLE,
    }
    if result.error_code == Result.MOTION_PLANNER_UNAVAILABLE:
        assert 'gave up after' in result.message, result.message
    assert result.planner_retries > 0, 'the goal never met a busy planner'

    assert ros_node.spin_until(lambda: trees and trees[-1].episode == result.episodes, 10.0)
    tree = trees[-1]
    infeasible = [(tree.node_sequences[e.parent], e.object_id) for e in tree.edges if e.reward < 0]
    client = load.clients[0]
    wrong = []
    for parent, object_id in infeasible:
        relocated = [s for s in parent.split(',') if s]
        request = RelocateObject.Request(object_id=object_id, relocated_ids=relocated)
        idle = ros_node.call(client, request, 60.0)
        assert idle.reason != 303, 'the idle planner is busy'
        if idle.feasible:
            wrong.append((relocated, object_id))
    print(f'[busy] {len(tree.edges)} edges, {len(infeasible)} infeasible, {len(wrong)} wrong')
    assert not wrong, f'edges learned infeasible that the idle planner finds feasible: {wrong}'
