"""``jaco2_sim`` node: kinematic Jaco² simulator (joint states, scene, grasp attach/detach).

Thin ROS wrapper around :class:`~jaco2_sim.integrator.JointIntegrator` and
:class:`~jaco2_sim.world.World`; see DESIGN.md for the graph contract.

Limits and failure behaviour:

* ``/joint_trajectory``: at most ``max_trajectory_points`` points (default 10 000, range 1 to
  100 000). Trajectories share the timer's thread, so a message blocks /joint_states while it is
  handled: 10 000 points take about 0.08 s (0.07 s of it rclpy deserialisation), 100 000 about
  0.9 s and 35 MB. The subscription is raw: the point count is read from the CDR bytes first, and
  a longer trajectory is rejected (warning naming the limit) without being deserialised; the arm
  keeps its current motion. Any other bad trajectory is rejected with a warning too.
* ``~/reset_scene`` and the ``scenario`` parameter: a bad scenario gives ``success=false`` /
  ``successful=false`` with the :class:`~jaco2_sim.exceptions.ScenarioError` text (file, field,
  problem); the current scene is kept. Any unexpected exception while loading is answered the
  same way and logged as an error: the node never dies from a request. Scenario files are at
  most 1 MB (``qtree_scene.scenario.MAX_SCENARIO_BYTES``), and services and parameters run on a
  second executor thread: loading never stops /joint_states for more than a few periods.
"""

from __future__ import annotations

import sys
import threading
from typing import Any

import numpy as np
from jaco2_description.model import FINGER_JOINTS, Jaco2Model, urdf_text
from qtree_msgs.msg import Scene
from qtree_msgs.srv import AttachObject, ResetScene, SetScene
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import SERVICE_QOS
from qtree_node_support.text import clip, quote
from qtree_scene.message import parse_scene_msg
from qtree_scene.scenario import load_scenario
from qtree_scene.scene import Scenario
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.exceptions import InvalidParameterValueException, ParameterUninitializedException
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory

from jaco2_sim.conversions import (
    STATUS_NAMES,
    decode_trajectory,
    joint_state_msg,
    parameter_descriptor,
    scene_msg,
    trajectory_arrays,
)
from jaco2_sim.disturbances import PARAMETER_FIELDS, DisturbedDrive, from_parameters
from jaco2_sim.exceptions import Jaco2SimError, ModelError, ScenarioError, TrajectoryError
from jaco2_sim.integrator import JointIntegrator
from jaco2_sim.world import World

LATCHED_QOS = QoSProfile(  # /scene and /robot_description
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
STATE_QOS = QoSProfile(depth=10)  # /joint_states: reliable, volatile
TRAJECTORY_QOS = QoSProfile(depth=10)  # /joint_trajectory
ATTACH_DISTANCE_WARN = 0.25  # attach farther than this from the EE origin is suspicious [m]
MAX_TRAJECTORY_POINTS_CAP = 100_000  # upper bound of max_trajectory_points (~0.9 s blocked)


# (name, default, (description, min, max)); robot_description (read-only URDF) is added on top.
PARAMETERS = [
    ('scenario', 's1', ('scenario name (s1, s2, s3) or YAML path',)),
    ('sim_rate_hz', 100.0, ('integration and /joint_states rate [Hz]', 1.0, 1000.0)),
    ('scene_rate_hz', 10.0, ('max /scene rate while an object moves [Hz]', 0.1, 100.0)),
    ('finger_angle_rad', 0.2, ('proximal finger joint angle [rad]', 0.0, 1.51)),
    ('initial_configuration', Parameter.Type.DOUBLE_ARRAY, ('7 arm angles [rad]; unset = home',)),
    (
        'max_trajectory_points',
        10_000,
        ('longer /joint_trajectory messages are rejected unread', 1, MAX_TRAJECTORY_POINTS_CAP),
    ),
    ('command_topic', '/joint_command', ('streamed sensor_msgs/JointState arm references',)),
    ('joint_offset_rad', [0.0] * 7, ('disturbance: servo offset per arm joint [rad]',)),
    ('command_latency_s', 0.0, ('disturbance: command latency [s]', 0.0, 2.0)),
    ('velocity_limit_scale', 1.0, ('disturbance: fraction of the velocity limits', 0.05, 1.0)),
    ('measurement_noise_rad', 0.0, ('disturbance: joint-state noise σ [rad]', 0.0, 0.1)),
    ('noise_seed', 0, ('seed of the measurement noise', 0, 2**31 - 1)),
]


class Jaco2SimNode(Node):
    """Publishes /joint_states each period, /scene on change, /robot_description once."""

    def __init__(self, **node_options: Any) -> None:
        """Declare the parameters, load the scenario, start publishing.

        Args:
            node_options: passed to :class:`rclpy.node.Node` (e.g. ``context=`` in tests).
        """
        super().__init__('jaco2_sim', **node_options)
        params = [(n, v, parameter_descriptor(*d)) for n, v, d in PARAMETERS]
        urdf = parameter_descriptor('URDF', read_only=True)
        params.append(('robot_description', urdf_text(), urdf))
        self.declare_parameters('', params)
        self.robot = Jaco2Model(self._param('finger_angle_rad'))
        self.scenario = load_scenario(self._param('scenario'))
        self.world = World(self.scenario)
        q0 = self._param('initial_configuration')
        self.sim = JointIntegrator(
            self.robot.limits, self._param('sim_rate_hz'), self.scenario.home if q0 is None else q0
        )
        self.drive = DisturbedDrive(self.sim, from_parameters(self._disturbance_values()))
        fingers = np.zeros(len(FINGER_JOINTS))
        fingers[:3] = self.robot.finger_angle
        self.fingers = fingers
        self._scene_version = -1
        self._last_scene_time = 0.0
        # Motion (timer, /joint_trajectory) in its own group; services and parameters run on the
        # executor's other thread, so loading a scenario never stops /joint_states (#18). The
        # lock covers what both touch: the integrator and the world.
        self._motion_group = MutuallyExclusiveCallbackGroup()
        self._lock = threading.Lock()
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.state_pub = self.create_publisher(JointState, '/joint_states', STATE_QOS)
        self.scene_pub = self.create_publisher(Scene, '/scene', LATCHED_QOS)
        self.urdf_pub = self.create_publisher(String, '/robot_description', LATCHED_QOS)
        self.create_subscription(
            JointTrajectory,
            '/joint_trajectory',
            self._on_raw_trajectory,
            TRAJECTORY_QOS,
            raw=True,
            callback_group=self._motion_group,
        )
        self.create_subscription(  # streamed references (closed-loop execution)
            JointState,
            self._param('command_topic'),
            self._on_command,
            TRAJECTORY_QOS,
            callback_group=self._motion_group,
        )
        self.create_service(ResetScene, '~/reset_scene', self._on_reset, qos_profile=SERVICE_QOS)
        self.create_service(SetScene, '~/set_scene', self._on_set_scene, qos_profile=SERVICE_QOS)
        self.create_service(
            AttachObject, '~/attach_object', self._on_attach, qos_profile=SERVICE_QOS
        )
        self.timer = self.create_timer(self.sim.period, self._on_timer, self._motion_group)
        self.urdf_pub.publish(String(data=urdf_text()))
        self._publish_scene()
        self.get_logger().info(
            f'jaco2_sim ready: scenario {self.scenario.name}, {1 / self.sim.period:g} Hz'
        )

    def _param(self, name: str):
        try:
            return self.get_parameter(name).value
        except ParameterUninitializedException:
            return None

    def _disturbance_values(self, params: list[Parameter] = ()) -> dict:
        values = {name: self._param(name) for name in PARAMETER_FIELDS}
        return values | {p.name: p.value for p in params if p.name in PARAMETER_FIELDS}

    def _check_parameters(self, params: list[Parameter]) -> SetParametersResult:
        for p in params:
            try:
                if p.name in PARAMETER_FIELDS:
                    from_parameters(self._disturbance_values(params))
                elif p.name == 'scenario':
                    load_scenario(p.value)
                elif p.name == 'initial_configuration' and p.value is not None:
                    JointIntegrator(self.robot.limits, q0=np.asarray(p.value, dtype=float))
                elif p.name == 'finger_angle_rad' and hasattr(self, 'robot'):
                    return SetParametersResult(
                        successful=False, reason='finger_angle_rad is fixed at start'
                    )
            except (Jaco2SimError, ModelError, ScenarioError, TypeError, ValueError) as err:
                return SetParametersResult(successful=False, reason=f'{p.name}: {err}')
            except Exception as err:  # a bad value must not kill the node
                reason = f'{p.name}: unexpected {type(err).__name__}: {err}'
                self.get_logger().error(f'parameter rejected: {reason}')
                return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params: list[Parameter]) -> None:
        if any(p.name in PARAMETER_FIELDS for p in params):
            self.drive.configure(from_parameters(self._disturbance_values()))
        for p in params:
            if p.name == 'scenario':
                try:
                    self._load(p.value)
                except Exception as err:  # checked before, so never expected
                    self.get_logger().error(f'scenario not loaded: {type(err).__name__}: {err}')
            elif p.name == 'sim_rate_hz':
                self.timer.cancel()
                self.destroy_timer(self.timer)
                self.sim.period = 1.0 / p.value
                self.timer = self.create_timer(self.sim.period, self._on_timer, self._motion_group)

    def _load(self, name: str) -> None:
        """Load scenario ``name`` and teleport home; on any exception nothing has changed."""
        self._install(load_scenario(name))

    def _install(self, scenario: Scenario) -> None:
        """Make ``scenario`` the scene and teleport home; on any exception nothing has changed."""
        world = World(scenario)
        with self._lock:
            self.sim.reset(np.asarray(scenario.home))
            self.drive.delay.clear()
            self.scenario, self.world = scenario, world
            self._publish_scene()

    def _on_timer(self) -> None:
        with self._lock:
            self._step()

    def _step(self) -> None:
        for error in self.drive.apply_due():
            self._reject_trajectory(f'(delayed command) {error}')
        if self.sim.step():
            self.get_logger().info('trajectory finished')
        if self.world.attached_id is not None:
            self.world.update(self.robot.ee_pose(self.sim.q))
        now = self.get_clock().now()
        self.state_pub.publish(
            joint_state_msg(now.to_msg(), self.drive.measured(), self.sim.velocity, self.fingers)
        )
        seconds = now.nanoseconds * 1e-9
        if self.world.version != self._scene_version and (
            seconds - self._last_scene_time >= 1.0 / self._param('scene_rate_hz')
        ):
            self._publish_scene()

    def _publish_scene(self) -> None:
        now = self.get_clock().now()
        self.scene_pub.publish(scene_msg(self.world, now.to_msg()))
        self._scene_version = self.world.version
        self._last_scene_time = now.nanoseconds * 1e-9

    def _on_raw_trajectory(self, raw: bytes) -> None:
        """Reject an oversized trajectory from its CDR lengths, else deserialise and follow it."""
        try:
            msg = decode_trajectory(raw, self._param('max_trajectory_points'))
        except TrajectoryError as err:
            self._reject_trajectory(str(err))
            return
        with self._lock:
            self._on_trajectory(msg)

    def _reject_trajectory(self, why: str) -> None:
        self.get_logger().warning(f'trajectory rejected: {why}')

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        if not msg.points:
            self.drive.delay.clear()
            self.sim.cancel()
            self.get_logger().info('empty trajectory: stopping')
            return
        try:
            clamped = self.drive.command('trajectory', *trajectory_arrays(msg))
        except (Jaco2SimError, ModelError, ScenarioError) as err:
            self._reject_trajectory(str(err))
            return
        if clamped:
            self.get_logger().warning('trajectory beyond the joint limits: clamped to them')
        self.get_logger().info(f'following a trajectory of {len(msg.points)} points')

    def _on_command(self, msg: JointState) -> None:
        try:
            with self._lock:
                self.drive.command('point', list(msg.name), list(msg.position))
        except (Jaco2SimError, ValueError) as err:
            self.get_logger().warning(f'command rejected: {err}', throttle_duration_sec=1.0)

    def _on_reset(self, request: ResetScene.Request, response: ResetScene.Response):
        name = request.scenario or self.scenario.source or self.scenario.name
        try:
            if request.scenario or self.scenario.source:
                self._load(name)
            else:  # a scene given by SetScene: back to its initial state
                self._install(self.scenario)
        except (Jaco2SimError, ModelError, ScenarioError) as err:
            response.success, response.message = False, str(err)
            self.get_logger().warning(f'reset_scene failed: {err}')
            return response
        except Exception as err:  # a bad file must not kill the node
            response.success = False
            response.message = clip(f'{quote(name)}: unexpected {type(err).__name__}: {err}', 1000)
            self.get_logger().error(f'reset_scene failed: {response.message}')
            return response
        response.success, response.message = True, f'scenario {quote(self.scenario.name)} loaded'
        return response

    def _on_set_scene(self, request: SetScene.Request, response: SetScene.Response):
        try:
            self._install(parse_scene_msg(request.scene))
        except (Jaco2SimError, ModelError, ScenarioError) as err:
            response.success, response.message = False, clip(str(err), 1000)
            self.get_logger().warning(f'set_scene rejected: {response.message}')
            return response
        except Exception as err:  # a bad message must not kill the node
            response.success = False
            response.message = clip(f'SetScene: unexpected {type(err).__name__}: {err}', 1000)
            self.get_logger().error(f'set_scene failed: {response.message}')
            return response
        response.success = True
        response.message = (
            f'scene {quote(self.scenario.name)} set ({len(self.scenario.objects)} objects)'
        )
        return response

    def _on_attach(self, request: AttachObject.Request, response: AttachObject.Response):
        with self._lock:
            return self._attach(request, response)

    def _attach(self, request: AttachObject.Request, response: AttachObject.Response):
        try:
            if request.attach:
                distance = self.world.attach(request.object_id, self.robot.ee_pose(self.sim.q))
                if distance > ATTACH_DISTANCE_WARN:
                    self.get_logger().warning(
                        f'attached {quote(request.object_id)} {distance:.3f} m from the EE'
                    )
                response.message = f'{quote(request.object_id)} attached'
            else:
                status = STATUS_NAMES.get(
                    request.status_after_release, f'code {request.status_after_release}'
                )
                self.world.detach(request.object_id, status)
                response.message = f'{quote(request.object_id)} released ({status})'
        except (Jaco2SimError, ModelError, ScenarioError) as err:
            response.success, response.message = False, str(err)
            return response
        response.success = True
        self._publish_scene()
        return response


def main(args: list[str] | None = None) -> None:
    """Run the node until SIGINT/SIGTERM (exit code 0); exit code 2 on bad start-up parameters."""
    startup = (Jaco2SimError, ModelError, ScenarioError, InvalidParameterValueException)
    executor = lambda context: MultiThreadedExecutor(2, context=context)  # noqa: E731 - see _lock
    code = run_node(
        Jaco2SimNode, args=args, make_executor=executor, startup_errors=startup, name='jaco2_sim'
    )
    sys.exit(code)


if __name__ == '__main__':
    main()
