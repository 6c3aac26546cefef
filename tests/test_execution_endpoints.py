"""Execution to a real controller: the motion planner's trajectory topic, joint-state topic and
attach service are parameters. No simulator here: the test node plays the robot (a
joint_trajectory_controller that jumps to each segment's last point, a joint-state broadcaster
and a gripper service) and publishes /scene itself.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from jaco2_description.model import ARM_JOINTS, HOME
from qtree_msgs.msg import Scene
from qtree_msgs.srv import AttachObject, RelocateObject
from qtree_scene.message import scene_msg
from qtree_scene.scenario import load_scenario
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

pytestmark = pytest.mark.timeout(240)

ENDPOINTS = {  # a joint_trajectory_controller takes whole trajectories: open loop
    'execution_mode': 'open_loop',
    'trajectory_topic': '/arm_controller/joint_trajectory',
    'joint_state_topic': '/arm/joint_states',
    'attach_service': '/gripper/attach',
}
LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


class FakeArm:
    """Controller, joint-state broadcaster and gripper of a pretend real arm."""

    def __init__(self, node: Any) -> None:
        self.q = np.array(HOME, dtype=float)
        self.trajectories: list[JointTrajectory] = []
        self.grasps: list[tuple[str, bool]] = []
        self.refuse = False  # the gripper answers success=false to a grasp (#32)
        self.states = node.create_publisher(JointState, ENDPOINTS['joint_state_topic'], 10)
        topic = ENDPOINTS['trajectory_topic']
        node.create_subscription(JointTrajectory, topic, self._on_trajectory, 10)
        node.create_service(AttachObject, ENDPOINTS['attach_service'], self._on_attach)
        node.create_timer(0.02, self._publish)
        self._node = node

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        assert list(msg.joint_names) == list(ARM_JOINTS)
        self.trajectories.append(msg)
        self.q = np.array(msg.points[-1].positions)

    def _on_attach(self, request: Any, response: Any) -> Any:
        self.grasps.append((request.object_id, request.attach))
        response.success, response.message = True, 'gripper closed' if request.attach else 'open'
        if self.refuse and request.attach:
            response.success, response.message = False, 'object slipped out of the fingers'
        return response

    def _publish(self) -> None:
        msg = JointState(name=list(ARM_JOINTS), position=[float(v) for v in self.q])
        msg.header.stamp = self._node.get_clock().now().to_msg()
        self.states.publish(msg)


def start(launch: Any, ros_node: Any) -> Any:
    """The motion planner on the pretend arm's endpoints, with s1 published on /scene."""
    planner = launch('stpik_motion_planner', 'motion_planner_node', parameters=ENDPOINTS)
    planner.wait_for_log('ready', 60.0)
    scene = ros_node.create_publisher(Scene, '/scene', LATCHED)
    assert ros_node.spin_until(lambda: scene.get_subscription_count() > 0, 20.0)
    scene.publish(scene_msg(load_scenario('s1')))
    assert ros_node.spin_until(lambda: 'planner rebuilt' in planner.log_text(), 30.0)
    return planner


def test_planner_drives_the_configured_controller(launch: Any, ros_node: Any) -> None:
    arm = FakeArm(ros_node)
    planner = start(launch, ros_node)
    assert ros_node.spin_until(lambda: arm.trajectories == [] and planner.alive(), 1.0)
    request = RelocateObject.Request(object_id='O2', execute=True)
    client = ros_node.create_client(RelocateObject, '/relocate_object')
    answer = ros_node.call(client, request, 120.0)
    assert answer.feasible, answer.message
    assert len(arm.trajectories) == 3  # approach, carry, retreat
    assert arm.grasps == [('O2', True), ('O2', False)]
    assert np.allclose(arm.q, answer.trajectory.points[-1].positions)


def test_a_refused_grasp_is_grasp_failed_and_the_arm_goes_back(launch: Any, ros_node: Any) -> None:
    """#32, open loop: the approach is reversed to its start, the answer names the object."""
    arm = FakeArm(ros_node)
    arm.refuse = True
    start(launch, ros_node)
    request = RelocateObject.Request(object_id='O2', execute=True)
    client = ros_node.create_client(RelocateObject, '/relocate_object')
    answer = ros_node.call(client, request, 120.0)
    assert not answer.feasible
    assert answer.reason == RelocateObject.Response.GRASP_FAILED, answer.message
    assert "refused 'O2': object slipped" in answer.message and 'undone' in answer.message
    assert len(arm.trajectories) == 2 and arm.grasps == [('O2', True)]  # approach, back
    assert np.allclose(arm.q, HOME, atol=1e-6)
