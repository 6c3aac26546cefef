"""Fault injection: SIGKILL one node of a running graph; the others end cleanly and say why.

(a) The motion planner dies in the middle of a training on s2: the task planner aborts the goal
    with MOTION_PLANNER_UNAVAILABLE, a message and the statistics so far, within
    ``planner_timeout_s`` plus the time to the next new tree edge; the recorder, stopped with
    SIGINT afterwards, leaves an MCAP that rosbags reads, with every /training_stats message up
    to the end of the goal.
(b) The simulator dies while the motion planner executes a relocation: the planner answers
    EXECUTION_FAILED within ``joint_state_timeout_s`` (no /joint_states) plus transport, then
    keeps serving feasibility checks.
(c) A SIGKILLed recorder is covered by tests/test_recording.py
    (``test_sigkilled_recorder_leaves_a_readable_file``), so it is not repeated here.

The measured recovery times are printed (``-s``) for docs/RELIABILITY.md.
"""

from __future__ import annotations

import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.timeout(300)

READY_S = 90.0
PLANNER_TIMEOUT_S = 5.0  # task planner: wait for one RelocateObject answer [s]
EXECUTION_TIMEOUT_S = 5.0  # motion planner: extra wait for the sim to reach a segment end [s]
JOINT_STATE_TIMEOUT_S = 3.0  # motion planner default: /joint_states silence failing execution [s]


def test_motion_planner_killed_mid_training(launch: Any, ros_node: Any, tmp_path: Path) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget
    from rclpy.action import ActionClient
    from rosbags.highlevel import AnyReader

    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's2', 'sim_rate_hz': 50.0})
    mp = launch('stpik_motion_planner', 'motion_planner_node')
    tp = launch(
        'qtree_task_planner',
        'task_planner_node',
        parameters={'planner_timeout_s': PLANNER_TIMEOUT_S},
    )
    recorder = launch(
        'qtree_recorder',
        'recorder_node',
        parameters={
            'output_dir': str(tmp_path),
            'file_name': 'fault.mcap',
            'scenario': 's2',
            'discovery_period_s': 0.2,
        },
    )
    for node in (sim, mp, tp, recorder):
        node.wait_for_log('ready', READY_S)
    mp.wait_for_log('planner rebuilt', 30.0)
    for topic in ('/training_stats', '/motion_planner/events', '/scene'):
        recorder.wait_for_log(f'recording {topic} ', 20.0)  # subscribed before the goal

    client = ActionClient(ros_node, RetrieveTarget, '/retrieve_target')
    ros_node.wait_action_answering(client)  # a goal sent earlier may be lost
    feedback: list[Any] = []
    goal = RetrieveTarget.Goal(
        policy='LRND', seed=4, max_episodes=5000, steady_episodes=1_000_000, feedback_every=1
    )
    sent = client.send_goal_async(goal, feedback_callback=lambda m: feedback.append(m.feedback))
    assert ros_node.spin_until(sent.done, 30.0) and sent.result().accepted
    handle = sent.result()
    training = ros_node.spin_until(
        lambda: bool(feedback) and feedback[-1].episode >= 20 and feedback[-1].mp_calls >= 10,
        120.0,
    )
    assert training, 'the training did not get going'
    seen = feedback[-1]
    mp.kill()
    killed_at = time.monotonic()
    result_future = handle.get_result_async()
    assert ros_node.spin_until(result_future.done, PLANNER_TIMEOUT_S + 60.0), 'goal never ended'
    recovery_s = time.monotonic() - killed_at
    status, result = result_future.result().status, result_future.result().result
    print(
        f'\n[faults] motion planner killed at episode {seen.episode} ({seen.mp_calls} MP calls):'
        f' goal ended after {recovery_s:.2f} s at episode {result.episodes}: {result.message}'
    )
    assert status == GoalStatus.STATUS_ABORTED
    assert not result.success
    assert result.error_code == RetrieveTarget.Result.MOTION_PLANNER_UNAVAILABLE
    assert 'no answer' in result.message and '5.0 s' in result.message, result.message
    assert result.episodes >= seen.episode > 0 and result.mp_calls >= seen.mp_calls > 0
    assert recovery_s < PLANNER_TIMEOUT_S + 30.0
    assert tp.alive() and sim.alive()

    assert recorder.stop() == 0, recorder.log_text()[-2000:]
    path = tmp_path / 'fault.mcap'
    counts: Counter[str] = Counter()
    episodes: list[int] = []
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            counts[connection.topic] += 1
            if connection.topic == '/training_stats':
                episodes.append(reader.deserialize(raw, connection.msgtype).episode)
    assert counts['/scene'] >= 1 and counts['/joint_states'] > 50
    assert episodes == list(range(1, len(episodes) + 1)), 'a /training_stats message was lost'
    assert episodes[-1] == result.episodes, (episodes[-1], result.episodes)
    assert counts['/motion_planner/events'] >= seen.mp_calls


def test_sim_killed_mid_execution(launch: Any, ros_node: Any) -> None:
    from qtree_msgs.srv import RelocateObject
    from sensor_msgs.msg import JointState

    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1', 'sim_rate_hz': 50.0})
    mp = launch(
        'stpik_motion_planner',
        'motion_planner_node',
        parameters={
            'execution_timeout_s': EXECUTION_TIMEOUT_S,
            'joint_state_timeout_s': JOINT_STATE_TIMEOUT_S,
        },
    )
    sim.wait_for_log('ready', READY_S)
    mp.wait_for_log('ready', READY_S)
    mp.wait_for_log('planner rebuilt', 30.0)
    states: list[np.ndarray] = []
    ros_node.create_subscription(
        JointState, '/joint_states', lambda m: states.append(np.array(m.position[:7])), 10
    )
    client = ros_node.create_client(RelocateObject, '/relocate_object')
    plan = ros_node.call(client, RelocateObject.Request(object_id='O2'))
    assert plan.feasible, plan.message
    last = plan.trajectory.points[-1].time_from_start
    duration_s = last.sec + 1e-9 * last.nanosec  # whole motion: bounds every segment [s]

    future = client.call_async(RelocateObject.Request(object_id='O2', execute=True))
    assert ros_node.spin_until(lambda: len(states) > 5, 10.0)
    start = states[-1]
    moving = ros_node.spin_until(lambda: np.max(np.abs(states[-1] - start)) > 0.01, 10.0)
    assert moving, 'the arm never moved'
    sim.kill()
    killed_at = time.monotonic()
    bound_s = JOINT_STATE_TIMEOUT_S + 5.0  # noticed from /joint_states, not the segment timeout
    assert ros_node.spin_until(future.done, bound_s), f'no answer within {bound_s:.1f} s'
    recovery_s = time.monotonic() - killed_at
    response = future.result()
    print(
        f'\n[faults] sim killed mid-execution: EXECUTION_FAILED after {recovery_s:.2f} s '
        f'(execution_timeout_s={EXECUTION_TIMEOUT_S}, motion {duration_s:.2f} s): '
        f'{response.message}'
    )
    assert not response.feasible
    assert response.reason == RelocateObject.Response.EXECUTION_FAILED, response.message
    # open loop: 'did not reach sample N: ...', closed loop: 'closed loop stopped: ...'
    assert 'did not reach' in response.message or 'closed loop stopped' in response.message
    assert 'stopped publishing' in response.message
    # still serving: a feasibility check on the scene it had (O2 standing: it blocks O3, the
    # next object of s1's chain), and a bad request
    again = ros_node.call(client, RelocateObject.Request(object_id='O3'), 30.0)
    assert again.reason == RelocateObject.Response.NO_CARTESIAN_PATH, again.message
    assert list(again.blocking_ids) == ['O2'], again.message
    bad = ros_node.call(client, RelocateObject.Request(object_id='ghost'), 30.0)
    assert bad.reason == RelocateObject.Response.UNKNOWN_OBJECT
    assert mp.alive()
