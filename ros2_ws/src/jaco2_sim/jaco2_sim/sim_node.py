"""``jaco2_sim`` node: kinematic Jaco² simulator (joint states, scene, grasp attach/detach); its
callbacks convert messages and call :class:`~jaco2_sim.simulation.Simulation` (limits, failures).
"""

from __future__ import annotations

import sys
from typing import Any

from jaco2_description.model import urdf_text
from qtree_msgs.msg import Scene
from qtree_msgs.srv import AttachObject, ResetScene, SetScene
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import LATCHED_QOS, SERVICE_QOS, STATE_QOS, TRAJECTORY_QOS
from qtree_node_support.text import quote
from qtree_scene.message import parse_scene_msg
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.exceptions import InvalidParameterValueException
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory

from jaco2_sim import conversions as conv
from jaco2_sim import interface as api
from jaco2_sim.exceptions import Jaco2SimError, ModelError, ScenarioError
from jaco2_sim.simulation import EXPECTED_ERRORS, Simulation, answer


class Jaco2SimNode(Node):
    """Publishes /joint_states each period, /scene on change, /robot_description once."""

    def __init__(self, **node_options: Any) -> None:
        """Declare the parameters, load the scenario, start publishing (``node_options``: Node)."""
        super().__init__('jaco2_sim', **node_options)
        api.declare_parameters(self)
        p = lambda name: api.param(self, name)  # noqa: E731
        self.core = Simulation(p('scenario'), p('sim_rate_hz'), p('finger_angle_rad'),
                               p('initial_configuration'),
                               api.disturbance_values(self))  # fmt: skip
        api.apply_parameters(self, self.core, [self.get_parameter('scene_events')])
        self.add_on_set_parameters_callback(lambda ps: api.check_parameters(self, self.core, ps))
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.state_pub = self.create_publisher(JointState, '/joint_states', STATE_QOS)
        self.scene_pub = self.create_publisher(Scene, '/scene', LATCHED_QOS)
        self.urdf_pub = self.create_publisher(String, '/robot_description', LATCHED_QOS)
        self._motion = MutuallyExclusiveCallbackGroup()  # services never stop the motion (#18)
        qos, group = TRAJECTORY_QOS, self._motion
        self.create_subscription(JointTrajectory, '/joint_trajectory', self._on_raw_trajectory,
                                 qos, raw=True, callback_group=group)  # fmt: skip
        self.create_subscription(JointState, p('command_topic'), self._on_command, qos,
                                 callback_group=group)  # fmt: skip
        for kind, name, cb in [(ResetScene, '~/reset_scene', self._on_reset),
                               (SetScene, '~/set_scene', self._on_set_scene),
                               (AttachObject, '~/attach_object', self._on_attach)]:  # fmt: skip
            self.create_service(kind, name, cb, qos_profile=SERVICE_QOS)
        self.timer = self.create_timer(self.core.sim.period, self._on_timer, self._motion)
        self.urdf_pub.publish(String(data=urdf_text()))
        self._publish_scene()
        rate, name = f'{1 / self.core.sim.period:g} Hz', self.core.scenario.name
        self.get_logger().info(f'jaco2_sim ready: scenario {name}, {rate}')

    def _apply_parameters(self, params: list[Parameter]) -> None:
        api.apply_parameters(self, self.core, params)
        for p in params:
            if p.name == 'scenario':
                try:
                    self._change(self.core.load, p.value)
                except Exception as err:  # checked before, so never expected
                    self.get_logger().error(f'scenario not loaded: {type(err).__name__}: {err}')
            elif p.name == 'sim_rate_hz':  # the timer keeps running at the new period
                self.core.sim.period = 1.0 / p.value
                self.timer.timer_period_ns = round(1e9 * self.core.sim.period)

    def _change(self, action, *args) -> str:
        """Run a scene change of the core, publish the new scene; the change's message."""
        message = action(*args)
        self._publish_scene()
        return message or ''

    def _on_timer(self) -> None:
        finished, errors = self.core.step()
        api.log_events(self, self.core)
        for error in errors:
            self._reject_trajectory(f'(delayed command) {error}')
        if finished:  # a whole trajectory; streamed references are counted by the core (#26)
            self.get_logger().info('trajectory finished')
        now = self.get_clock().now()
        self.state_pub.publish(conv.joint_state_msg(now.to_msg(), *self.core.joint_state()))
        if self.core.scene_due(now.nanoseconds * 1e-9, api.param(self, 'scene_rate_hz')):
            self._publish_scene()

    def _publish_scene(self) -> None:
        now = self.get_clock().now()
        with self.core.lock:  # the message is built under the lock, published outside it
            msg = conv.scene_msg(self.core.world, now.to_msg())
        self.scene_pub.publish(msg)
        self.core.scene_published(now.nanoseconds * 1e-9)

    def _on_raw_trajectory(self, raw: bytes) -> None:
        """Reject an oversized trajectory from its CDR lengths, else deserialise and follow it."""
        try:
            msg = conv.decode_trajectory(raw, api.param(self, 'max_trajectory_points'))
            warning, info = self.core.follow(*conv.trajectory_arrays(msg))
        except EXPECTED_ERRORS as err:  # TrajectoryError among them
            self._reject_trajectory(str(err))
            return
        if warning:
            self.get_logger().warning(warning)
        self.get_logger().info(info)

    def _on_command(self, msg: JointState) -> None:  # a streamed reference (closed loop)
        if why := self.core.command_point(list(msg.name), list(msg.position)):
            self.get_logger().warning(f'command rejected: {why}', throttle_duration_sec=1.0)

    def _reject_trajectory(self, why: str) -> None:
        self.get_logger().warning(f'trajectory rejected: {why}')

    def _on_reset(self, request: ResetScene.Request, response: ResetScene.Response):
        name = request.scenario or self.core.scenario.source or self.core.scenario.name
        change = lambda: self._change(self.core.reset_scene, request.scenario)  # noqa: E731
        return answer(response, change, 'reset_scene', quote(name), self.get_logger())

    def _on_set_scene(self, request: SetScene.Request, response: SetScene.Response):
        change = lambda: self._change(self.core.set_scene, parse_scene_msg(request.scene))  # noqa: E731
        return answer(response, change, 'set_scene', 'SetScene', self.get_logger())

    def _on_attach(self, request: AttachObject.Request, response: AttachObject.Response):
        args = (request.object_id, request.attach, request.status_after_release)
        change = lambda: self._change(self.core.grasp, *args)  # noqa: E731
        return answer(response, change, 'attach_object', quote(args[0]), self.get_logger())


def run(args: list[str] | None = None, **options: Any) -> int:
    """Run the node until SIGINT/SIGTERM (0); 2 on bad start-up parameters."""
    startup = (Jaco2SimError, ModelError, ScenarioError, InvalidParameterValueException)
    executor = lambda context: MultiThreadedExecutor(2, context=context)  # noqa: E731
    return run_node(Jaco2SimNode, args=args, make_executor=executor, startup_errors=startup,
                    name='jaco2_sim', **options)  # fmt: skip


def main(args: list[str] | None = None) -> None:
    """The console script: :func:`run`, its code as the exit status."""
    sys.exit(run(args))


if __name__ == '__main__':
    main()
