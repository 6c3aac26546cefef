"""Closed-loop execution on ``jaco2_sim`` for the ``motion_planner`` node (paper Sect. 3.1).

:class:`Execution` declares ``execution_mode`` (``closed_loop``, the default, or ``open_loop``)
and the :class:`~stpik_motion_planner.execution_config.ExecutionConfig` parameters. In
``open_loop`` it behaves as :class:`~stpik_motion_planner.execution.TrajectoryExecution` (whole
segments on ``/joint_trajectory``). In ``closed_loop`` a timer at ``control_rate_hz``, in its own
callback group, runs one :class:`~stpik_motion_planner.closed_loop.ClosedLoopController` step
from each new ``/joint_states`` (a tick without a new measurement does nothing, so a starved
subscription never makes the loop integrate on a stale state) and the live ``/scene``, streams
the joint reference as ``sensor_msgs/JointState`` on ``command_topic`` (default
``/joint_command``) and publishes a ``qtree_msgs/TrackingState`` on
``/motion_planner/tracking``. The service thread only waits for each segment's end and attaches /
releases the object in between.

On a stop (tracking lost, a set-based task that cannot hold, a joint state with missing or extra
joints, no joint state for ``joint_state_timeout_s``) the arm is commanded to hold its last
measured position and the relocation is answered ``EXECUTION_FAILED`` with the reason.

Execution in a changing world (#32): until the object is released, every new /scene is compared
with the scene at the start of the execution
(:func:`qtree_scene.changes.changes_under_relocation`: the objects in the clutter, the one being
relocated too until it leaves the clutter, so a target moved under its own approach is seen);
on a change the arm stops at once, before the
controller's clearance check of that tick (so a newcomer is seen as a change, not a near miss),
the relocation is undone (:mod:`.undo`: back along the executed path, a carried object put back
down) and answered ``SCENE_CHANGED`` naming the objects; a grasp refused by the attach service is
answered ``GRASP_FAILED`` the same way. If the way back is blocked too, ``EXECUTION_FAILED``.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pinocchio as pin
from jaco2_description.model import ARM_JOINTS, Jaco2Model
from qtree_msgs.msg import ObjectState, Scene, TrackingState
from qtree_node_support.parameters import range_descriptor
from qtree_node_support.qos import STATE_QOS
from qtree_scene.changes import changes_under_relocation, clutter_objects, standing_objects
from qtree_scene.message import scenario_from_msg
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import JointState

from stpik_motion_planner.closed_loop import (
    ClosedLoopController,
    ControlTick,
    ExecutionStopped,
    PlannedMotion,
    measured_q,
    segments,
)
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import RANGES, PlannerConfig
from stpik_motion_planner.conversions import command_msg
from stpik_motion_planner.conversions import xyzquat_pose_msg as pose_msg
from stpik_motion_planner.exceptions import InvalidConfig
from stpik_motion_planner.execution import REFUSED, TrajectoryExecution, arm_speed
from stpik_motion_planner.execution_config import (
    EXECUTION_RANGES,
    ExecutionConfig,
    check_execution_value,
    check_mode,
)
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.scene_checks import format_id
from stpik_motion_planner.state_watch import ProgressWatch, SilenceWatch
from stpik_motion_planner.undo import UNDONE, reversed_samples

SCENE_FRAME = 'j2s7s300_link_base'  # frame of the EE poses in TrackingState
SEGMENT_POLL_S = 0.1  # how often the service thread looks at a segment's progress [s]


class Execution(TrajectoryExecution):
    """Open- or closed-loop execution of a feasible plan; owned by the node."""

    def __init__(self, node: Node) -> None:
        super().__init__(node)
        node.declare_parameter('execution_mode', 'closed_loop')
        node.declare_parameter('command_topic', '/joint_command')
        defaults = ExecutionConfig()
        for name, (low, high, text) in EXECUTION_RANGES.items():
            descriptor = range_descriptor(text, low, high, integer=False)
            node.declare_parameter(name, getattr(defaults, name), descriptor)
        node.add_on_set_parameters_callback(self._on_parameters)
        check_mode(node.get_parameter('execution_mode').value)
        self._config()  # refuse bad start-up values at once
        self.robot = Jaco2Model()
        self._command_pub = node.create_publisher(
            JointState, node.get_parameter('command_topic').value, STATE_QOS
        )
        self._tracking_pub = node.create_publisher(TrackingState, '/motion_planner/tracking', 10)
        self._timer_group = MutuallyExclusiveCallbackGroup()
        self._lock = threading.Lock()  # controller, scene and outcome between the two threads
        self._segment_end = threading.Event()
        self._controller: ClosedLoopController | None = None
        self._scene_msg: Scene | None = None
        self._scene_dirty = False
        self._object_id = ''
        self._removed: set[str] = set()
        self._last_state_time = -math.inf  # /joint_states time of the last control step [s]
        self._watch = SilenceWatch()  # /joint_states silence, not counting our own stalls
        self._stopped = ''
        self._stop_reason = Reason.EXECUTION_FAILED
        self._watched: dict | None = None  # clutter at the start, watched until the release
        self._state_error = ''

    def _config(self) -> ExecutionConfig:
        return ExecutionConfig(**{n: self._node.get_parameter(n).value for n in EXECUTION_RANGES})

    def _on_parameters(self, params: list) -> SetParametersResult:
        try:
            for p in params:
                if p.name == 'execution_mode':
                    check_mode(p.value)
                elif p.name in EXECUTION_RANGES:
                    check_execution_value(p.name, p.value)
                elif p.name == 'command_topic':
                    raise InvalidConfig(p.name, p.value, 'fixed at start')
        except InvalidConfig as err:
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def on_scene(self, msg: Scene) -> None:
        """The live scene (every /scene message, also while executing)."""
        with self._lock:
            self._scene_msg, self._scene_dirty = msg, True

    def follow(
        self, result: PlanResult, object_id: str, relocated: list[str] | tuple = ()
    ) -> PlanResult:
        """Execute ``result`` in the mode of ``execution_mode``.

        Args:
            result: a feasible plan.
            object_id: the object relocated.
            relocated: the request's relocated ids: left out of the live scene, as the planner
                left them out of its scene (Assumption 2).
        """
        self._state_error = ''
        self._removed = {*relocated, object_id}
        return super().follow(result, object_id)

    def _on_joint_states(self, msg: JointState) -> None:
        try:
            self.q = measured_q(msg.name, msg.position)
            self.speed = arm_speed(msg)
            self.state_time = time.monotonic()
        except ExecutionStopped as err:
            self._state_error = str(err)

    def _follow_segments(self, result: PlanResult, object_id: str) -> PlanResult:
        if self._node.get_parameter('execution_mode').value == 'open_loop':
            return super()._follow_segments(result, object_id)
        failure, reason = self._closed_loop(result, object_id)
        if not failure:
            return result
        return result.failed(reason, failure)

    def _closed_loop(self, result: PlanResult, object_id: str) -> tuple[str, Reason]:
        """Run every segment; ('', SUCCESS) when executed, else (why not, reason)."""
        node, config = self._node, self._config()
        silence_s = node.get_parameter('joint_state_timeout_s').value
        deadline = time.monotonic() + silence_s
        while self.q is None and not self._state_error and time.monotonic() < deadline:
            time.sleep(0.01)
        if self.q is None:
            why = self._state_error or f'no /joint_states within {silence_s:.1f} s'
            return why, Reason.EXECUTION_FAILED
        planner_config = PlannerConfig(**{n: node.get_parameter(n).value for n in RANGES})
        with self._lock:
            self._object_id, self._stopped = object_id, ''
            self._stop_reason = Reason.EXECUTION_FAILED
            msg = self._scene_msg
            self._watched = None if msg is None else clutter_objects(msg)
            self._controller = ClosedLoopController(
                self.robot, self._live_scene(), planner_config, config
            )
            self._scene_dirty = False
            self._last_state_time = -math.inf
            self._watch.start(time.monotonic())
        motion = PlannedMotion(result.times, result.joint_trajectory, self.robot)
        timer = node.create_timer(config.period, self._on_tick, callback_group=self._timer_group)
        try:
            q_ref = np.array(self.q)
            for index, (start, end, attach) in enumerate(segments(result)):
                if self._stopped:  # e.g. canceled while attaching (#18)
                    return self._stopped, self._stop_reason
                if index == 2:  # released: placed, nothing to undo; the retreat is finished
                    with self._lock:
                        self._watched = None
                if self._run_segment(motion, start, end, q_ref):
                    return self._undone(result, motion, object_id, index)
                last = self._live_controller.q_ref  # set by begin()
                q_ref = q_ref if last is None else last
                failure, reason = self._grasp_or_release(object_id, attach)
                if failure:
                    self._stop(failure, reason)
                    return self._undone(result, motion, object_id, index)
            return '', Reason.SUCCESS
        finally:
            timer.cancel()
            node.destroy_timer(timer)
            with self._lock:
                self._controller = None

    @property
    def _live_controller(self) -> ClosedLoopController:
        """The controller of the execution in progress (only used during one)."""
        if self._controller is None:
            raise RuntimeError('no execution in progress')
        return self._controller

    def _run_segment(self, motion: PlannedMotion, start: int, end: int, q_ref: np.ndarray) -> str:
        """Track samples ``start`` to ``end`` of ``motion``; '' when done, else the stop.

        The loop moves the reference one control period per tick, so a loaded machine that
        ticks late takes longer than the plan (the README demo ticked at 27 Hz instead of 100:
        S1's first segment then ran 2.7x the plan's time and a fixed "duration +
        execution_timeout_s" wait ended the goal). The wait ends when the reference time has
        not advanced for ``execution_timeout_s`` (the controller stops a stalled or unsettled
        arm itself sooner: ``settle_timeout_s``).
        """
        timeout = self._node.get_parameter('execution_timeout_s').value
        self._segment_end.clear()
        with self._lock:
            self._live_controller.begin(motion, start, end, q_ref)
        watch = ProgressWatch(self._live_controller.plan_time, time.monotonic())
        while not self._segment_end.wait(SEGMENT_POLL_S):
            plan_time = self._live_controller.plan_time
            if watch.stalled_for(plan_time, time.monotonic()) > timeout:
                self._stop(
                    f'segment to sample {end} made no progress for {timeout:.1f} s '
                    f'(execution_timeout_s; at {plan_time:.2f} s of '
                    f'{motion.times[end]:.2f} s of the plan)'
                )
        c = self._live_controller
        self._node.get_logger().info(
            f'segment to sample {end} {"stopped" if self._stopped else "done"}: {c.ticks} ticks, '
            f'worst EE error {c.worst_error_m * 1e3:.1f} mm / {c.worst_error_rad:.3f} rad, '
            f'round trip {c.observer.latency_ticks} ticks'
        )
        return self._stopped

    def _undone(
        self, result: PlanResult, motion: PlannedMotion, object_id: str, segment: int
    ) -> tuple[str, Reason]:
        """After a stop in ``segment``: undo a SCENE_CHANGED / GRASP_FAILED one (:mod:`.undo`).

        Returns:
            (the answer's message, its reason): the stop's reason when undone, else
            EXECUTION_FAILED naming the stop and why the arm could not go back.
        """
        why, reason = self._stopped, self._stop_reason
        if reason not in (Reason.SCENE_CHANGED, Reason.GRASP_FAILED) or segment > 1:
            return why, Reason.EXECUTION_FAILED if reason == Reason.SUCCESS else reason
        with self._lock:
            self._stopped, self._watched = '', None
            t_stop = self._live_controller.plan_time
            self._live_controller.set_scene(self._live_scene())
            self._scene_dirty = False
        t_grasp = float(result.times[result.grasp_index])
        failure, put_back = '', ''
        if segment == 1:  # carrying: back to the grasp, the object put down where it was
            failure = self._back(motion, t_stop, t_grasp)
            if not failure:
                outcome, text = self._attach_call(object_id, False, ObjectState.STATUS_IN_CLUTTER)
                failure = f'release of {format_id(object_id)} failed: {text}' if outcome else ''
                put_back = f', {format_id(object_id)} put back in the clutter where it was grasped'
            if not failure:
                with self._lock:
                    self._live_controller.detach()
            t_stop = t_grasp
        failure = failure or self._back(motion, t_stop, float(result.times[0]))
        if failure:
            return f'{why}; the arm could not go back: {failure}', Reason.EXECUTION_FAILED
        return f'{why}; {UNDONE}{put_back}', reason

    def _back(self, motion: PlannedMotion, t_from: float, t_to: float) -> str:
        """Go back along ``motion`` from plan time ``t_from`` to ``t_to`` [s]; '' or the stop."""
        times, joints = reversed_samples(motion.times, motion.joints, t_from, t_to)
        backwards = PlannedMotion(times, joints, self.robot)
        return self._run_segment(backwards, 0, len(times) - 1, np.array(self.q))

    def _grasp_or_release(self, object_id: str, attach: bool | None) -> tuple[str, Reason]:
        if attach is None:
            return '', Reason.SUCCESS
        outcome, text = self._attach_call(object_id, attach)
        if outcome == REFUSED and attach:
            why = f'the attach service refused {format_id(object_id)}: {text}'
            return why, Reason.GRASP_FAILED
        if outcome:
            why = f'attach_object({format_id(object_id)}, {attach}) failed: {text}'
            return why, Reason.EXECUTION_FAILED
        with self._lock:
            if not attach:
                self._live_controller.detach()
                return '', Reason.SUCCESS
            found = self._scene_object(object_id)
            if found is None:
                return f'{format_id(object_id)} is not in the last /scene', Reason.EXECUTION_FAILED
            spec, pose = found
            self._live_controller.attach(spec, pose, np.array(self.q))
        return '', Reason.SUCCESS

    def _on_tick(self) -> None:
        """One control tick (timer thread)."""
        with self._lock:
            controller = self._controller
            if controller is None or self._stopped or controller.phase in ('done', 'idle'):
                return
            silence_s = self._node.get_parameter('joint_state_timeout_s').value
            silent = self._watch.silence(self.state_time, time.monotonic())
            if self._canceled.is_set():  # ~/cancel_execution (the sim got an empty trajectory)
                self._stop_locked('execution canceled')
                return
            if self._state_error:
                self._stop_locked(f'bad /joint_states: {self._state_error}')
                return
            if self.state_time <= self._last_state_time:  # no new measurement: wait for it
                if silent > silence_s:
                    self._stop_locked(
                        f'the simulator stopped publishing /joint_states (none for '
                        f'{silent:.1f} s, joint_state_timeout_s={silence_s:.1f})'
                    )
                return
            self._last_state_time = self.state_time
            try:
                if self._scene_dirty:
                    changes = self._scene_changes()
                    if changes:  # #32: before this tick's clearance check
                        why = f'scene changed under the execution: {", ".join(changes)}'
                        self._stop_locked(why, Reason.SCENE_CHANGED)
                        return
                    controller.set_scene(self._live_scene())
                    self._scene_dirty = False
                tick = controller.step(np.array(self.q))
            except ExecutionStopped as err:
                self._stop_locked(str(err))
                return
            except Exception as err:  # a bad scene or state must not kill the node
                self._stop_locked(f'unexpected {type(err).__name__}: {err}')
                return
        self._command_pub.publish(command_msg(tick.q_ref))
        self._tracking_pub.publish(self._tracking_msg(tick, ''))
        if tick.phase == 'done':
            self._segment_end.set()

    def _halt(self) -> None:
        """Cancel (#18): also end a running closed loop, holding the measured position."""
        super()._halt()
        if self._controller is not None:
            self._stop('execution canceled')

    def _stop(self, why: str, reason: Reason = Reason.EXECUTION_FAILED) -> None:
        with self._lock:
            self._stop_locked(why, reason)

    def _stop_locked(self, why: str, reason: Reason = Reason.EXECUTION_FAILED) -> None:
        """Hold the last measured position, publish the stop, wake the service thread."""
        if self._stopped:
            return
        self._stopped = f'closed loop stopped: {why}'
        self._stop_reason = reason
        self._node.get_logger().warning(self._stopped)
        if self.q is not None:
            self._command_pub.publish(command_msg(self.q))
        msg = TrackingState(object_id=self._object_id, phase='stopped', message=self._stopped)
        msg.header.stamp = self._node.get_clock().now().to_msg()
        self._tracking_pub.publish(msg)
        self._segment_end.set()

    def _scene_changes(self) -> list[str]:
        """What changed in the clutter since the execution started (none once released)."""
        if self._watched is None or self._scene_msg is None:
            return []
        now = clutter_objects(self._scene_msg)
        in_scene = any(o.id == self._object_id for o in self._scene_msg.objects)
        return changes_under_relocation(self._watched, now, self._object_id, in_scene)

    def _live_scene(self) -> SceneWorld:
        """Every object the arm must clear (:func:`qtree_scene.changes.standing_objects`): the
        clutter but the request's relocated ones (the planner left them out too) and the objects
        already placed on their drop slots, where they really stand (#29 point 5: they were left
        out; the planner's slot envelopes hold them). Not the object being relocated: carried,
        it is part of the arm; released, the retreat starts from it (the planner checked it).
        """
        msg = self._scene_msg
        if msg is None:
            return SceneWorld([])
        return SceneWorld(standing_objects(msg, self._object_id, self._removed).values())

    def _scene_object(self, object_id: str):
        msg = self._scene_msg
        if msg is None:
            return None
        for spec, o in zip(scenario_from_msg(msg).objects, msg.objects, strict=True):
            if spec.id == object_id:
                p, r = o.pose.position, o.pose.orientation
                return spec, pin.XYZQUATToSE3(np.array([p.x, p.y, p.z, r.x, r.y, r.z, r.w]))
        return None

    def _tracking_msg(self, tick: ControlTick, message: str) -> TrackingState:
        msg = TrackingState(
            object_id=self._object_id,
            phase=tick.phase,
            plan_time=tick.plan_time,
            joint_names=list(ARM_JOINTS),
            reference=[float(v) for v in tick.q_ref],
            measured=[float(v) for v in tick.q_meas],
            ee_reference=pose_msg(tick.ee_ref),
            ee_measured=pose_msg(tick.ee_meas),
            error_m=tick.error_m,
            error_rad=tick.error_rad,
            clearance_m=tick.clearance_m,
            active_tasks=list(tick.active),
            step_time_s=tick.step_s,
            message=message,
        )
        msg.header.stamp = self._node.get_clock().now().to_msg()
        msg.header.frame_id = SCENE_FRAME
        return msg
