"""Execution of a planned relocation on ``jaco2_sim``, for the ``motion_planner`` node.

:class:`TrajectoryExecution` streams the trajectory on ``/joint_trajectory`` segment by segment
(approach, carry, retreat), waits on ``/joint_states`` until the arm reaches each segment's last
sample, and attaches and releases the object through ``/jaco2_sim/attach_object``. It reads the
node's ``execution_timeout_s``, ``joint_state_timeout_s`` and ``goal_tolerance_rad``
parameters at every segment.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from jaco2_description.model import ARM_JOINTS
from qtree_msgs.msg import ObjectState
from qtree_msgs.srv import AttachObject
from qtree_node_support.qos import SERVICE_QOS
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from stpik_motion_planner.conversions import trajectory_msg
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.scene_checks import format_id

STATE_QOS = QoSProfile(depth=10)
ATTACH_SERVICE_WAIT_S = 5.0  # longest wait for /jaco2_sim/attach_object to appear [s]
ATTACH_ANSWER_WAIT_S = 10.0  # longest wait for its answer [s]


class TrajectoryExecution:
    """Streams a feasible :class:`PlanResult` to the simulator; owned by the node.

    One execution at a time: the node guarantees it (``EXECUTION_FAILED`` for another).

    Attributes:
        q: last arm configuration from /joint_states, shape (7,) [rad]; None before the first.
        state_time: ``time.monotonic()`` of the last /joint_states [s].
    """

    def __init__(self, node: Node) -> None:
        """Create the publisher and client on ``node``; /joint_states only while executing.

        Args:
            node: the node owning the entities and the execution parameters.
        """
        self._node = node
        self.q: np.ndarray | None = None
        self.state_time = -math.inf
        # /joint_states only while executing: at 100 Hz its executor wake-ups alone kept one core
        # busy (rclpy's Python executor), which slowed planning 10-50x under load.
        self._state_group = MutuallyExclusiveCallbackGroup()
        self._trajectory_pub = node.create_publisher(JointTrajectory, '/joint_trajectory', 10)
        self._attach = node.create_client(
            AttachObject,
            '/jaco2_sim/attach_object',
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
        states = self._node.create_subscription(
            JointState,
            '/joint_states',
            self._on_joint_states,
            STATE_QOS,
            callback_group=self._state_group,
        )
        try:
            return self._follow_segments(result, object_id)
        finally:
            self._node.destroy_subscription(states)

    def _on_joint_states(self, msg: JointState) -> None:
        index = {n: i for i, n in enumerate(msg.name)}
        if all(n in index for n in ARM_JOINTS):
            self.q = np.array([msg.position[index[n]] for n in ARM_JOINTS])
            self.state_time = time.monotonic()

    def _follow_segments(self, result: PlanResult, object_id: str) -> PlanResult:
        g, r = result.grasp_index, result.release_index
        steps = [(0, g, True), (g, r, False), (r, len(result.times) - 1, None)]
        for start, end, attach in steps:
            times = result.times[start : end + 1] - result.times[start]
            self._trajectory_pub.publish(
                trajectory_msg(times, result.joint_trajectory[start : end + 1])
            )
            failure = self._reach(result.joint_trajectory[end], times[-1])
            if failure:
                return dataclasses.replace(
                    result,
                    feasible=False,
                    reason=Reason.EXECUTION_FAILED,
                    message=f'the sim did not reach sample {end}: {failure}',
                )
            if attach is not None and not self._call_attach(object_id, attach):
                return dataclasses.replace(
                    result,
                    feasible=False,
                    reason=Reason.EXECUTION_FAILED,
                    message=f'attach_object({format_id(object_id)}, {attach}) failed',
                )
        return result

    def _reach(self, q_goal: np.ndarray, duration: float) -> str:
        """Wait until the arm is at ``q_goal`` [rad], ``duration`` [s] being the segment's.

        Returns:
            '' when reached, else why not.
        """
        node = self._node
        timeout = node.get_parameter('execution_timeout_s').value + duration
        silence_s = node.get_parameter('joint_state_timeout_s').value
        tolerance = node.get_parameter('goal_tolerance_rad').value
        start = time.monotonic()
        while True:
            now = time.monotonic()
            if self.q is not None and np.max(np.abs(self.q - q_goal)) < tolerance:
                return ''
            silent = now - max(self.state_time, start)
            if silent > silence_s:
                return (
                    f'the simulator stopped publishing /joint_states (none for {silent:.1f} s, '
                    f'joint_state_timeout_s={silence_s:.1f})'
                )
            if now - start > timeout:
                return f'not within {timeout:.1f} s (execution_timeout_s + segment duration)'
            time.sleep(0.02)

    def _call_attach(self, object_id: str, attach: bool) -> bool:
        """Attach (True) or release (False) ``object_id``; whether the simulator agreed."""
        if not self._attach.wait_for_service(timeout_sec=ATTACH_SERVICE_WAIT_S):
            return False
        request = AttachObject.Request(
            object_id=object_id, attach=attach, status_after_release=ObjectState.STATUS_RELOCATED
        )
        future = self._attach.call_async(request)
        deadline = time.monotonic() + ATTACH_ANSWER_WAIT_S
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        return future.done() and future.result() is not None and future.result().success
