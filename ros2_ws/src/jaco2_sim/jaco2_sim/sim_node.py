"""``jaco2_sim`` node: kinematic Jaco² simulator (joint states, scene, grasp attach/detach).

Parameters, entities and callbacks that convert messages and call
:class:`~jaco2_sim.simulation.Simulation` (limits and failure behaviour are documented there).
"""

from __future__ import annotations

import sys
from typing import Any

from jaco2_description.model import urdf_text
from qtree_msgs.msg import Scene
from qtree_msgs.srv import AttachObject, ResetScene, SetScene
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import SERVICE_QOS
from qtree_node_support.text import quote
from qtree_scene.message import parse_scene_msg
from rclpy.exceptions import InvalidParameterValueException
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
        self.core = Simulation(
            *map(p, ('scenario', 'sim_rate_hz', 'finger_angle_rad', 'initial_configuration')),
            api.disturbance_values(self),
        )
        self.sim = self.core.sim
        self.add_on_set_parameters_callback(lambda ps: api.check_parameters(self, self.core, ps))
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.state_pub = self.create_publisher(JointState, '/joint_states', api.STATE_QOS)
        self.scene_pub = self.create_publisher(Scene, '/scene', api.LATCHED_QOS)
        self.urdf_pub = self.create_publisher(String, '/robot_description', api.LATCHED_QOS)
        qos, on_raw = api.TRAJECTORY_QOS, self._on_raw_trajectory
        self.create_subscription(JointTrajectory, '/joint_trajectory', on_raw, qos, raw=True)
        self.create_subscription(JointState, p('command_topic'), self._on_command, qos)  # streamed
        for kind, name, cb in [(ResetScene, '~/reset_scene', self._on_reset),
                               (SetScene, '~/set_scene', self._on_set_scene),
                               (AttachObject, '~/attach_object', self._on_attach)]:  # fmt: skip
            self.create_service(kind, name, cb, qos_profile=SERVICE_QOS)
        self.timer = self.create_timer(self.sim.period, self._on_timer)
        self.urdf_pub.publish(String(data=urdf_text()))
        self._publish_scene()
        rate = f'{1 / self.sim.period:g} Hz'
        self.get_logger().info(f'jaco2_sim ready: scenario {self.scenario.name}, {rate}')

    @property
    def scenario(self):
        """The current scene (:class:`~qtree_scene.scene.Scenario`)."""
        return self.core.scenario

    def _apply_parameters(self, params: list[Parameter]) -> None:
        api.apply_disturbances(self, self.core, params)
        for p in params:
            if p.name == 'scenario':
                try:
                    self._change(self.core.load, p.value)
                except Exception as err:  # checked before, so never expected
                    self.get_logger().error(f'scenario not loaded: {type(err).__name__}: {err}')
            elif p.name == 'sim_rate_hz':
                self.timer.cancel()
                self.destroy_timer(self.timer)
                self.sim.period = 1.0 / p.value
                self.timer = self.create_timer(self.sim.period, self._on_timer)

    def _change(self, action, *args) -> str:
        """Run a scene change of the core, publish the new scene; the change's message."""
        message = action(*args)
        self._publish_scene()
        return message or ''

    def _on_timer(self) -> None:
        finished, errors = self.core.step()
        for error in errors:
            self._reject_trajectory(f'(delayed command) {error}')
        if finished:
            self.get_logger().info('trajectory finished')
        now = self.get_clock().now()
        self.state_pub.publish(conv.joint_state_msg(now.to_msg(), *self.core.joint_state()))
        if self.core.scene_due(now.nanoseconds * 1e-9, api.param(self, 'scene_rate_hz')):
            self._publish_scene()

    def _publish_scene(self) -> None:
        now = self.get_clock().now()
        self.scene_pub.publish(conv.scene_msg(self.core.world, now.to_msg()))
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
        name = request.scenario or self.scenario.source or self.scenario.name
        change = lambda: self._change(self.core.reset_scene, request.scenario)  # noqa: E731
        return answer(response, change, 'reset_scene', quote(name), self.get_logger())

    def _on_set_scene(self, request: SetScene.Request, response: SetScene.Response):
        change = lambda: self._change(self.core.set_scene, parse_scene_msg(request.scene))  # noqa: E731
        return answer(response, change, 'set_scene', 'SetScene', self.get_logger())

    def _on_attach(self, request: AttachObject.Request, response: AttachObject.Response):
        args = (request.object_id, request.attach, request.status_after_release)
        change = lambda: self._change(self.core.grasp, *args)  # noqa: E731
        return answer(response, change, 'attach_object', quote(args[0]), self.get_logger())


def main(args: list[str] | None = None) -> None:
    """Run the node until SIGINT/SIGTERM (exit code 0); exit code 2 on bad start-up parameters."""
    startup = (Jaco2SimError, ModelError, ScenarioError, InvalidParameterValueException)
    sys.exit(run_node(Jaco2SimNode, args=args, startup_errors=startup, name='jaco2_sim'))


if __name__ == '__main__':
    main()
