"""Cross-process tests of the jaco2_sim node: trajectory following, bad input, attach/detach."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from builtin_interfaces.msg import Duration
from jaco2_description.model import ARM_JOINTS, FINGER_JOINTS, HOME, Jaco2Model, arm_limits
from qtree_msgs.msg import ObjectState, Scene
from qtree_msgs.srv import AttachObject, ResetScene
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from shape_msgs.msg import SolidPrimitive
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
RATE_HZ = 100.0


class Probe:
    """Collects /joint_states and /scene, publishes /joint_trajectory."""

    def __init__(self, node: Any) -> None:
        self.node = node
        self.states: list[tuple[float, np.ndarray]] = []
        self.scenes: list[Scene] = []
        node.create_subscription(JointState, '/joint_states', self._on_state, 100)
        node.create_subscription(Scene, '/scene', self.scenes.append, LATCHED)
        self.pub = node.create_publisher(JointTrajectory, '/joint_trajectory', 10)
        self.reset = node.create_client(ResetScene, '/jaco2_sim/reset_scene')
        self.attach = node.create_client(AttachObject, '/jaco2_sim/attach_object')
        assert node.spin_until(lambda: self.states and self.pub.get_subscription_count() > 0)

    def _on_state(self, msg: JointState) -> None:
        assert list(msg.name) == [*ARM_JOINTS, *FINGER_JOINTS]
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        self.states.append((stamp, np.array(msg.position[:7])))
        self.fingers = np.array(msg.position[7:])

    @property
    def q(self) -> np.ndarray:
        return self.states[-1][1]

    def send(self, times: list[float], points: list[np.ndarray], names=ARM_JOINTS) -> None:
        msg = JointTrajectory(joint_names=list(names))
        for t, p in zip(times, points, strict=True):
            sec = math.floor(t)
            msg.points.append(
                JointTrajectoryPoint(
                    positions=[float(v) for v in p],
                    time_from_start=Duration(sec=sec, nanosec=int((t - sec) * 1e9)),
                )
            )
        self.pub.publish(msg)

    def reach(self, goal: np.ndarray, timeout_s: float = 10.0, tol: float = 1e-3) -> bool:
        return self.node.spin_until(lambda: np.max(np.abs(self.q - goal)) < tol, timeout_s)

    def object_pose(self, object_id: str) -> pin.SE3:
        obj = next(o for o in self.scenes[-1].objects if o.id == object_id)
        p, o = obj.pose.position, obj.pose.orientation
        return pin.XYZQUATToSE3(np.array([p.x, p.y, p.z, o.x, o.y, o.z, o.w]))


@pytest.fixture
def probe(launch: Any, ros_node: Any) -> Probe:
    sim = launch('jaco2_sim', 'sim_node', parameters={'sim_rate_hz': RATE_HZ})
    sim.wait_for_log('ready', timeout_s=30.0)
    probe = Probe(ros_node)
    probe.sim = sim
    return probe


def test_trajectory_followed_within_velocity_limits(probe: Probe, ros_node: Any) -> None:
    np.testing.assert_allclose(probe.q, HOME, atol=1e-9)
    # Joint 1 asked for 0.35 rad in 0.4 s (0.875 rad/s > its 0.6283 rad/s limit): it saturates.
    mid = HOME + np.array([0.35, 0.1, -0.2, 0.1, 0.0, -0.1, 0.2])
    goal = HOME + np.array([0.45, 0.15, -0.3, 0.2, 0.1, -0.2, 0.3])
    start = len(probe.states)
    probe.send([0.4, 1.2], [mid, goal])
    assert probe.reach(goal), f'did not reach the goal: {probe.q - goal}'
    ros_node.spin_until(lambda: False, 0.2)
    np.testing.assert_allclose(probe.q, goal, atol=2e-4)  # holds the goal
    vmax = arm_limits().velocity
    period = 1.0 / RATE_HZ
    stamps = np.array([s for s, _ in probe.states[start - 1 :]])
    qs = np.array([q for _, q in probe.states[start - 1 :]])
    steps = np.maximum(1, np.round(np.diff(stamps) / period))  # sim periods between messages
    speeds = np.abs(np.diff(qs, axis=0)) / (steps[:, None] * period)  # [rad/s]
    assert np.all(speeds <= vmax * (1 + 1e-6)), speeds.max(axis=0)
    assert speeds[:, 0].max() == pytest.approx(vmax[0], rel=1e-3)  # joint 1 did saturate
    # Fingers: proximal at the default 0.2 rad, tips at 0.
    np.testing.assert_allclose(probe.fingers, [0.2, 0.2, 0.2, 0.0, 0.0, 0.0])
    assert probe.sim.alive()


def test_bad_input_is_rejected_and_node_keeps_publishing(probe: Probe, ros_node: Any) -> None:
    response = ros_node.call(probe.reset, ResetScene.Request(scenario='no_such_scene'))
    assert not response.success
    assert 'no such scenario' in response.message
    probe.send([1.0], [HOME + np.array([math.nan, 0, 0, 0, 0, 0, 0])])
    probe.sim.wait_for_log('non-finite', timeout_s=5.0)
    probe.send([1.0], [HOME + 0.1], names=[*ARM_JOINTS[:6], 'j2s7s300_joint_finger_1'])
    probe.sim.wait_for_log('joint names must be', timeout_s=5.0)
    count = len(probe.states)
    assert ros_node.spin_until(lambda: len(probe.states) > count + 20, 5.0)
    np.testing.assert_allclose(probe.q, HOME, atol=1e-9)  # nothing moved
    # Beyond the limit of joint 2 (5.462881 rad): clamped and followed.
    beyond = HOME.copy()
    beyond[1] = 5.6
    probe.send([0.5], [beyond])
    probe.sim.wait_for_log('clamped', timeout_s=5.0)
    clamped = beyond.copy()
    clamped[1] = arm_limits().upper[1]
    assert probe.reach(clamped)
    # A good reset still works afterwards and brings the arm home with the new scene.
    response = ros_node.call(probe.reset, ResetScene.Request(scenario='s2'))
    assert response.success, response.message
    assert ros_node.spin_until(lambda: probe.scenes and probe.scenes[-1].scenario_name == 's2')
    assert probe.reach(HOME, timeout_s=2.0, tol=1e-9)
    assert probe.sim.alive()


def test_attached_object_follows_the_end_effector(probe: Probe, ros_node: Any) -> None:
    assert ros_node.spin_until(lambda: bool(probe.scenes))
    scene = probe.scenes[-1]
    assert scene.scenario_name == 's1' and scene.attached_id == ''
    table = next(o for o in scene.objects if o.id == 'table')
    assert table.role == ObjectState.ROLE_STATIC and table.shape.type == SolidPrimitive.BOX
    assert list(table.shape.dimensions) == pytest.approx([1.2, 1.4, 0.05])
    robot_description: list[String] = []
    ros_node.create_subscription(String, '/robot_description', robot_description.append, LATCHED)
    assert ros_node.spin_until(lambda: bool(robot_description))
    assert '<robot name="j2s7s300">' in robot_description[0].data

    bad = ros_node.call(probe.attach, AttachObject.Request(object_id='table', attach=True))
    assert not bad.success and 'static' in bad.message
    bad = ros_node.call(probe.attach, AttachObject.Request(object_id='O2', attach=False))
    assert not bad.success and 'not attached' in bad.message

    robot = Jaco2Model()
    pose0 = probe.object_pose('O1')
    ok = ros_node.call(probe.attach, AttachObject.Request(object_id='O1', attach=True))
    assert ok.success, ok.message
    assert ros_node.spin_until(lambda: probe.scenes[-1].attached_id == 'O1')
    goal = HOME + np.array([0.3, 0.1, 0.0, -0.1, 0.0, 0.0, 0.2])
    probe.send([0.8], [goal])
    assert probe.reach(goal)
    expected = robot.ee_pose(goal) * robot.ee_pose(HOME).actInv(pose0)

    def followed() -> bool:
        return np.allclose(probe.object_pose('O1').homogeneous, expected.homogeneous, atol=1e-6)

    assert ros_node.spin_until(followed, 3.0), probe.object_pose('O1')
    moved = np.linalg.norm(expected.translation - pose0.translation)
    assert moved > 0.1  # the object really travelled [m]
    status = next(o.status for o in probe.scenes[-1].objects if o.id == 'O1')
    assert status == ObjectState.STATUS_GRASPED

    request = AttachObject.Request(object_id='O1', attach=False)
    assert request.status_after_release == ObjectState.STATUS_RELOCATED
    assert ros_node.call(probe.attach, request).success
    assert ros_node.spin_until(lambda: probe.scenes[-1].attached_id == '')
    released = next(o for o in probe.scenes[-1].objects if o.id == 'O1')
    assert released.status == ObjectState.STATUS_RELOCATED
    probe.send([0.5], [HOME])
    assert probe.reach(HOME)
    np.testing.assert_allclose(
        probe.object_pose('O1').homogeneous, expected.homogeneous, atol=1e-6
    )


def test_parameter_changes_are_validated(probe: Probe, ros_node: Any) -> None:
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    client = AsyncParameterClient(ros_node, 'jaco2_sim')
    assert client.wait_for_services(10.0)

    def set_param(name: str, value: Any) -> Any:
        future = client.set_parameters([Parameter(name, value=value)])
        assert ros_node.spin_until(future.done, 10.0)
        return future.result().results[0]

    result = set_param('scenario', 'nope')
    assert not result.successful and 'no such scenario' in result.reason
    assert not set_param('sim_rate_hz', 5000.0).successful
    assert not set_param('robot_description', '<robot/>').successful
    assert set_param('scenario', 's3').successful
    assert ros_node.spin_until(lambda: probe.scenes[-1].scenario_name == 's3', 5.0)
    assert len(probe.scenes[-1].objects) == 15 + 1 + 1  # obstacles, target, table
    assert probe.sim.alive()
