"""``motion_planner`` node: serves /relocate_object with the STPIK motion planner (Figure 2).

Parameters, entities and callbacks that convert messages (:mod:`.conversions`) and call
:class:`~stpik_motion_planner.service.PlannerService` (limits and timing are documented there);
with ``execute=true`` :class:`~stpik_motion_planner.closed_loop_execution.Execution` drives the
arm (``execution_mode``: closed loop on ``command_topic``, or whole trajectories on
``trajectory_topic``) and grasps through ``attach_service``.
"""

from __future__ import annotations

import sys
import time
from typing import Any

from qtree_msgs.msg import PlanningEvent, Scene
from qtree_msgs.srv import RelocateObject
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import LATCHED_QOS, SERVICE_QOS
from qtree_node_support.text import clip
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from stpik_motion_planner import interface as api
from stpik_motion_planner.closed_loop_execution import Execution
from stpik_motion_planner.conversions import fill_relocate_response, planning_event_msg
from stpik_motion_planner.scene_checks import format_id, format_ids
from stpik_motion_planner.service import MAX_WAITING_PLANS, PlannerService

EXECUTOR_THREADS = MAX_WAITING_PLANS + 4  # + execution, /joint_states, /scene, quick answers
MAX_MESSAGE_CHARS = 1000  # longest answer message, log line or event message [characters]


class MotionPlannerNode(Node):
    """Relocation feasibility and execution service on top of the STPIK planner."""

    def __init__(self) -> None:
        super().__init__('motion_planner')
        api.declare_parameters(self)
        self.add_on_set_parameters_callback(self._on_parameters)
        self._service = PlannerService(lambda: api.planner_config(self), self._log)
        # Own groups, so that waiting requests never hold back the state, scene or attach answer.
        self.create_subscription(
            Scene,
            '/scene',
            self._on_scene,
            LATCHED_QOS,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )
        self._execution = Execution(self)  # open or closed loop (execution_mode)
        self._event_pub = self.create_publisher(PlanningEvent, '/motion_planner/events', 10)
        self.create_service(
            RelocateObject,
            '/relocate_object',
            self._on_relocate,
            qos_profile=SERVICE_QOS,  # a burst of requests is queued, never dropped (#18)
            callback_group=ReentrantCallbackGroup(),
        )
        self.get_logger().info('motion_planner ready: serving /relocate_object')

    def _log(self, level: str, line: str) -> None:
        if level == 'warning':  # one call site per severity (rclpy requires it)
            self.get_logger().warning(line)
        else:
            self.get_logger().info(line)

    def _on_scene(self, msg: Scene) -> None:
        self._execution.on_scene(msg)  # the live scene of the closed loop
        self._service.on_scene(msg)

    def _on_parameters(self, params: list) -> SetParametersResult:
        result, config = api.check_parameters(params, api.planner_config(self))
        if config is not None:
            self._service.reconfigure(config)
        return result

    def _on_relocate(self, request, response):
        received = time.monotonic()
        relocated = list(request.relocated_ids)
        wait_s = self.get_parameter('request_timeout_s').value
        scene_wait_s = self.get_parameter('scene_wait_s').value
        result = self._service.answer(
            request.object_id, relocated, received, wait_s, request.scene_name, scene_wait_s
        )
        if result.feasible and request.execute:
            follow = lambda r: self._execution.follow(r, request.object_id, relocated)  # noqa: E731
            result = self._service.execute(result, follow)
        fill_relocate_response(response, result, clip(result.message, MAX_MESSAGE_CHARS))
        stamp = self.get_clock().now().to_msg()
        self._event_pub.publish(planning_event_msg(stamp, request, response, result))
        line = (
            f'relocate {format_id(request.object_id)} after {format_ids(relocated)}'
            f': {result.reason.name} ({result.planning_time * 1e3:.1f} ms planning, '
            f'{(time.monotonic() - received) * 1e3:.1f} ms in all)'
        )
        self.get_logger().info(clip(line, MAX_MESSAGE_CHARS))
        return response


def run(args: list[str] | None = None, **options: Any) -> int:
    """Run the node until SIGINT/SIGTERM (0)."""
    executor = lambda context: MultiThreadedExecutor(EXECUTOR_THREADS, context=context)  # noqa: E731
    return run_node(MotionPlannerNode, args=args, make_executor=executor, **options)


def main(args: list[str] | None = None) -> None:
    """Entry point: exit with the code of :func:`run`."""
    sys.exit(run(args))


if __name__ == '__main__':
    main()
