"""Cross-process tests of the task planner: real sim, motion planner and task planner nodes.

A RetrieveTarget goal on s1 learns a sequence of the exact optimal length (checked against the
exact BFS over sets on the in-process motion planner), MP calls equal the tree's edges, feedback
and per-episode statistics arrive; bad goals are aborted with a message naming the field and the
node keeps serving; cancel works; a missing or dying motion planner aborts with
MOTION_PLANNER_UNAVAILABLE and keeps the statistics so far.
"""

from __future__ import annotations

import functools
import time
from typing import Any

import pytest

pytestmark = pytest.mark.timeout(400)

READY_TIMEOUT_S = 90.0


@functools.cache
def exact_s1() -> Any:
    """Exact optimum of s1 from the real in-process planner (shared by the tests)."""
    from qtree_scene.scenario import load_scenario
    from qtree_task_planner.exact import solve_exact
    from qtree_task_planner.oracle import MotionPlannerOracle
    from stpik_motion_planner.config import PlannerConfig
    from stpik_motion_planner.planner import MotionPlanner

    scenario = load_scenario('s1')
    # a 300 s planning limit: a loaded machine's TIMEOUT must not become an infeasible edge of
    # the reference (a soak run found s1's optimum as 5 instead of 4, #18)
    planner = MotionPlanner(scenario, PlannerConfig(time_limit_s=300.0))
    oracle = MotionPlannerOracle(scenario, planner=planner)
    return solve_exact(tuple(o.id for o in scenario.obstacles), scenario.target.id, oracle)


def start_graph(launch, *, planner: bool = True, **tp_params: Any) -> dict:
    """Start sim (s1), motion planner and task planner; wait until each is ready."""
    nodes = {'sim': launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1'})}
    if planner:
        nodes['mp'] = launch('stpik_motion_planner', 'motion_planner_node')
    nodes['tp'] = launch('qtree_task_planner', 'task_planner_node', parameters=tp_params)
    for node in nodes.values():
        node.wait_for_log('ready', timeout_s=READY_TIMEOUT_S)
    return nodes


class GoalRunner:
    """Send RetrieveTarget goals from the test's rclpy node and collect everything."""

    def __init__(self, ros_node: Any) -> None:
        from qtree_msgs.action import RetrieveTarget
        from qtree_msgs.msg import QTree, TrainingStats
        from rclpy.action import ActionClient
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        self.node = ros_node
        self.Goal = RetrieveTarget.Goal
        self.client = ActionClient(ros_node, RetrieveTarget, '/retrieve_target')
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.stats: list[Any] = []
        self.trees: list[Any] = []
        self.feedback: list[Any] = []
        stats = ros_node.create_subscription(
            TrainingStats, '/training_stats', self.stats.append, 1000
        )
        ros_node.create_subscription(QTree, '/qtree', self.trees.append, latched)
        ros_node.wait_action_answering(self.client)  # a goal sent earlier may be lost
        ros_node.wait_matched(stats)  # every episode's /training_stats is counted

    def send(self, **fields: Any) -> Any:
        future = self.client.send_goal_async(
            self.Goal(**fields), feedback_callback=lambda m: self.feedback.append(m.feedback)
        )
        assert self.node.spin_until(future.done, 30.0), 'goal not answered'
        handle = future.result()
        assert handle.accepted
        return handle

    def result(self, handle: Any, timeout_s: float = 300.0) -> tuple[int, Any]:
        future = handle.get_result_async()
        assert self.node.spin_until(future.done, timeout_s), 'no result in time'
        return future.result().status, future.result().result


def test_heg_learns_the_exact_optimum_on_s1(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget

    start_graph(launch)
    runner = GoalRunner(ros_node)
    status, result = runner.result(runner.send(policy='H-EG', seed=3, feedback_every=5))
    exact = exact_s1()
    assert exact.solvable, 'the s1 scenario has no feasible sequence'
    assert status == GoalStatus.STATUS_SUCCEEDED, result.message
    assert result.error_code == RetrieveTarget.Result.SUCCESS and result.success
    assert len(result.sequence) == exact.level
    assert result.sequence[-1] == exact.sequence[-1]  # the target
    assert result.converged and 0 < result.episodes <= 5000
    assert result.first_optimal_episode == -1  # the node does not know the optimal level
    assert 1 <= result.first_learned_level_episode <= result.episodes
    assert result.extraction == 'eq19'
    assert 0 < result.planner_runs <= result.mp_calls
    ros_node.spin_until(lambda: len(runner.stats) >= result.episodes, 10.0)
    assert len(runner.stats) == result.episodes  # one /training_stats per episode
    assert runner.stats[-1].mp_calls == runner.stats[-1].edges == result.mp_calls
    assert ros_node.spin_until(
        lambda: runner.trees and runner.trees[-1].episode == result.episodes, 10.0
    )
    assert len(runner.trees[-1].edges) == result.mp_calls  # MP calls == tree edges
    # feedback every 5 episodes (the action's feedback topic keeps the last 10: bursts may drop)
    episodes = [f.episode for f in runner.feedback]
    assert episodes and episodes == sorted(set(episodes)), episodes
    assert all(e % 5 == 0 and e <= result.episodes for e in episodes)
    assert runner.feedback[-1].mp_calls <= result.mp_calls


def test_bad_goals_are_explained_and_the_node_keeps_serving(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget

    nodes = start_graph(launch)
    runner = GoalRunner(ros_node)
    for fields, word in [
        ({'policy': 'SARSA'}, 'policy'),
        ({'alpha': 0.0}, 'alpha'),
        ({'gamma': 1.5}, 'gamma'),
        ({'epsilon0': 0.1, 'epsilon_min': 0.5}, 'epsilon_min'),
        ({'max_episodes': 0}, 'max_episodes'),
        ({'beta': -1.0}, 'beta'),
        ({'feedback_every': 0}, 'feedback_every'),
    ]:
        status, result = runner.result(runner.send(**fields), 30.0)
        assert status == GoalStatus.STATUS_ABORTED
        assert result.error_code == RetrieveTarget.Result.INVALID_GOAL
        assert word in result.message and not result.success
    status, result = runner.result(runner.send(policy='H-EG-SET', seed=1))
    assert status == GoalStatus.STATUS_SUCCEEDED, result.message
    assert len(result.sequence) == exact_s1().level
    assert nodes['tp'].alive()


def test_cancel_stops_training(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget

    start_graph(launch)
    runner = GoalRunner(ros_node)
    handle = runner.send(policy='LRND', seed=2, steady_episodes=1_000_000, feedback_every=1)
    assert ros_node.spin_until(lambda: len(runner.feedback) >= 3, 120.0), 'no feedback'
    status, busy = runner.result(runner.send(policy='H-EG'), 30.0)  # one goal at a time
    assert status == GoalStatus.STATUS_ABORTED and 'busy' in busy.message
    cancel = handle.cancel_goal_async()
    assert ros_node.spin_until(cancel.done, 10.0)
    status, result = runner.result(handle, 60.0)
    assert status == GoalStatus.STATUS_CANCELED
    assert result.error_code == RetrieveTarget.Result.CANCELED
    assert 3 <= result.episodes < 5000 and result.mp_calls > 0


DEAD_PLANNER_REPORT_S = 5.0  # one 3 s time-out + goal delivery; two time-outs take > 6 s [s]


def test_motion_planner_absent_or_dying(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget

    code = RetrieveTarget.Result.MOTION_PLANNER_UNAVAILABLE
    nodes = start_graph(launch, planner=False, planner_wait_s=5.0, planner_timeout_s=3.0)
    runner = GoalRunner(ros_node)
    status, result = runner.result(runner.send(policy='H-EG'), 30.0)
    assert status == GoalStatus.STATUS_ABORTED and result.error_code == code
    assert '/relocate_object' in result.message
    # the planner comes up, then dies in the middle of a training: statistics so far are kept
    mp = launch('stpik_motion_planner', 'motion_planner_node')
    mp.wait_for_log('ready', timeout_s=READY_TIMEOUT_S)
    # Its first /scene comes 2-3 s after 'ready' (discovery): a request before it waits for the
    # scene, and with planner_timeout_s=3 s both tries ran out (suite of 1e9c6b5: 'no feedback').
    mp.wait_for_log('planner rebuilt', timeout_s=READY_TIMEOUT_S)
    handle = runner.send(policy='LRND', seed=4, steady_episodes=1_000_000, feedback_every=1)
    assert ros_node.spin_until(lambda: len(runner.feedback) >= 2, 120.0), 'no feedback'
    killed = time.monotonic()
    mp.kill()
    status, result = runner.result(handle, 60.0)
    reported_s = time.monotonic() - killed
    print(f'dead planner reported in {reported_s:.2f} s')
    assert status == GoalStatus.STATUS_ABORTED and result.error_code == code
    assert '/relocate_object: no answer in 3.0 s' in result.message
    # one 3 s answer time-out (#26: was two, 6.1 s and more); see docs/RELIABILITY.md
    assert reported_s < DEAD_PLANNER_REPORT_S, reported_s
    assert result.episodes >= 2 and result.mp_calls > 0
    assert nodes['tp'].alive()
