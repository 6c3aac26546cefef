"""``motion_planner`` node: serves /relocate_object with the STPIK motion planner (Figure 2).

Converts messages and calls :class:`~stpik_motion_planner.planner.MotionPlanner`; with
``execute=true`` it streams the trajectory to ``jaco2_sim`` segment by segment and attaches and
releases the object through ``/jaco2_sim/attach_object``.
"""

from __future__ import annotations

import dataclasses
import threading
import time

import numpy as np
import rclpy
from jaco2_sim.model import ARM_JOINTS
from qtree_msgs.msg import ObjectState, PlanningEvent, Scene
from qtree_msgs.srv import AttachObject, RelocateObject
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from stpik_motion_planner.config import INTEGER_FIELDS, RANGES, PlannerConfig, check_value
from stpik_motion_planner.conversions import pose_array_msg, scenario_from_msg, trajectory_msg
from stpik_motion_planner.exceptions import MotionPlannerError
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult, Reason

SCENE_QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
STATE_QOS = QoSProfile(depth=10)
EXTRA = {
    'execution_timeout_s': (30.0, 0.1, 600.0, 'time for the sim to follow a segment [s]'),
    'goal_tolerance_rad': (0.02, 1e-4, 0.5, 'joint error at which a segment is reached [rad]'),
}


class MotionPlannerNode(Node):
    """Relocation feasibility and execution service on top of the STPIK planner."""

    def __init__(self) -> None:
        super().__init__('motion_planner')
        defaults = PlannerConfig()
        for name, (low, high, text) in RANGES.items():
            value = getattr(defaults, name)
            if name in INTEGER_FIELDS:
                rng = IntegerRange(from_value=int(low), to_value=int(high), step=1)
                desc = ParameterDescriptor(description=text, integer_range=[rng])
            else:
                rng = FloatingPointRange(from_value=float(low), to_value=float(high))
                desc = ParameterDescriptor(description=text, floating_point_range=[rng])
            self.declare_parameter(name, value, desc)
        for name, (value, low, high, text) in EXTRA.items():
            rng = FloatingPointRange(from_value=low, to_value=high)
            self.declare_parameter(
                name, value, ParameterDescriptor(description=text, floating_point_range=[rng])
            )
        self.add_on_set_parameters_callback(self._on_parameters)
        self._lock = threading.Lock()
        self._planner: MotionPlanner | None = None
        self._scene_error = ''
        self._geometry: tuple | None = None
        self._original: dict[str, tuple[float, float, float]] = {}
        self._q: np.ndarray | None = None
        group = ReentrantCallbackGroup()
        self.create_subscription(Scene, '/scene', self._on_scene, SCENE_QOS, callback_group=group)
        self.create_subscription(
            JointState, '/joint_states', self._on_joint_states, STATE_QOS, callback_group=group
        )
        self._trajectory_pub = self.create_publisher(JointTrajectory, '/joint_trajectory', 10)
        self._event_pub = self.create_publisher(PlanningEvent, '/motion_planner/events', 10)
        self._attach = self.create_client(
            AttachObject, '/jaco2_sim/attach_object', callback_group=group
        )
        self.create_service(
            RelocateObject, '/relocate_object', self._on_relocate, callback_group=group
        )
        self.get_logger().info('motion_planner ready: serving /relocate_object')

    def _config(self) -> PlannerConfig:
        values = {n: self.get_parameter(n).value for n in RANGES}
        return PlannerConfig(**values)

    def _on_parameters(self, params: list) -> SetParametersResult:
        try:
            for p in params:
                if p.name in RANGES:
                    check_value(p.name, p.value)
            changes = {p.name: p.value for p in params if p.name in RANGES}
            config = dataclasses.replace(self._config(), **changes)
        except (MotionPlannerError, TypeError) as err:
            return SetParametersResult(successful=False, reason=str(err))
        with self._lock:
            if self._planner is not None and changes:
                self._planner = MotionPlanner(self._planner.scenario, config)
        return SetParametersResult(successful=True)

    def _on_joint_states(self, msg: JointState) -> None:
        index = {n: i for i, n in enumerate(msg.name)}
        if all(n in index for n in ARM_JOINTS):
            self._q = np.array([msg.position[index[n]] for n in ARM_JOINTS])

    def _on_scene(self, msg: Scene) -> None:
        for o in msg.objects:
            if o.status == ObjectState.STATUS_IN_CLUTTER or o.id not in self._original:
                p = o.pose.position
                self._original.setdefault(o.id, (p.x, p.y, p.z))
        try:
            scenario = scenario_from_msg(msg, original=self._original)
            geometry = (scenario.name, scenario.objects, scenario.drop_zone_center)
            if geometry == self._geometry:
                return
            planner = MotionPlanner(scenario, self._config())
            self._scene_error = ''
        except (MotionPlannerError, ValueError) as err:
            planner, self._scene_error, geometry = None, str(err), None
            self.get_logger().warning(f'scene rejected: {err}')
        with self._lock:
            self._planner, self._geometry = planner, geometry
        self._original = {o.id: o.position for o in scenario.objects} if planner else {}
        self.get_logger().info(f'scene {msg.scenario_name!r}: planner rebuilt')

    def _on_relocate(self, request, response):
        with self._lock:
            planner = self._planner
            if planner is None:
                reason = Reason.INVALID_SCENE if self._scene_error else Reason.NO_SCENE
                result = PlanResult(False, reason, self._scene_error or 'no /scene received yet')
            else:
                result = planner.check(request.object_id, list(request.relocated_ids))
        if result.feasible and request.execute:
            result = self._execute(result, request.object_id)
        response.feasible, response.reason = result.feasible, int(result.reason)
        response.message, response.planning_time = result.message, result.planning_time
        response.from_cache = result.from_cache
        response.trajectory = trajectory_msg(result.times, result.joint_trajectory)
        response.ee_path = pose_array_msg(result.ee_path, 'j2s7s300_link_base')
        event = PlanningEvent(
            stamp=self.get_clock().now().to_msg(),
            object_id=request.object_id,
            relocated_ids=list(request.relocated_ids),
            execute=request.execute,
            feasible=result.feasible,
            reason=int(result.reason),
            message=result.message,
            planning_time=result.planning_time,
            from_cache=result.from_cache,
            ee_path=response.ee_path,
        )
        self._event_pub.publish(event)
        self.get_logger().info(
            f'relocate {request.object_id} after {list(request.relocated_ids)}'
            f': {result.reason.name} ({result.planning_time * 1e3:.1f} ms)'
        )
        return response

    def _execute(self, result: PlanResult, object_id: str) -> PlanResult:
        g, r = result.grasp_index, result.release_index
        steps = [(0, g, True), (g, r, False), (r, len(result.times) - 1, None)]
        for start, end, attach in steps:
            times = result.times[start : end + 1] - result.times[start]
            self._trajectory_pub.publish(
                trajectory_msg(times, result.joint_trajectory[start : end + 1])
            )
            if not self._reach(result.joint_trajectory[end], times[-1]):
                return dataclasses.replace(
                    result,
                    feasible=False,
                    reason=Reason.EXECUTION_FAILED,
                    message=f'the sim did not reach sample {end}',
                )
            if attach is not None and not self._call_attach(object_id, attach):
                return dataclasses.replace(
                    result,
                    feasible=False,
                    reason=Reason.EXECUTION_FAILED,
                    message=f'attach_object({object_id}, {attach}) failed',
                )
        return result

    def _reach(self, q_goal: np.ndarray, duration: float) -> bool:
        timeout = self.get_parameter('execution_timeout_s').value + duration
        tolerance = self.get_parameter('goal_tolerance_rad').value
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self._q is not None and np.max(np.abs(self._q - q_goal)) < tolerance:
                return True
            time.sleep(0.02)
        return False

    def _call_attach(self, object_id: str, attach: bool) -> bool:
        if not self._attach.wait_for_service(timeout_sec=5.0):
            return False
        request = AttachObject.Request(
            object_id=object_id, attach=attach, status_after_release=ObjectState.STATUS_RELOCATED
        )
        future = self._attach.call_async(request)
        deadline = time.monotonic() + 10.0
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        return future.done() and future.result() is not None and future.result().success


def main(args: list[str] | None = None) -> None:
    """Run the node until Ctrl-C."""
    rclpy.init(args=args)
    node = MotionPlannerNode()
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
