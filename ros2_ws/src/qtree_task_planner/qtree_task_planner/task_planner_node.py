"""ROS 2 node ``task_planner``: the Q-Tree learner served as the ``/retrieve_target`` action.

Parameters, entities and callbacks; one goal is run by
:func:`~qtree_task_planner.goal_run.run_goal` (threading and failure behaviour: there).
"""

from __future__ import annotations

import sys
import threading
from typing import Any

from qtree_msgs.action import RetrieveTarget
from qtree_msgs.msg import QTree as QTreeMsg
from qtree_msgs.msg import Scene, TrainingStats
from qtree_msgs.srv import RelocateObject
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import LATCHED_QOS, SERVICE_QOS, STATS_QOS, action_server_qos
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from qtree_task_planner.conversions import result_msg, stats_msg, tree_msg
from qtree_task_planner.goal_run import (
    TIMEOUTS,
    GoalContext,
    check_parameters,
    end_goal,
    run_goal,
    timeout_descriptor,
)
from qtree_task_planner.sequence_execution import SequenceExecution

Result = RetrieveTarget.Result


class TaskPlannerNode(Node):
    """Serves RetrieveTarget goals (failure behaviour: :mod:`qtree_task_planner.goal_run`)."""

    def __init__(self) -> None:
        super().__init__('task_planner')
        for name, (default, description) in TIMEOUTS.items():
            self.declare_parameter(name, default, timeout_descriptor(description))
        self.add_on_set_parameters_callback(check_parameters)
        self._group = ReentrantCallbackGroup()
        self._scene: Scene | None = None
        self._busy = threading.Lock()
        self.stopping = threading.Event()  # set on shutdown: a running training ends at once
        self.context.on_shutdown(self.stopping.set)
        self.create_subscription(Scene, '/scene', self._on_scene, LATCHED_QOS)
        self._stats_pub = self.create_publisher(TrainingStats, '/training_stats', STATS_QOS)
        self._tree_pub = self.create_publisher(QTreeMsg, '/qtree', LATCHED_QOS)
        self._planner = self.create_client(
            RelocateObject, '/relocate_object', qos_profile=SERVICE_QOS, callback_group=self._group
        )
        self._execution = SequenceExecution(self, self._planner)  # stops the arm on cancel
        self._active = None  # the running goal's handle
        self._goal_context = GoalContext(
            scene=lambda: self._scene,
            planner=self._planner,
            param=lambda name: float(self.get_parameter(name).value),
            stopping=self.stopping,
            publish_stats=self._publish_stats,
            publish_tree=self._publish_tree,
            execution=self._execution,
        )
        self._server = ActionServer(
            self,
            RetrieveTarget,
            '/retrieve_target',
            execute_callback=self._execute,
            cancel_callback=self._on_cancel,
            callback_group=self._group,
            **action_server_qos(),
        )
        self.get_logger().info('task planner ready: action /retrieve_target')

    def _on_scene(self, msg: Scene) -> None:
        self._scene = msg

    def _publish_stats(self, stats, policy: str) -> None:
        self._stats_pub.publish(stats_msg(stats, policy, self.get_clock().now().to_msg()))

    def _publish_tree(self, tree, episode: int) -> None:
        self._tree_pub.publish(tree_msg(tree, episode, self.get_clock().now().to_msg()))

    def _on_cancel(self, goal_handle) -> CancelResponse:
        if goal_handle is self._active:  # training: per episode; execution: the arm stops now
            self._execution.cancel()
        return CancelResponse.ACCEPT

    def _execute(self, goal_handle) -> RetrieveTarget.Result:
        if not self._busy.acquire(blocking=False):
            goal_handle.abort()
            return result_msg(None, error_code=Result.INVALID_GOAL, message='busy with a goal')
        self._active, self._goal_context.oracle = goal_handle, None
        self._goal_context.replan_causes, self._goal_context.reused_answers = [], []
        self._execution.reset()
        try:
            code, message, result, executed = run_goal(goal_handle, self._goal_context)
        except Exception as err:  # a bug must end the goal with a reason, never hang the client
            self.get_logger().error(f'goal failed with an internal error: {err!r}')
            code, message, result, executed = (
                Result.INTERNAL_ERROR,
                f'internal error: {err}',
                None,
                False,
            )
        finally:
            self._busy.release()
        self.get_logger().info(f'goal finished: {message}')
        msg = result_msg(result, error_code=code, message=message, executed=executed)
        msg.executed_ids = list(self._execution.executed)
        oracle = self._goal_context.oracle
        msg.planner_retries = oracle.retries if oracle else 0
        msg.replan_causes = list(self._goal_context.replan_causes)
        msg.replans = len(msg.replan_causes)
        msg.reused_answers = list(self._goal_context.reused_answers)
        ended = end_goal(goal_handle, code, self.stopping)
        if ended:
            self.get_logger().info(ended)
        return msg


def run(args: list[str] | None = None, **options: Any) -> int:
    """Run the node until SIGINT/SIGTERM (0); a running training ends at once."""
    executor = lambda context: MultiThreadedExecutor(4, context=context)  # noqa: E731
    cleanup = lambda node: node.stopping.set()  # noqa: E731 - frees the training's thread
    return run_node(TaskPlannerNode, args=args, make_executor=executor, cleanup=cleanup, **options)


def main(args: list[str] | None = None) -> None:
    """Entry point: exit with the code of :func:`run`."""
    sys.exit(run(args))


if __name__ == '__main__':
    main()
