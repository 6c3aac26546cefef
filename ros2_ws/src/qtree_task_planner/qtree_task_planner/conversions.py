"""Conversions between the core's data and qtree_msgs messages (node side; no rclpy import)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from qtree_msgs.action import RetrieveTarget
from qtree_msgs.msg import ObjectState, QTreeEdge, Scene, TrainingStats
from qtree_msgs.msg import QTree as QTreeMsg

from qtree_task_planner.exceptions import InvalidScenarioError
from qtree_task_planner.extraction import extract, path_of
from qtree_task_planner.training import EpisodeStats, TrainingResult
from qtree_task_planner.tree import QTree


def movable_from_scene(scene: Scene) -> tuple[tuple[str, ...], str]:
    """The action set from a /scene message: obstacles still in clutter, then the target.

    Returns:
        (movable ids, target id), obstacles in message order.

    Raises:
        InvalidScenarioError: no target, several targets, the target is not in the clutter, or
            duplicate ids.
    """
    targets = [o for o in scene.objects if o.role == ObjectState.ROLE_TARGET]
    if len(targets) != 1:
        raise InvalidScenarioError(
            f'scene {scene.scenario_name!r} has {len(targets)} targets, expected exactly one'
        )
    target = targets[0]
    if target.status != ObjectState.STATUS_IN_CLUTTER:
        raise InvalidScenarioError(f'target {target.id!r} is not in the clutter any more')
    obstacles = tuple(
        o.id
        for o in scene.objects
        if o.role == ObjectState.ROLE_OBSTACLE and o.status == ObjectState.STATUS_IN_CLUTTER
    )
    ids = (*obstacles, target.id)
    if len(set(ids)) != len(ids):
        raise InvalidScenarioError(f'scene {scene.scenario_name!r} has duplicate object ids')
    return ids, target.id


def stats_msg(stats: EpisodeStats, policy: str, stamp: Any) -> TrainingStats:
    """A /training_stats message from one episode's statistics."""
    return TrainingStats(
        stamp=stamp,
        policy=policy,
        episode=stats.episode,
        nodes=stats.nodes,
        edges=stats.edges,
        mp_calls=stats.mp_calls,
        planner_runs=stats.planner_runs,
        q_bar=float(stats.q_bar),
        epsilon=float(stats.epsilon),
        episode_sequence=list(stats.sequence),
        reached_target=stats.reached_target,
        best_sequence=list(stats.best_sequence),
    )


def feedback_msg(
    stats: EpisodeStats | None, replan_causes: Sequence[str] = (), reused: Sequence[int] = ()
) -> RetrieveTarget.Feedback:
    """Action feedback from one episode's statistics (None: only the re-plans, #32), with the
    answers reused by each re-plan whose training ended (``reused``).
    """
    msg = RetrieveTarget.Feedback(
        replans=len(replan_causes),
        replan_causes=list(replan_causes),
        reused_answers=[int(n) for n in reused],
    )
    if stats is not None:
        msg.episode, msg.nodes, msg.edges = stats.episode, stats.nodes, stats.edges
        msg.mp_calls, msg.best_sequence = stats.mp_calls, list(stats.best_sequence)
        msg.q_bar, msg.epsilon = float(stats.q_bar), float(stats.epsilon)
    return msg


def relocated_ids(scene: Scene) -> list[str]:
    """Ids of the objects a /scene message shows RELOCATED, in message order."""
    return [o.id for o in scene.objects if o.status == ObjectState.STATUS_RELOCATED]


def holds_object(scene: Scene) -> bool:
    """Whether an object of a /scene message is GRASPED (an execution is not settled)."""
    return any(o.status == ObjectState.STATUS_GRASPED for o in scene.objects)


def tree_msg(tree: QTree, episode: int, stamp: Any) -> QTreeMsg:
    """A /qtree snapshot: every node (ids joined by ',') and edge; the edges of the extracted
    sequence (eq. 19, or the best known one when eq. 19 finds none) are marked on_best_path.
    """
    index = {node.key: i for i, node in enumerate(tree.nodes())}
    best = {(edge.parent, edge.action) for edge in path_of(tree, extract(tree)[0])}
    edges = [
        QTreeEdge(
            parent=index[edge.parent],
            child=index[edge.child],
            object_id=edge.action,
            q=float(edge.q),
            reward=float(edge.reward),
            on_best_path=(edge.parent, edge.action) in best,
        )
        for edge in tree.edges()
    ]
    sequences = [','.join(node.sequence) for node in tree.nodes()]
    return QTreeMsg(stamp=stamp, episode=episode, node_sequences=sequences, edges=edges)


def result_msg(
    result: TrainingResult | None, *, error_code: int, message: str, executed: bool = False
) -> RetrieveTarget.Result:
    """The action result; training statistics are kept even when the goal failed."""
    msg = RetrieveTarget.Result(
        success=error_code == RetrieveTarget.Result.SUCCESS,
        error_code=error_code,
        message=message,
        executed=executed,
        first_optimal_episode=-1,
        first_learned_level_episode=-1,
        extraction='none',
    )
    if result is not None:
        msg.sequence = list(result.sequence)
        msg.episodes = result.episodes
        msg.mp_calls = result.mp_calls
        msg.planner_runs = result.planner_runs
        msg.first_optimal_episode = result.first_optimal_episode
        msg.converged = result.converged
        msg.training_time = float(result.wall_time_s)
        msg.extraction = result.extraction
        msg.first_learned_level_episode = result.first_learned_level_episode
    return msg
