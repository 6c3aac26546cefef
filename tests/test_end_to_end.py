"""End to end on s1: learn a sequence, execute it on the simulated arm, check the sim's /scene.

Real nodes only: jaco2_sim, the STPIK motion planner and the task planner. After a
RetrieveTarget goal with ``execute=true``, every object of the learned sequence (the target last)
must be reported RELOCATED on /scene, and the obstacles not in the sequence still IN_CLUTTER.
"""

from __future__ import annotations

from typing import Any

import pytest

pytestmark = pytest.mark.timeout(600)


def test_learn_and_execute_on_s1(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus
    from qtree_msgs.action import RetrieveTarget
    from qtree_msgs.msg import ObjectState, Scene
    from rclpy.action import ActionClient
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    nodes = [
        launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1'}),
        launch('stpik_motion_planner', 'motion_planner_node', parameters={'velocity_scale': 1.0}),
        launch('qtree_task_planner', 'task_planner_node', parameters={'execute_timeout_s': 240.0}),
    ]
    for node in nodes:
        node.wait_for_log('ready', timeout_s=90.0)
    latched = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    scenes: list[Any] = []
    ros_node.create_subscription(Scene, '/scene', scenes.append, latched)
    client = ActionClient(ros_node, RetrieveTarget, '/retrieve_target')
    ros_node.wait_action_answering(client)  # a goal sent earlier may be lost
    assert ros_node.spin_until(lambda: bool(scenes), 20.0), 'no /scene'
    before = {o.id: o.status for o in scenes[-1].objects}

    goal = RetrieveTarget.Goal(policy='H-EG-SET', seed=0, execute=True)
    sent = client.send_goal_async(goal)
    assert ros_node.spin_until(sent.done, 30.0) and sent.result().accepted
    done = sent.result().get_result_async()
    assert ros_node.spin_until(done.done, 540.0), 'no result'
    status, result = done.result().status, done.result().result
    assert status == GoalStatus.STATUS_SUCCEEDED, result.message
    assert result.executed and result.success and result.sequence

    sequence = list(result.sequence)
    target = next(o.id for o in scenes[-1].objects if o.role == ObjectState.ROLE_TARGET)
    assert sequence[-1] == target

    def relocated() -> bool:
        status_of = {o.id: o.status for o in scenes[-1].objects}
        return all(status_of[i] == ObjectState.STATUS_RELOCATED for i in sequence)

    assert ros_node.spin_until(relocated, 20.0), f'/scene does not show {sequence} relocated'
    final = {o.id: o for o in scenes[-1].objects}
    for object_id, obj in final.items():
        if obj.role == ObjectState.ROLE_OBSTACLE and object_id not in sequence:
            assert obj.status == before[object_id] == ObjectState.STATUS_IN_CLUTTER
    assert scenes[-1].attached_id == ''  # the target was released in the drop zone

    # a second goal on the cleared scene has nothing to retrieve: a clear NO_SOLUTION
    sent = client.send_goal_async(RetrieveTarget.Goal(policy='H-EG'))
    assert ros_node.spin_until(sent.done, 30.0) and sent.result().accepted
    done = sent.result().get_result_async()
    assert ros_node.spin_until(done.done, 30.0)
    assert done.result().status == GoalStatus.STATUS_ABORTED
    assert done.result().result.error_code == RetrieveTarget.Result.NO_SOLUTION
    assert 'not in the clutter' in done.result().result.message
