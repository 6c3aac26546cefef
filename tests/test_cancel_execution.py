"""Cancel a RetrieveTarget goal while the arm executes the learned sequence (#18).

Before the fix the cancel was accepted and ignored: all relocations still ran and the goal
SUCCEEDED. Now the arm stops within 1 s of the cancel (no /joint_states motion afterwards), the
goal ends CANCELED, and ``executed_ids`` lists the relocations finished before the cancel (the
sim's /scene agrees).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.timeout(600)

STOP_BOUND_S = 1.0  # the arm is still within this time after the cancel [s]
STILL_RAD = 1e-4  # largest joint change after the stop [rad]


def test_cancel_during_execution_stops_the_arm(launch: Any, ros_node: Any) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget
    from qtree_msgs.msg import ObjectState, Scene
    from rclpy.action import ActionClient
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    nodes = [
        launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1', 'sim_rate_hz': 100.0}),
        # a generous planning limit: on the loaded shared machine 2 s planning TIMEOUTs (asked
        # again, never learned as infeasible) could exhaust the back-off and abort the training
        launch('stpik_motion_planner', 'motion_planner_node', parameters={'time_limit_s': 30.0}),
        launch('qtree_task_planner', 'task_planner_node', parameters={'execute_timeout_s': 240.0}),
    ]
    for node in nodes:
        node.wait_for_log('ready', timeout_s=90.0)
    states: list[tuple[float, np.ndarray]] = []
    scenes: list[Any] = []
    latched = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    joint_states = ros_node.create_subscription(
        JointState,
        '/joint_states',
        lambda m: states.append((time.monotonic(), np.array(m.position[:7]))),
        100,
    )
    ros_node.create_subscription(Scene, '/scene', scenes.append, latched)
    client = ActionClient(ros_node, RetrieveTarget, '/retrieve_target')
    ros_node.wait_matched(client, joint_states)
    ros_node.wait_action_answering(client)  # a goal sent earlier may be lost
    goal = RetrieveTarget.Goal(policy='H-EG-SET', seed=0, execute=True)
    sent = client.send_goal_async(goal)
    assert ros_node.spin_until(sent.done, 30.0) and sent.result().accepted
    handle = sent.result()
    done = handle.get_result_async()

    def moving() -> bool:  # the arm moved in the last 0.1 s: the execution has started
        recent = [q for t, q in states if t > time.monotonic() - 0.1]
        return len(recent) > 2 and float(np.max(np.abs(recent[-1] - recent[0]))) > 1e-3

    ros_node.spin_until(lambda: moving() or done.done(), 400.0)
    assert not done.done(), f'the goal ended before executing: {done.result().result.message}'
    assert moving(), 'the execution never started'
    ros_node.spin_until(lambda: False, 1.0)  # well inside the first relocation
    cancel = handle.cancel_goal_async()
    canceled_at = time.monotonic()
    assert ros_node.spin_until(cancel.done, 10.0) and cancel.result().goals_canceling
    ros_node.spin_until(lambda: time.monotonic() > canceled_at + STOP_BOUND_S, 5.0)
    q_stop = states[-1][1]
    ros_node.spin_until(lambda: False, 2.0)  # the arm must not move any more
    drift = float(np.max(np.abs(states[-1][1] - q_stop)))
    moved = [t for (t, q), (_, p) in zip(states[1:], states[:-1], strict=False) if np.any(q != p)]
    last_motion_s = max(0.0, max(moved, default=canceled_at) - canceled_at)
    print(f'\n[cancel] last arm motion {last_motion_s:.3f} s after the cancel (bound 1 s)')
    assert drift < STILL_RAD, f'the arm still moved {drift:.4f} rad more than 1 s after cancel'

    assert ros_node.spin_until(done.done, 30.0), 'no result after the cancel'
    status, result = done.result().status, done.result().result
    assert status == GoalStatus.STATUS_CANCELED, result.message
    assert result.error_code == RetrieveTarget.Result.CANCELED
    assert not result.success and not result.executed
    assert 'canceled during the relocation' in result.message, result.message
    assert list(result.executed_ids) == list(result.sequence[: len(result.executed_ids)])
    assert len(result.executed_ids) < len(result.sequence)
    relocated = {o.id for o in scenes[-1].objects if o.status == ObjectState.STATUS_RELOCATED}
    assert set(result.executed_ids) <= relocated
