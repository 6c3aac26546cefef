"""One ``RetrieveTarget`` goal of the ``task_planner`` node, from its request to its result code.

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

Execution in a changing world (#32, :mod:`.replanning`): a step answered SCENE_CHANGED or
GRASP_FAILED (undone by the motion planner), a step no longer feasible, or a scene change between
two steps does not end the goal: the relocations done are kept, the rest is learned again from
the current /scene with the goal's planner and executed, at most ``max_replans`` times (then
REPLAN_LIMIT); no sequence from the new state -> NO_SOLUTION saying what changed; a target no
longer in the clutter -> NO_SOLUTION. Feedback and result carry ``replans``,
``replan_causes`` and ``reused_answers`` (per re-plan: questions answered from the answers the
motion planner kept across the change, :class:`~.replanning.ReuseCounter`).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from qtree_msgs.action import RetrieveTarget
from qtree_node_support.parameters import range_descriptor
from qtree_node_support.ranges import range_problem
from qtree_scene.changes import clutter_objects, scene_changes
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult

from qtree_task_planner.conversions import (
    feedback_msg,
    holds_object,
    movable_from_scene,
    relocated_ids,
)
from qtree_task_planner.exceptions import (
    InvalidParameterError,
    InvalidScenarioError,
    OracleUnavailableError,
)
from qtree_task_planner.goal_checks import GoalSettings, settings_from_goal
from qtree_task_planner.replanning import PrefixOracle, combined, kept_prefix
from qtree_task_planner.ros_oracle import RosPlannerOracle
from qtree_task_planner.sequence_execution import CANCELED, FAILED, OK, SequenceExecution
from qtree_task_planner.trainers import make_trainer
from qtree_task_planner.training import STOP_CANCELLED

Result = RetrieveTarget.Result
TIMEOUTS = {  # name: (default [s], description)
    'planner_timeout_s': (30.0, 'timeout of one feasibility RelocateObject call [s]'),
    'planner_wait_s': (10.0, 'wait for the /relocate_object service at goal start [s]'),
    'execute_timeout_s': (180.0, 'timeout of one RelocateObject call with execute=true [s]'),
    'scene_wait_s': (10.0, 'wait for a /scene message at goal start [s]'),
}
TIMEOUT_RANGE_S = (0.1, 3600.0)


def timeout_descriptor(description: str) -> ParameterDescriptor:
    """Descriptor of a timeout parameter in :data:`TIMEOUT_RANGE_S` [s]."""
    return range_descriptor(description, *TIMEOUT_RANGE_S, integer=False)


def check_parameters(params: list) -> SetParametersResult:
    """The on-set-parameters answer: every timeout a float in :data:`TIMEOUT_RANGE_S`."""
    for param in params:
        if param.name not in TIMEOUTS:
            continue
        problem = range_problem(param.value, *TIMEOUT_RANGE_S)
        if problem is None and not isinstance(param.value, float):
            problem = 'must be a float'  # the parameters are declared as doubles
        if problem is not None:
            reason = f'{param.name} {problem} s, got {param.value!r}'
            return SetParametersResult(successful=False, reason=reason)
    return SetParametersResult(successful=True)


@dataclass
class GoalContext:
    """What a goal needs from the node.

    Attributes:
        scene: the last /scene message (None before the first).
        planner: the /relocate_object client.
        param: a timeout parameter by name [s].
        stopping: set when the node shuts down (ends a training at once).
        publish_stats: ``(stats, policy name)`` → /training_stats.
        publish_tree: ``(tree, episode)`` → /qtree.
        execution: runs the learned sequence (stops the arm on cancel).
        oracle: the running goal's planner oracle (its ``retries``), None before training.
        replan_causes: the running goal's re-plans, the cause of each (#32).
        reused_answers: per re-plan whose training ended, its questions answered from the
            answers the motion planner kept across the change (#32 item 4).
    """

    scene: Callable[[], Any]
    planner: Any
    param: Callable[[str], float]
    stopping: threading.Event
    publish_stats: Callable[[Any, str], None]
    publish_tree: Callable[[Any, int], None]
    execution: SequenceExecution
    oracle: RosPlannerOracle | None = None
    replan_causes: list[str] = field(default_factory=list)
    reused_answers: list[int] = field(default_factory=list)


def run_goal(goal_handle: Any, ctx: GoalContext) -> tuple[int, str, Any, bool]:
    """Train (and execute, re-planning when the world changes: #32) for one goal.

    Returns:
        ``(error_code, message, TrainingResult or None, executed)``.
    """
    try:
        settings = settings_from_goal(goal_handle.request)
    except InvalidParameterError as err:
        return Result.INVALID_GOAL, str(err), None, False
    if not wait_for(lambda: ctx.scene() is not None, ctx.param('scene_wait_s')):
        msg = 'no /scene received (is the simulator or a scene publisher running?)'
        return Result.MOTION_PLANNER_UNAVAILABLE, msg, None, False
    scene = ctx.scene()
    try:
        movable, target = movable_from_scene(scene)
    except InvalidScenarioError as err:
        return Result.NO_SOLUTION, str(err), None, False
    if not ctx.planner.wait_for_service(timeout_sec=ctx.param('planner_wait_s')):
        msg = 'service /relocate_object not available'
        return Result.MOTION_PLANNER_UNAVAILABLE, msg, None, False
    ctx.oracle = RosPlannerOracle(
        ctx.planner,
        ctx.param('planner_timeout_s'),
        ctx.param('scene_wait_s'),
        ctx.stopping,
        scene_name=scene.scenario_name,
    )
    code, message, result = train(goal_handle, ctx, settings, movable, target, ctx.oracle)
    if code != Result.SUCCESS or not settings.execute:
        return code, message, result, False
    code, message, result, executed = execute_with_replans(
        goal_handle, ctx, settings, result, scene
    )
    return code, (f'{message}, executed' if executed else message), result, executed


def train(
    goal_handle: Any,
    ctx: GoalContext,
    settings: GoalSettings,
    movable: tuple[str, ...],
    target: str,
    oracle: Any,
) -> tuple[int, str, Any]:
    """Learn a sequence of ``movable`` ending with ``target``: ``(code, message, result)``."""
    trainer = make_trainer(movable, target, oracle, settings.config)
    every = settings.feedback_every

    def on_episode(stats) -> bool:
        ctx.publish_stats(stats, trainer.policy.name)
        if stats.episode % every == 0:
            feedback = feedback_msg(stats, ctx.replan_causes, ctx.reused_answers)
            goal_handle.publish_feedback(feedback)
            ctx.publish_tree(trainer.tree, stats.episode)
        return not (goal_handle.is_cancel_requested or ctx.stopping.is_set())

    try:
        result = trainer.run(on_episode)
    except OracleUnavailableError as err:
        partial = trainer.result('motion_planner_unavailable')
        return Result.MOTION_PLANNER_UNAVAILABLE, str(err), partial
    finally:
        ctx.publish_tree(trainer.tree, trainer.episode)
    if result.stop_reason == STOP_CANCELLED:
        return Result.CANCELED, f'canceled after {result.episodes} episodes', result
    if not result.sequence:
        msg = f'no feasible sequence learned in {result.episodes} episodes'
        return Result.NO_SOLUTION, msg, result
    summary = (
        f'{result.policy}: {list(result.sequence)} after {result.episodes} episodes, '
        f'{result.mp_calls} MP calls ({result.stop_reason})'
    )
    return Result.SUCCESS, summary, result


def execute_with_replans(
    goal_handle: Any, ctx: GoalContext, settings: GoalSettings, first: Any, scene: Any
) -> tuple[int, str, Any, bool]:
    """Execute the learned sequence; on a re-plan cause (:mod:`.replanning`) keep what was
    executed, learn the rest again from the current /scene and go on, ``max_replans`` times.

    Args:
        goal_handle: the RetrieveTarget goal being executed (feedback, cancel).
        ctx: the node's goal context (parameters, scene, execution, stop flag).
        settings: the goal's validated settings (planner, ``max_replans``, ...).
        first: the training result of the goal's scene.
        scene: the /scene message that training was made on.
    """
    results, prefix = [first], tuple[str, ...]()
    timeout_s = ctx.param('execute_timeout_s')
    while True:
        changed = scene_watch(ctx.scene, scene)
        status, error = ctx.execution.run(
            results[-1].sequence, timeout_s, ctx.stopping, prefix=prefix, changed=changed
        )
        total = combined(results, prefix)
        if status == OK:
            n = len(ctx.replan_causes)
            replans = f'; {n} re-plans, followed {list(total.sequence)}' if n else ''
            summary = (
                f'{total.policy}: {list(first.sequence)} after {first.episodes} episodes, '
                f'{first.mp_calls} MP calls ({first.stop_reason}){replans}'
            )
            return Result.SUCCESS, summary, total, True
        if status == CANCELED:
            return Result.CANCELED, error, total, False
        if status == FAILED:
            return Result.EXECUTION_FAILED, error, total, False
        if len(ctx.replan_causes) >= settings.max_replans:
            why = f'max_replans={settings.max_replans} re-plans made, one more needed: {error}'
            return Result.REPLAN_LIMIT, why, total, False
        ctx.replan_causes.append(error)
        goal_handle.publish_feedback(feedback_msg(None, ctx.replan_causes, ctx.reused_answers))
        n = len(ctx.replan_causes)
        publish = getattr(ctx.execution, 'publish_replan', None)  # /task_planner/replans
        done_ids = list(ctx.execution.executed)
        if publish is not None:
            publish(replan=n, phase='started', cause=error, kept_ids=done_ids, reused_answers=-1,
                    planner_runs=-1)  # fmt: skip
        # the scene once the undone relocation has put its object down (no object GRASPED)
        wait_for(lambda: not holds_object(ctx.scene()), ctx.param('scene_wait_s'))
        scene = ctx.scene()
        prefix = kept_prefix(ctx.execution.executed, relocated_ids(scene))
        try:
            movable, target = movable_from_scene(scene)
        except InvalidScenarioError as err:
            return Result.NO_SOLUTION, f'after {error}: {err}', total, False
        oracle = PrefixOracle(ctx.oracle, prefix)
        reuse = getattr(ctx.oracle, 'reuse', None)  # a ReuseCounter (RosPlannerOracle)
        if reuse is not None:
            reuse.reset()  # count this training's answers kept across the change
        code, message, result = train(goal_handle, ctx, settings, movable, target, oracle)
        if reuse is not None:
            ctx.reused_answers.append(reuse.reused)
        if publish is not None:
            done = code == Result.SUCCESS
            publish(replan=n, phase='planned' if done else 'failed', cause=error,
                    kept_ids=list(prefix), sequence=list(result.sequence) if done else [],
                    reused_answers=reuse.reused if reuse is not None else -1,
                    planner_runs=result.planner_runs if result is not None else -1)  # fmt: skip
        if result is not None:
            results.append(result)
        if code == Result.NO_SOLUTION:
            kept = f'{len(prefix)} relocations kept {list(prefix)}'
            message = f'after {error}: no sequence from the current state ({kept}): {message}'
        if code != Result.SUCCESS:
            return code, message, combined(results, prefix), False


def scene_watch(scene: Callable[[], Any], baseline: Any) -> Callable[[list[str]], list[str]]:
    """``changed(executed)``: what changed in the clutter of ``scene()`` since ``baseline``
    (a /scene message), the objects in ``executed`` left out (they are carried away).
    """
    before = clutter_objects(baseline)

    def changed(executed: list[str]) -> list[str]:
        kept = {k: v for k, v in before.items() if k not in executed}
        return scene_changes(kept, clutter_objects(scene(), set(executed)))

    return changed


def end_goal(goal_handle: Any, code: int, stopping: threading.Event) -> str:
    """Succeed, cancel or abort ``goal_handle`` by ``code``; '' or why it ended by shutdown.

    Raises:
        Exception: the goal handle failed while the node is not shutting down.
    """
    try:
        if code == Result.SUCCESS:
            goal_handle.succeed()
        elif code == Result.CANCELED and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        else:  # failures, and a training ended by the node shutting down
            goal_handle.abort()
    except Exception as err:  # the context is gone when the node shuts down mid-goal
        if not stopping.is_set():
            raise
        return f'goal ended by shutdown: {err}'
    return ''


def wait_for(predicate: Callable[[], bool], timeout_s: float) -> bool:
    """Poll ``predicate`` every 50 ms for up to ``timeout_s`` [s]; its last value."""
    event = threading.Event()
    while not predicate() and timeout_s > 0:
        event.wait(0.05)
        timeout_s -= 0.05
    return predicate()
