"""``motion_planner`` node: serves /relocate_object with the STPIK motion planner (Figure 2).

Converts messages (:mod:`.conversions`) and calls
:class:`~stpik_motion_planner.planner.MotionPlanner`; with ``execute=true``
:class:`~stpik_motion_planner.execution.TrajectoryExecution` streams the trajectory to
``jaco2_sim`` segment by segment and attaches and releases the object through
``/jaco2_sim/attach_object``.

Limits and timing of a request:

- At most ``MAX_RELOCATED_IDS`` (256) relocated ids and ``MAX_ID_CHARS`` (256) characters per id
  (:mod:`.scene_checks`); an id not in the scene is ``UNKNOWN_OBJECT`` whatever its length.
  Answers, log lines and ``/motion_planner/events`` quote at most 5 ids, each cut to 40
  characters; the event carries at most 256 ids of at most 256 characters.
- Bad requests, ``NO_SCENE`` and cache hits are answered at once, without waiting for the
  planner. Checks that need planning run one at a time (one STPIK state per planner); a request
  waits at most ``request_timeout_s`` for its turn, then ``PLANNER_BUSY``. ``time_limit_s`` bounds
  the planning itself, so an answer takes at most about ``request_timeout_s + time_limit_s``.
  At most ``MAX_WAITING_PLANS`` requests wait or plan at once; more get ``PLANNER_BUSY`` at
  once, so the executor (``EXECUTOR_THREADS`` threads) always has threads for /joint_states,
  /scene and the other requests.
- One execution at a time (another gets ``EXECUTION_FAILED``); /scene messages received
  meanwhile (the carried object moves) rebuild the planner once, after the execution. If no
  /joint_states arrives for ``joint_state_timeout_s`` during execution, it stops with
  ``EXECUTION_FAILED`` ("the simulator stopped publishing /joint_states").
"""

from __future__ import annotations

import dataclasses
import sys
import threading
import time

from qtree_msgs.msg import PlanningEvent, Scene
from qtree_msgs.srv import RelocateObject
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import SERVICE_QOS
from qtree_scene.message import scenario_from_msg
from qtree_scene.scene import ObjectSpec
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from stpik_motion_planner.closed_loop_execution import Execution
from stpik_motion_planner.config import INTEGER_FIELDS, RANGES, PlannerConfig, check_value
from stpik_motion_planner.conversions import (
    clip,
    fill_relocate_response,
    planning_event_msg,
    range_descriptor,
)
from stpik_motion_planner.exceptions import MotionPlannerError
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.scene_checks import format_id, format_ids

SCENE_QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
EXTRA = {
    'execution_timeout_s': (30.0, 0.1, 600.0, 'time for the sim to follow a segment [s]'),
    'goal_tolerance_rad': (0.02, 1e-4, 0.5, 'joint error at which a segment is reached [rad]'),
    'joint_state_timeout_s': (  # 3 s: a loaded 2-core demo once saw a 1.1 s callback gap
        3.0,
        0.05,
        60.0,
        'longest /joint_states silence during execution before EXECUTION_FAILED [s]',
    ),
    'request_timeout_s': (
        10.0,
        0.0,
        600.0,
        'longest wait of a request for the busy planner before PLANNER_BUSY; the planning itself '
        'is bounded by time_limit_s [s]',
    ),
}
EVENTS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)  # docs/QOS.md
MAX_WAITING_PLANS = 8  # requests waiting for or holding the planner at once [-]
EXECUTOR_THREADS = MAX_WAITING_PLANS + 4  # + execution, /joint_states, /scene, quick answers
MAX_MESSAGE_CHARS = 1000  # longest answer message, log line or event message [characters]


class MotionPlannerNode(Node):
    """Relocation feasibility and execution service on top of the STPIK planner."""

    def __init__(self) -> None:
        super().__init__('motion_planner')
        defaults = PlannerConfig()
        for name, (low, high, text) in RANGES.items():
            desc = range_descriptor(text, low, high, integer=name in INTEGER_FIELDS)
            self.declare_parameter(name, getattr(defaults, name), desc)
        for name, (value, low, high, text) in EXTRA.items():
            self.declare_parameter(name, value, range_descriptor(text, low, high))
        self.add_on_set_parameters_callback(self._on_parameters)
        self._lock = threading.Lock()  # swaps of the planner (held for an assignment only)
        self._plan_lock = threading.Lock()  # held while planning: one STPIK state per planner
        self._waiting = threading.BoundedSemaphore(MAX_WAITING_PLANS)
        self._scene_lock = threading.Lock()  # one /scene handled at a time
        self._executing = False  # under self._lock
        self._deferred_scene: Scene | None = None  # under self._lock
        self._planner: MotionPlanner | None = None
        self._scene_error = ''
        self._geometry: tuple | None = None
        self._original: dict[str, ObjectSpec] = {}  # objects as last seen IN_CLUTTER
        # Own groups, so that waiting requests never hold back the state, scene or attach answer.
        self.create_subscription(
            Scene,
            '/scene',
            self._on_scene,
            SCENE_QOS,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )
        self._execution = Execution(self)  # open or closed loop (execution_mode)
        self._event_pub = self.create_publisher(
            PlanningEvent, '/motion_planner/events', EVENTS_QOS
        )
        self.create_service(
            RelocateObject,
            '/relocate_object',
            self._on_relocate,
            qos_profile=SERVICE_QOS,  # a burst of requests is queued, never dropped (#18)
            callback_group=ReentrantCallbackGroup(),
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

    def _on_scene(self, msg: Scene) -> None:
        self._execution.on_scene(msg)  # the live scene of the closed loop
        with self._lock:
            if self._executing:  # the sim moves the carried object: rebuild once released
                self._deferred_scene = msg
                return
        with self._scene_lock:
            self._rebuild(msg)

    def _rebuild(self, msg: Scene) -> None:
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
        self._original = {o.id: o for o in scenario.objects} if planner else {}
        if planner is not None:
            self.get_logger().info(f'scene {msg.scenario_name!r}: planner rebuilt')

    def _on_relocate(self, request, response):
        received = time.monotonic()
        relocated = list(request.relocated_ids)
        result = self._answer(request.object_id, relocated, received)
        if result.feasible and request.execute:
            result = self._execute(result, request.object_id, relocated)
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

    def _answer(self, object_id: str, relocated: list[str], received: float) -> PlanResult:
        """Validate and answer from the cache at once; plan (waiting for the planner) if needed."""
        planner = self._planner
        if planner is None:
            return self._no_planner()
        answer = planner.precheck(object_id, relocated)
        if answer is not None:
            return answer
        wait_s = self.get_parameter('request_timeout_s').value
        if not self._waiting.acquire(blocking=False):
            return PlanResult(
                False,
                Reason.PLANNER_BUSY,
                f'planner busy: {MAX_WAITING_PLANS} requests are already waiting for it',
            )
        try:
            remaining_s = max(0.0, received + wait_s - time.monotonic())
            if not self._plan_lock.acquire(timeout=remaining_s):
                return PlanResult(
                    False,
                    Reason.PLANNER_BUSY,
                    f'planner busy: not free within request_timeout_s={wait_s:.1f} s',
                )
            try:
                planner = self._planner  # the scene may have changed while waiting
                if planner is None:
                    return self._no_planner()
                return planner.check(object_id, relocated)  # may now be in the cache
            finally:
                self._plan_lock.release()
        finally:
            self._waiting.release()

    def _no_planner(self) -> PlanResult:
        reason = Reason.INVALID_SCENE if self._scene_error else Reason.NO_SCENE
        return PlanResult(False, reason, self._scene_error or 'no /scene received yet')

    def _execute(self, result: PlanResult, object_id: str, relocated: list[str]) -> PlanResult:
        with self._lock:
            busy, self._executing = self._executing, True
        if busy:
            return dataclasses.replace(
                result,
                feasible=False,
                reason=Reason.EXECUTION_FAILED,
                message='another relocation is being executed',
            )
        try:
            return self._execution.follow(result, object_id, relocated)
        finally:
            with self._lock:
                self._executing = False
                deferred, self._deferred_scene = self._deferred_scene, None
            if deferred is not None:
                self._on_scene(deferred)


def main(args: list[str] | None = None) -> None:
    """Run the node until SIGINT/SIGTERM (exit code 0)."""
    executor = lambda context: MultiThreadedExecutor(EXECUTOR_THREADS, context=context)  # noqa: E731
    sys.exit(run_node(MotionPlannerNode, args=args, make_executor=executor))


if __name__ == '__main__':
    main()
