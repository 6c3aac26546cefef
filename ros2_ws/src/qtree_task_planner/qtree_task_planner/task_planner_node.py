"""ROS 2 node ``task_planner``: the Q-Tree learner served as the ``/retrieve_target`` action.

Training runs inside the (synchronous) execute callback on a MultiThreadedExecutor; every new tree
edge is one ``/relocate_object`` call (execute=false) made with ``call_async`` and waited for on a
threading.Event, so the response is handled by another executor thread.

Failure behaviour (result ``error_code`` and ``message`` always say why; the node keeps running):
invalid goal field -> INVALID_GOAL (accepted then aborted, the message names the field); another
goal running -> INVALID_GOAL ("busy"); no /scene in time, no /relocate_object service, a call
timing out or a request rejected by the planner (reason 1xx, e.g. unknown object) ->
MOTION_PLANNER_UNAVAILABLE, with the statistics learned so far in the result; scene
without a target in the clutter or no sequence learned -> NO_SOLUTION; cancel -> CANCELED (checked
once per episode; during the execution the arm stops at once, result ``executed_ids``); an
execution step failing -> EXECUTION_FAILED.
"""

from __future__ import annotations

import sys
import threading

from qtree_msgs.action import RetrieveTarget
from qtree_msgs.msg import QTree as QTreeMsg
from qtree_msgs.msg import Scene, TrainingStats
from qtree_msgs.srv import RelocateObject
from qtree_node_support.lifecycle import run_node
from qtree_node_support.qos import SERVICE_QOS, action_server_qos
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from qtree_task_planner.exceptions import (
    InvalidParameterError,
    InvalidScenarioError,
    OracleUnavailableError,
)
from qtree_task_planner.goal import settings_from_goal
from qtree_task_planner.messages import (
    feedback_msg,
    movable_from_scene,
    result_msg,
    stats_msg,
    tree_msg,
)
from qtree_task_planner.ros_oracle import RosPlannerOracle
from qtree_task_planner.sequence_execution import CANCELED, FAILED, SequenceExecution
from qtree_task_planner.training import STOP_CANCELLED, QTreeTrainer

LATCHED_QOS = QoSProfile(  # /scene and /qtree: late joiners get the last message
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
STATS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)  # bursts of episodes
Result = RetrieveTarget.Result
_TIMEOUTS = {  # name: (default [s], description)
    'planner_timeout_s': (30.0, 'timeout of one feasibility RelocateObject call [s]'),
    'planner_wait_s': (10.0, 'wait for the /relocate_object service at goal start [s]'),
    'execute_timeout_s': (180.0, 'timeout of one RelocateObject call with execute=true [s]'),
    'scene_wait_s': (10.0, 'wait for a /scene message at goal start [s]'),
}


class TaskPlannerNode(Node):
    """Serves RetrieveTarget goals (see the module docstring for the failure behaviour)."""

    def __init__(self) -> None:
        super().__init__('task_planner')
        for name, (default, description) in _TIMEOUTS.items():
            rng = FloatingPointRange(from_value=0.1, to_value=3600.0)
            descriptor = ParameterDescriptor(description=description, floating_point_range=[rng])
            self.declare_parameter(name, default, descriptor)
        self.add_on_set_parameters_callback(self._check_parameters)
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
        self._server = ActionServer(
            self,
            RetrieveTarget,
            '/retrieve_target',
            execute_callback=self._execute,
            cancel_callback=self._on_cancel,
            callback_group=self._group,
            **action_server_qos(),
        )
        self._execution = SequenceExecution(self, self._planner)  # stops the arm on cancel
        self._active, self._oracle = None, None  # the running goal's handle and oracle
        self.get_logger().info('task planner ready: action /retrieve_target')

    def _check_parameters(self, params: list) -> SetParametersResult:
        for param in params:
            if param.name in _TIMEOUTS and not (
                isinstance(param.value, float) and 0.1 <= param.value <= 3600.0
            ):
                reason = f'{param.name} must be a float in [0.1, 3600] s, got {param.value!r}'
                return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _on_scene(self, msg: Scene) -> None:
        self._scene = msg

    def _param(self, name: str) -> float:
        return float(self.get_parameter(name).value)

    def _on_cancel(self, goal_handle) -> CancelResponse:
        if goal_handle is self._active:  # training: per episode; execution: the arm stops now
            self._execution.cancel()
        return CancelResponse.ACCEPT

    def _execute(self, goal_handle) -> Result:
        if not self._busy.acquire(blocking=False):
            goal_handle.abort()
            return result_msg(None, error_code=Result.INVALID_GOAL, message='busy with a goal')
        self._active, self._oracle = goal_handle, None
        self._execution.reset()
        try:
            code, message, result, executed = self._run(goal_handle)
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
        msg.planner_retries = self._oracle.retries if self._oracle else 0
        try:
            if code == Result.SUCCESS:
                goal_handle.succeed()
            elif code == Result.CANCELED and goal_handle.is_cancel_requested:
                goal_handle.canceled()
            else:  # failures, and a training ended by the node shutting down
                goal_handle.abort()
        except Exception as err:  # the context is gone when the node shuts down mid-goal
            if not self.stopping.is_set():
                raise
            self.get_logger().info(f'goal ended by shutdown: {err}')
        return msg

    def _run(self, goal_handle) -> tuple:
        try:
            settings = settings_from_goal(goal_handle.request)
        except InvalidParameterError as err:
            return Result.INVALID_GOAL, str(err), None, False
        deadline_ok = self._wait_for(lambda: self._scene is not None, self._param('scene_wait_s'))
        if not deadline_ok:
            msg = 'no /scene received (is jaco2_sim running?)'
            return Result.MOTION_PLANNER_UNAVAILABLE, msg, None, False
        try:
            movable, target = movable_from_scene(self._scene)
        except InvalidScenarioError as err:
            return Result.NO_SOLUTION, str(err), None, False
        if not self._planner.wait_for_service(timeout_sec=self._param('planner_wait_s')):
            msg = 'service /relocate_object not available'
            return Result.MOTION_PLANNER_UNAVAILABLE, msg, None, False
        oracle = self._oracle = RosPlannerOracle(
            self._planner,
            self._param('planner_timeout_s'),
            self._param('scene_wait_s'),
            self.stopping,
        )
        trainer = QTreeTrainer(movable, target, oracle, settings.config)
        every = settings.feedback_every

        def on_episode(stats) -> bool:
            now = self.get_clock().now().to_msg()
            self._stats_pub.publish(stats_msg(stats, trainer.policy.name, now))
            if stats.episode % every == 0:
                goal_handle.publish_feedback(feedback_msg(stats))
                self._tree_pub.publish(tree_msg(trainer.tree, stats.episode, now))
            return not (goal_handle.is_cancel_requested or self.stopping.is_set())

        try:
            result = trainer.run(on_episode)
        except OracleUnavailableError as err:
            partial = trainer.result('motion_planner_unavailable')
            return Result.MOTION_PLANNER_UNAVAILABLE, str(err), partial, False
        finally:
            stamp = self.get_clock().now().to_msg()
            self._tree_pub.publish(tree_msg(trainer.tree, trainer.episode, stamp))
        if result.stop_reason == STOP_CANCELLED:
            return Result.CANCELED, f'canceled after {result.episodes} episodes', result, False
        if not result.sequence:
            msg = f'no feasible sequence learned in {result.episodes} episodes'
            return Result.NO_SOLUTION, msg, result, False
        summary = (
            f'{result.policy}: {list(result.sequence)} after {result.episodes} episodes, '
            f'{result.mp_calls} MP calls ({result.stop_reason})'
        )
        if not settings.execute:
            return Result.SUCCESS, summary, result, False
        timeout_s = self._param('execute_timeout_s')
        status, error = self._execution.run(result.sequence, timeout_s, self.stopping)
        if status == CANCELED:
            return Result.CANCELED, error, result, False
        if status == FAILED:
            return Result.EXECUTION_FAILED, error, result, False
        return Result.SUCCESS, summary + ', executed', result, True

    def _wait_for(self, predicate, timeout_s: float) -> bool:
        event = threading.Event()
        while not predicate() and timeout_s > 0:
            event.wait(0.05)
            timeout_s -= 0.05
        return predicate()


def main(args: list[str] | None = None) -> None:
    """Run the node until SIGINT/SIGTERM (exit code 0); a running training ends at once."""
    executor = lambda context: MultiThreadedExecutor(4, context=context)  # noqa: E731
    cleanup = lambda node: node.stopping.set()  # noqa: E731 - frees the training's thread
    sys.exit(run_node(TaskPlannerNode, args=args, make_executor=executor, cleanup=cleanup))


if __name__ == '__main__':
    main()
