"""qtree_msgs: the generated Python types import and round-trip through CDR serialisation."""

from __future__ import annotations

import math

import pytest
from qtree_msgs.action import RetrieveTarget
from qtree_msgs.msg import ObjectState, PlanningEvent, QTree, QTreeEdge, Scene, TrainingStats
from qtree_msgs.srv import AttachObject, RelocateObject, ResetScene, SetScene
from rclpy.serialization import deserialize_message, serialize_message
from shape_msgs.msg import SolidPrimitive


def _scene() -> Scene:
    scene = Scene(scenario_name='s1', attached_id='')
    scene.header.frame_id = 'world'
    for index in range(3):
        obj = ObjectState(
            id=f'O{index}',
            role=ObjectState.ROLE_OBSTACLE,
            shape=SolidPrimitive(type=SolidPrimitive.CYLINDER, dimensions=[0.15, 0.03]),
            status=ObjectState.STATUS_IN_CLUTTER,
        )
        obj.pose.position.x = 0.4 + 0.1 * index
        obj.pose.orientation.w = 1.0
        scene.objects.append(obj)
    scene.drop_zone_size.x = 0.3
    return scene


@pytest.mark.parametrize(
    'message',
    [
        _scene(),
        TrainingStats(
            policy='H-EG',
            episode=12,
            nodes=5,
            edges=4,
            mp_calls=4,
            q_bar=181.0,
            epsilon=0.5,
            episode_sequence=['O1', 'T'],
            reached_target=True,
            best_sequence=['O1', 'T'],
        ),
        QTree(
            episode=3,
            node_sequences=['', 'O1', 'O1,T'],
            edges=[
                QTreeEdge(parent=0, child=1, object_id='O1', q=0.0, reward=0.0),
                QTreeEdge(
                    parent=1, child=2, object_id='T', q=100.0, reward=100.0, on_best_path=True
                ),
            ],
        ),
        PlanningEvent(
            object_id='O2',
            relocated_ids=['O1'],
            feasible=False,
            reason=RelocateObject.Response.SCENE_COLLISION,
            message='hit O3',
        ),
        RelocateObject.Request(object_id='O2', relocated_ids=['O1', 'O3'], execute=True),
        RelocateObject.Response(
            feasible=True,
            reason=RelocateObject.Response.SUCCESS,
            planning_time=0.012,
            from_cache=True,
        ),
        ResetScene.Request(scenario='s2'),
        SetScene.Request(scene=_scene()),
        SetScene.Response(success=False, message="SetScene: objects[0].pose.position.x: 'O0'"),
        AttachObject.Request(object_id='O1', attach=False),
        RetrieveTarget.Goal(policy='H-LRND', seed=7),
        RetrieveTarget.Result(success=True, sequence=['O1', 'T'], episodes=100, mp_calls=9),
        RetrieveTarget.Feedback(episode=10, best_sequence=['T']),
    ],
    ids=lambda m: type(m).__name__,
)
def test_cdr_round_trip(message) -> None:
    data = serialize_message(message)
    assert isinstance(data, bytes) and len(data) > 4
    assert deserialize_message(data, type(message)) == message


def test_reason_codes_are_distinct_and_ordered_by_family() -> None:
    codes = {
        name: getattr(RelocateObject.Response, name)
        for name in dir(RelocateObject.Response)
        if name.isupper() and name != 'SLOT_TYPES'
    }
    assert codes['SUCCESS'] == 0
    assert len(set(codes.values())) == len(codes) >= 14
    assert all(100 < codes[n] < 200 for n in ('UNKNOWN_OBJECT', 'INVALID_REQUEST', 'NO_SCENE'))
    assert all(200 < codes[n] < 300 for n in ('JOINT_LIMIT', 'SELF_COLLISION', 'SCENE_COLLISION'))
    assert codes['TIMEOUT'] == 301 and codes['EXECUTION_FAILED'] == 302
    assert codes['PLANNER_BUSY'] == 303  # busy: not an answer about feasibility (#18)


def test_goal_defaults_are_the_papers() -> None:
    goal = RetrieveTarget.Goal()
    assert goal.policy == 'H-EG'
    assert (goal.alpha, goal.gamma) == (0.5, 0.9)
    assert (goal.epsilon0, goal.epsilon_min, goal.max_episodes) == (1.0, 1e-4, 5000)
    assert not goal.execute and goal.feedback_every > 0 and goal.beta > 0
    assert math.isclose(AttachObject.Request().status_after_release, ObjectState.STATUS_RELOCATED)


def test_strings_are_cut_at_a_nul_byte() -> None:
    """Documented limit (#18, interface comments): the generated code ends a string at NUL."""
    from rclpy.serialization import deserialize_message, serialize_message

    request = RelocateObject.Request(object_id='O1\x00ghost', relocated_ids=['O2\x00O3'])
    received = deserialize_message(serialize_message(request), RelocateObject.Request)
    assert (received.object_id, list(received.relocated_ids)) == ('O1', ['O2'])
    goal = deserialize_message(
        serialize_message(RetrieveTarget.Goal(policy='H-EG\x00DQN')), RetrieveTarget.Goal
    )
    assert goal.policy == 'H-EG'
