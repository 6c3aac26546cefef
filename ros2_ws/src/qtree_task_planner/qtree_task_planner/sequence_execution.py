"""Execution of a learned sequence on the arm, for the ``task_planner`` node; cancellable (#18).

:class:`SequenceExecution` relocates the objects one RelocateObject call (execute=true) at a
time. A cancel of the goal (:meth:`SequenceExecution.cancel`) ends it at once: the arm is stopped
with an empty ``/joint_trajectory`` (the sim holds its position) and
``/motion_planner/cancel_execution``, sent again every ``CANCEL_REPEAT_S`` until the motion
planner answers the running relocation (it may still be planning when the cancel arrives), at
most ``CANCEL_CONFIRM_S``. What was executed before is kept in :attr:`executed`.

A world changing under the execution (#32) ends a run with ``'replan'`` and the cause
(:func:`~.replanning.replan_cause`): a ``SCENE_CHANGED`` or ``GRASP_FAILED`` answer (the motion
planner undid that relocation), a step answered infeasible, or the ``changed`` check before a
step naming what moved since the sequence was learned. The goal then re-plans the rest and
publishes each re-plan on ``/task_planner/replans`` (:meth:`SequenceExecution.publish_replan`,
``qtree_msgs/ReplanEvent``) for the recording and the Rerun view.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from jaco2_description.model import ARM_JOINTS
from qtree_msgs.msg import ReplanEvent
from qtree_msgs.srv import RelocateObject
from qtree_node_support.qos import SERVICE_QOS, TRAJECTORY_QOS
from qtree_node_support.text import quote
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from qtree_task_planner.replanning import replan_cause
from qtree_task_planner.ros_oracle import wait_for_future

CANCEL_REPEAT_S = 0.2  # period of the stop while the running relocation has not answered [s]
CANCEL_CONFIRM_S = 5.0  # longest wait for the motion planner to confirm the stop [s]
OK, CANCELED, FAILED, REPLAN = 'ok', 'canceled', 'failed', 'replan'


@dataclass
class _AnyOf:
    """Set when any of the events is set (the stop argument of :func:`wait_for_future`)."""

    events: tuple[threading.Event, ...]

    def is_set(self) -> bool:
        return any(e.is_set() for e in self.events)


class SequenceExecution:
    """Relocates a learned sequence on the arm through ``/relocate_object``; owned by the node.

    Attributes:
        executed: ids relocated on the arm by the last :meth:`run`, in order.
    """

    def __init__(self, node: Node, client) -> None:
        """Create the stop publisher and the cancel client on ``node``.

        Args:
            node: the task planner node.
            client: its ``/relocate_object`` client.
        """
        self._client = client
        self._canceled = threading.Event()
        self._stop_pub = node.create_publisher(
            JointTrajectory, '/joint_trajectory', TRAJECTORY_QOS
        )
        self._replan_pub = node.create_publisher(ReplanEvent, '/task_planner/replans', 10)
        self._clock = node.get_clock()
        self._cancel_client = node.create_client(
            Trigger,
            '/motion_planner/cancel_execution',
            qos_profile=SERVICE_QOS,
            callback_group=ReentrantCallbackGroup(),
        )
        self.executed: list[str] = []

    def publish_replan(self, **fields) -> None:
        """Publish one :class:`ReplanEvent` on /task_planner/replans (#32), stamped now."""
        self._replan_pub.publish(ReplanEvent(stamp=self._clock.now().to_msg(), **fields))

    def reset(self) -> None:
        """Forget a cancel of a previous goal (call at goal start)."""
        self._canceled.clear()
        self.executed = []

    def cancel(self) -> None:
        """Cancel the running :meth:`run` (thread-safe; returns at once)."""
        self._canceled.set()

    def run(
        self,
        sequence: tuple[str, ...],
        timeout_s: float,
        stop: threading.Event,
        prefix: tuple[str, ...] = (),
        changed: Callable[[list[str]], list[str]] | None = None,
    ) -> tuple[str, str]:
        """Relocate each object of ``sequence`` on the arm, unless canceled or failing.

        Args:
            sequence: object ids in relocation order.
            timeout_s: longest wait for one relocation [s].
            stop: set when the node is shutting down; ends a wait at once.
            prefix: ids relocated before (kept from an earlier run; in every request).
            changed: ``changed(executed ids)`` before each step: what changed in the scene
                since ``sequence`` was learned (empty: nothing).

        Returns:
            (``'ok'`` | ``'canceled'`` | ``'failed'`` | ``'replan'``, message or cause);
            :attr:`executed` lists what was relocated, ``prefix`` first.
        """
        self.executed = list(prefix)
        interrupted = _AnyOf((stop, self._canceled))
        for object_id in sequence:
            if self._canceled.is_set():
                return CANCELED, f'canceled before {quote(object_id)} (executed {self.executed})'
            changes = changed(self.executed) if changed is not None else []
            if changes:
                return REPLAN, f'scene changed before relocating {quote(object_id)}: ' + (
                    ', '.join(changes)
                )
            request = RelocateObject.Request(
                object_id=object_id, relocated_ids=list(self.executed), execute=True
            )
            future = self._client.call_async(request)
            done = wait_for_future(future, timeout_s, interrupted)
            if self._canceled.is_set() and not (done and self._succeeded(future)):
                self._stop_arm(future)
                return CANCELED, (
                    f'canceled during the relocation of {quote(object_id)}: arm stopped '
                    f'(executed {self.executed})'
                )
            if not done or future.result() is None:
                return FAILED, f'executing {quote(object_id)}: no answer in {timeout_s} s'
            answer = future.result()
            if not answer.feasible:
                cause = replan_cause(object_id, answer.reason, answer.message)
                if cause is not None:
                    return REPLAN, cause
                return FAILED, f'executing {quote(object_id)} failed: {answer.message}'
            self.executed.append(object_id)
        return OK, ''

    @staticmethod
    def _succeeded(future) -> bool:
        return future.result() is not None and bool(future.result().feasible)

    def _stop_arm(self, pending) -> None:
        """Stop the arm until the motion planner answered ``pending`` (or CANCEL_CONFIRM_S)."""
        deadline = time.monotonic() + CANCEL_CONFIRM_S
        while True:
            self._stop_pub.publish(JointTrajectory(joint_names=list(ARM_JOINTS)))
            if self._cancel_client.service_is_ready():
                self._cancel_client.call_async(Trigger.Request())
            if pending.done() or time.monotonic() > deadline:
                return
            wait_for_future(pending, CANCEL_REPEAT_S, threading.Event())
