"""Scenes from any node: SetScene on the simulator, and /scene from a publisher of our own.

SetScene: a good scene is published and planned in; each bad one (NaN pose, unknown primitive,
negative dimension, duplicate id, no target, thousands of objects) is rejected with a message
naming the object and the field, the previous scene is kept and the sim keeps publishing.
"""

from __future__ import annotations

import math
from typing import Any

import pytest
from qtree_msgs.msg import ObjectState, Scene
from qtree_msgs.srv import RelocateObject, SetScene
from qtree_scene.message import scene_msg
from qtree_scene.scenario import load_scenario
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from shape_msgs.msg import SolidPrimitive
from stpik_motion_planner.result import Reason

pytestmark = pytest.mark.timeout(240)

LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


def _s2_edited(edit: Any) -> Scene:
    msg = scene_msg(load_scenario('s2'))
    edit(next(o for o in msg.objects if o.id == 'O3'), msg)
    return msg


def _many(_: Any, msg: Scene) -> None:
    template = msg.objects[1]
    msg.objects += [
        ObjectState(id=f'X{i}', role=1, shape=template.shape, pose=template.pose)
        for i in range(3000)
    ]


def _set(path: str, value: Any) -> Any:
    def edit(obj: Any, _: Scene) -> None:
        *parents, leaf = path.split('.')
        for name in parents:
            obj = getattr(obj, name)
        setattr(obj, leaf, value)

    return edit


BAD = [  # (case, edit of O3 in s2, field and object named in the message)
    ('NaN pose', _set('pose.position.y', math.nan), ".pose.position.y: 'O3'"),
    ('unknown primitive', _set('shape.type', SolidPrimitive.CONE), ".shape.type: 'O3'"),
    ('negative dimension', _set('shape.dimensions', [0.12, -0.03]), ".shape.dimensions[1]: 'O3'"),
    ('duplicate id', _set('id', 'O1'), "duplicate id 'O1'"),
    ('no target', lambda _, m: setattr(m.objects[0], 'role', 1), 'objects: exactly one object'),
    ('thousands of objects', _many, 'objects: 3012 objects, at most 500'),
]


@pytest.fixture
def sim_and_planner(launch: Any, ros_node: Any) -> dict[str, Any]:
    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1', 'sim_rate_hz': 50.0})
    planner = launch('stpik_motion_planner', 'motion_planner_node')
    sim.wait_for_log('ready', 60.0)
    planner.wait_for_log('planner rebuilt', 60.0)
    state: dict[str, Any] = {'scenes': [], 'states': 0}
    ros_node.create_subscription(Scene, '/scene', state['scenes'].append, LATCHED)
    ros_node.create_subscription(
        JointState, '/joint_states', lambda _: state.update(states=state['states'] + 1), 10
    )
    state['set'] = ros_node.create_client(SetScene, '/jaco2_sim/set_scene')
    state['relocate'] = ros_node.create_client(RelocateObject, '/relocate_object')
    state['sim'], state['planner'] = sim, planner
    assert ros_node.spin_until(lambda: state['scenes'] and state['states'] > 0, 20.0)
    return state


def test_set_scene_then_bad_scenes_keep_it(sim_and_planner: dict[str, Any], ros_node: Any):
    nodes = sim_and_planner
    mark = len(nodes['planner'].log_text())
    ok = ros_node.call(nodes['set'], SetScene.Request(scene=scene_msg(load_scenario('s2'))))
    assert ok.success, ok.message
    assert ros_node.spin_until(lambda: nodes['scenes'][-1].scenario_name == 's2', 10.0)
    assert len(nodes['scenes'][-1].objects) == 12
    assert ros_node.spin_until(lambda: "scene 's2'" in nodes['planner'].log_text()[mark:], 30.0)
    answer = ros_node.call(nodes['relocate'], RelocateObject.Request(object_id='T'), 60.0)
    assert answer.reason not in (Reason.NO_SCENE, Reason.INVALID_SCENE), answer.message
    assert ros_node.call(nodes['relocate'], RelocateObject.Request(object_id='O10')).reason != (
        Reason.UNKNOWN_OBJECT
    )
    for case, edit, fragment in BAD:
        published, states = len(nodes['scenes']), nodes['states']
        response = ros_node.call(nodes['set'], SetScene.Request(scene=_s2_edited(edit)))
        assert not response.success, case
        assert response.message.startswith('SetScene: ') and fragment in response.message, (
            case,
            response.message,
        )
        assert ros_node.spin_until(lambda s=states: nodes['states'] > s + 5, 5.0), case
        assert len(nodes['scenes']) == published and nodes['scenes'][-1].scenario_name == 's2', (
            case
        )
        assert nodes['sim'].alive(), case


def test_planner_takes_a_scene_from_any_publisher(launch: Any, ros_node: Any) -> None:
    planner = launch('stpik_motion_planner', 'motion_planner_node')
    planner.wait_for_log('ready', 60.0)
    relocate = ros_node.create_client(RelocateObject, '/relocate_object')
    none_yet = ros_node.call(relocate, RelocateObject.Request(object_id='T'))
    assert none_yet.reason == Reason.NO_SCENE
    publisher = ros_node.create_publisher(Scene, '/scene', LATCHED)
    assert ros_node.spin_until(lambda: publisher.get_subscription_count() > 0, 20.0)
    wrong = scene_msg(load_scenario('s1'))
    wrong.header.frame_id = 'camera_link'
    publisher.publish(wrong)
    assert ros_node.spin_until(lambda: 'scene rejected' in planner.log_text(), 20.0)
    rejected = ros_node.call(relocate, RelocateObject.Request(object_id='T'))
    assert rejected.reason == Reason.INVALID_SCENE and 'header.frame_id' in rejected.message
    assert 'planner rebuilt' not in planner.log_text()
    publisher.publish(scene_msg(load_scenario('s1')))
    rebuilt = "scene 's1': planner rebuilt"
    assert ros_node.spin_until(lambda: rebuilt in planner.log_text(), 20.0), planner.log_text()
    answer = ros_node.call(relocate, RelocateObject.Request(object_id='O2'), 60.0)
    assert answer.feasible, answer.message  # O2 is free on s1 (the planner's unit tests)
