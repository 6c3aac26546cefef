"""Execution of a planned relocation on the simulator or a real arm (``motion_planner`` node).

:class:`TrajectoryExecution` streams the trajectory on the ``trajectory_topic`` parameter's topic
(default ``/joint_trajectory``, the simulator's; on a real arm a ``joint_trajectory_controller``'s
``~/joint_trajectory``) segment by segment (approach, carry, retreat), waits on
``joint_state_topic`` (default ``/joint_states``) until the arm reaches each segment's last sample,
and attaches and releases the object through the ``attach_service`` (default
``/jaco2_sim/attach_object``, a ``qtree_msgs/srv/AttachObject`` server). The three names are
read-only parameters declared here. It reads the node's ``execution_timeout_s``,
``joint_state_timeout_s`` and ``goal_tolerance_rad`` parameters at every segment.

Cancel (#18): ``~/cancel_execution`` (std_srvs/Trigger, e.g. the task planner cancelling its
goal) stops the arm at once with an empty trajectory on ``trajectory_topic`` (the sim holds its
position), and the running execution ends with ``EXECUTION_FAILED`` "execution canceled" within
one 20 ms poll; no further segment is sent (the check and the publication of a segment are
atomic with the stop).

A grasp refused by the attach service (``success=false``) is answered ``GRASP_FAILED`` after the
arm went back along the approach (:mod:`.undo`, #32); an attach service that does not answer
stays ``EXECUTION_FAILED``.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
from jaco2_description.model import ARM_JOINTS
from qtree_msgs.msg import ObjectState
from qtree_msgs.srv import AttachObject
from qtree_node_support.qos import SERVICE_QOS, STATE_QOS, TRAJECTORY_QOS
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from stpik_motion_planner.conversions import trajectory_msg
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.scene_checks import format_id
from stpik_motion_planner.state_watch import SilenceWatch, arrived
from stpik_motion_planner.undo import UNDONE, reversed_samples

ENDPOINTS = {  # read-only parameters of the node: name -> (default, description)
    'trajectory_topic': (
        '/joint_trajectory',
        'trajectory_msgs/JointTrajectory topic the arm follows (a joint_trajectory_controller: '
        '/<controller>/joint_trajectory)',
    ),
    'joint_state_topic': ('/joint_states', 'sensor_msgs/JointState topic of the arm'),
    'attach_service': (
        '/jaco2_sim/attach_object',
        'qtree_msgs/srv/AttachObject server that grasps (attach) and releases the object',
    ),
}
ATTACH_SERVICE_WAIT_S = 5.0  # longest wait for the attach service to appear [s]
ATTACH_ANSWER_WAIT_S = 10.0  # longest wait for its answer [s]
REFUSED, NO_ANSWER = 'refused', 'no answer'  # attach call outcomes besides ''


class TrajectoryExecution:
    """Streams a feasible :class:`PlanResult` to the simulator; owned by the node.

    One execution at a time: the node guarantees it (``EXECUTION_FAILED`` for another).

    Attributes:
        q: last arm configuration from /joint_states, shape (7,) [rad]; None before the first.
        speed: largest |arm joint velocity| of the last /joint_states [rad/s]; None when it
            carries no velocities.
        state_time: ``time.monotonic()`` of the last /joint_states [s].
    """

    def __init__(self, node: Node) -> None:
        """Create the publisher and client on ``node``; /joint_states only while executing.

        Args:
            node: the node owning the entities and the execution parameters.
        """
        self._node = node
        for name, (default, text) in ENDPOINTS.items():
            node.declare_parameter(
                name, default, ParameterDescriptor(description=text, read_only=True)
            )
        self.endpoints = {name: node.get_parameter(name).value for name in ENDPOINTS}
        self.q: np.ndarray | None = None
        self.speed: float | None = None
        self.state_time = -math.inf
        # /joint_states only while executing: at 100 Hz its executor wake-ups alone kept one core
        # busy (rclpy's Python executor), which slowed planning 10-50x under load.
        self._state_group = MutuallyExclusiveCallbackGroup()
        self._trajectory_pub = node.create_publisher(
            JointTrajectory, self.endpoints['trajectory_topic'], TRAJECTORY_QOS
        )
        self._canceled = threading.Event()  # set by ~/cancel_execution, cleared by follow()
        self._running = False
        self._stop_lock = threading.Lock()  # a segment is sent, or the stop; never both crossed
        node.create_service(
            Trigger,
            '~/cancel_execution',
            self._on_cancel,
            qos_profile=SERVICE_QOS,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )
        self._attach = node.create_client(
            AttachObject,
            self.endpoints['attach_service'],
            qos_profile=SERVICE_QOS,
            callback_group=MutuallyExclusiveCallbackGroup(),
        )

    def follow(self, result: PlanResult, object_id: str) -> PlanResult:
        """Execute ``result`` with ``object_id`` attached between grasp and release.

        Args:
            result: a feasible plan (times [s], joint trajectory [rad], grasp/release indices).
            object_id: the object to attach at the grasp sample and release at the release one.

        Returns:
            ``result`` when executed, else a copy with ``EXECUTION_FAILED`` and why.
        """
        self.q, self.state_time = None, -math.inf
        with self._stop_lock:
            self._canceled.clear()
            self._running = True
        states = self._node.create_subscription(
            JointState,
            self.endpoints['joint_state_topic'],
            self._on_joint_states,
            STATE_QOS,
            callback_group=self._state_group,
        )
        try:
            return self._follow_segments(result, object_id)
        finally:
            self._running = False
            self._node.destroy_subscription(states)

    def _on_cancel(self, _request: Trigger.Request, response: Trigger.Response):
        """Stop the arm now (empty /joint_trajectory) and end the running execution."""
        with self._stop_lock:
            running = self._running
            self._canceled.set()
            self._halt()
        response.success = True
        response.message = 'execution canceled, arm stopped' if running else 'arm stopped'
        self._node.get_logger().info(f'cancel_execution: {response.message}')
        return response

    def _halt(self) -> None:
        """Stop the arm where it is: an empty /joint_trajectory (the sim holds its position)."""
        self._trajectory_pub.publish(JointTrajectory(joint_names=list(ARM_JOINTS)))

    def _on_joint_states(self, msg: JointState) -> None:
        index = {n: i for i, n in enumerate(msg.name)}
        if all(n in index for n in ARM_JOINTS):
            self.q = np.array([msg.position[index[n]] for n in ARM_JOINTS])
            self.speed = arm_speed(msg)
            self.state_time = time.monotonic()

    def _follow_segments(self, result: PlanResult, object_id: str) -> PlanResult:
        g, r = result.grasp_index, result.release_index
        steps = [(0, g, True), (g, r, False), (r, len(result.times) - 1, None)]
        for start, end, attach in steps:
            times = result.times[start : end + 1] - result.times[start]
            segment = trajectory_msg(times, result.joint_trajectory[start : end + 1])
            with self._stop_lock:
                if not self._canceled.is_set():
                    self._trajectory_pub.publish(segment)
            failure = self._reach(result.joint_trajectory[end], times[-1])
            if failure:
                return result.failed(
                    Reason.EXECUTION_FAILED, f'the sim did not reach sample {end}: {failure}'
                )
            if attach is None or self._canceled.is_set():
                continue
            outcome, text = self._attach_call(object_id, attach)
            if outcome == REFUSED and attach:  # #32: undone, the caller may re-plan
                return self._grasp_failed(result, object_id, text)
            if outcome:
                return result.failed(
                    Reason.EXECUTION_FAILED,
                    f'attach_object({format_id(object_id)}, {attach}) failed: {text}',
                )
        return result

    def _grasp_failed(self, result: PlanResult, object_id: str, text: str) -> PlanResult:
        """Open loop: back along the approach to its first sample; GRASP_FAILED (#32)."""
        why = f'the attach service refused {format_id(object_id)}: {text}'
        t_grasp = result.times[result.grasp_index]
        times, joints = reversed_samples(result.times, result.joint_trajectory, t_grasp, 0.0)
        with self._stop_lock:
            if not self._canceled.is_set():
                self._trajectory_pub.publish(trajectory_msg(times, joints))
        failure = self._reach(joints[-1], times[-1])
        if failure:
            why = f'{why}; the arm could not go back: {failure}'
            return result.failed(Reason.EXECUTION_FAILED, why)
        return result.failed(Reason.GRASP_FAILED, f'{why}; {UNDONE}')

    def _reach(self, q_goal: np.ndarray, duration: float) -> str:
        """Wait until the arm is at rest at ``q_goal`` [rad], ``duration`` [s] being the segment's
        (:func:`~stpik_motion_planner.state_watch.arrived`).

        Returns:
            '' when reached, else why not.
        """
        node = self._node
        timeout = node.get_parameter('execution_timeout_s').value + duration
        silence_s = node.get_parameter('joint_state_timeout_s').value
        tolerance = node.get_parameter('goal_tolerance_rad').value
        start = time.monotonic()
        watch = SilenceWatch()
        watch.start(start)
        while True:
            now = time.monotonic()
            if self._canceled.is_set():
                return 'execution canceled'
            if arrived(self.q, self.speed, q_goal, tolerance, now - start, duration):
                return ''
            silent = watch.silence(self.state_time, now)
            if silent > silence_s:
                return (
                    f'the simulator stopped publishing {self.endpoints["joint_state_topic"]} '
                    f'(none for {silent:.1f} s, '
                    f'joint_state_timeout_s={silence_s:.1f})'
                )
            if now - start > timeout:
                return f'not within {timeout:.1f} s (execution_timeout_s + segment duration)'
            time.sleep(0.02)

    def _call_attach(self, object_id: str, attach: bool) -> bool:
        """Attach (True) or release (False) ``object_id``; whether the simulator agreed."""
        return not self._attach_call(object_id, attach)[0]

    def _attach_call(
        self, object_id: str, attach: bool, status: int = ObjectState.STATUS_RELOCATED
    ) -> tuple[str, str]:
        """Attach or release ``object_id`` (``status``: ObjectState.STATUS_* after a release).

        Returns:
            ``('', message)`` when done, ``(REFUSED, message)`` when the server answered
            ``success=false`` (a failed grasp: #32), ``(NO_ANSWER, why)`` otherwise.
        """
        if not self._attach.wait_for_service(timeout_sec=ATTACH_SERVICE_WAIT_S):
            return NO_ANSWER, f'{self.endpoints["attach_service"]} not available'
        request = AttachObject.Request(
            object_id=object_id, attach=attach, status_after_release=status
        )
        future = self._attach.call_async(request)
        deadline = time.monotonic() + ATTACH_ANSWER_WAIT_S
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        if not future.done() or future.result() is None:
            return NO_ANSWER, f'no answer in {ATTACH_ANSWER_WAIT_S:g} s'
        answer = future.result()
        return ('' if answer.success else REFUSED), answer.message


def arm_speed(msg: JointState) -> float | None:
    """Largest |velocity| of the 7 arm joints in ``msg`` [rad/s]; None without velocities."""
    if len(msg.velocity) != len(msg.name):
        return None
    index = {n: i for i, n in enumerate(msg.name)}
    if not all(n in index for n in ARM_JOINTS):
        return None
    return max(abs(float(msg.velocity[index[n]])) for n in ARM_JOINTS)
