"""Message conversions of the node (qtree_msgs only, no rclpy)."""

import pytest
from builtin_interfaces.msg import Time
from qtree_msgs.action import RetrieveTarget
from qtree_msgs.msg import ObjectState, Scene
from qtree_task_planner.conversions import movable_from_scene, result_msg, tree_msg
from qtree_task_planner.exceptions import InvalidScenarioError
from qtree_task_planner.testing import TOY_MOVABLE, toy_oracle
from qtree_task_planner.training import TrainingConfig, train
from qtree_task_planner.tree import QTree


def _scene(*objects: tuple[str, int, int]) -> Scene:
    return Scene(
        scenario_name='t', objects=[ObjectState(id=i, role=r, status=s) for i, r, s in objects]
    )


def test_movable_ids_are_obstacles_in_clutter_then_target() -> None:
    ob, tg, st = ObjectState.ROLE_OBSTACLE, ObjectState.ROLE_TARGET, ObjectState.ROLE_STATIC
    moved = ObjectState.STATUS_RELOCATED
    scene = _scene(('T', tg, 0), ('O1', ob, 0), ('table', st, 0), ('O2', ob, moved), ('O3', ob, 0))
    assert movable_from_scene(scene) == (('O1', 'O3', 'T'), 'T')


@pytest.mark.parametrize(
    ('objects', 'match'),
    [
        ([('O1', ObjectState.ROLE_OBSTACLE, 0)], '0 targets'),
        ([('T', ObjectState.ROLE_TARGET, 0), ('U', ObjectState.ROLE_TARGET, 0)], '2 targets'),
        ([('T', ObjectState.ROLE_TARGET, ObjectState.STATUS_RELOCATED)], 'not in the clutter'),
        ([('T', ObjectState.ROLE_TARGET, 0), ('T', ObjectState.ROLE_OBSTACLE, 0)], 'duplicate'),
    ],
)
def test_bad_scenes_are_explained(objects: list, match: str) -> None:
    with pytest.raises(InvalidScenarioError, match=match):
        movable_from_scene(_scene(*objects))


def test_tree_snapshot_marks_the_best_path() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    tree.add_edge((), 'O1', 0.0)
    tree.add_edge((), 'T', -1.0)
    tree.add_edge(('O1',), 'T', 100.0)
    tree.update(tree.node(()).children['O1'])
    msg = tree_msg(tree, 7, Time())
    assert msg.episode == 7 and msg.node_sequences[0] == ''
    assert len(msg.edges) == 3 and len(msg.node_sequences) == 4
    best = [(msg.node_sequences[e.parent], e.object_id) for e in msg.edges if e.on_best_path]
    assert best == [('', 'O1'), ('O1', 'T')]


def test_result_keeps_statistics_on_failure() -> None:
    result = train(TOY_MOVABLE, 'T', toy_oracle(), TrainingConfig(seed=0, max_episodes=30))
    code = RetrieveTarget.Result.MOTION_PLANNER_UNAVAILABLE
    msg = result_msg(result, error_code=code, message='gone')
    assert not msg.success and msg.error_code == code and msg.episodes == 30
    assert msg.mp_calls == result.mp_calls > 0
    empty = result_msg(None, error_code=RetrieveTarget.Result.INVALID_GOAL, message='bad')
    assert empty.first_optimal_episode == -1 and empty.episodes == 0
