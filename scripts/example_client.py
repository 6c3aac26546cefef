#!/usr/bin/env python3
"""From your own software: set a scene, check one relocation, retrieve the target.

Needs the simulator, the motion planner and the task planner running (README, "Using the nodes
from your own software"). ``python scripts/example_client.py [--execute] [--max-episodes N]``.
"""

import argparse

import rclpy
from qtree_msgs.action import RetrieveTarget
from qtree_msgs.msg import ObjectState, Scene
from qtree_msgs.srv import RelocateObject, SetScene
from rclpy.action import ActionClient
from shape_msgs.msg import SolidPrimitive

# What a perception node might see. Lengths [m]; centres in the robot base frame, table top z = 0.
SCENE = {
    'name': 'my_table',
    'drop_zone': {'center': [0.0, 0.5, 0.15], 'size': [0.3, 0.3, 0.3]},
    'objects': [  # cylinder: [height, radius], box: [x, y, z]
        {'id': 'table', 'role': 'static', 'box': [1.2, 1.4, 0.05], 'center': [0.35, 0, -0.025]},
        {'id': 'T', 'role': 'target', 'cylinder': [0.16, 0.03], 'center': [0.8, 0.0, 0.08]},
        {'id': 'O1', 'role': 'obstacle', 'cylinder': [0.12, 0.03], 'center': [0.7, 0.0, 0.06]},
        {'id': 'O2', 'role': 'obstacle', 'cylinder': [0.15, 0.03], 'center': [0.6, -0.075, 0.075]},
        {'id': 'O3', 'role': 'obstacle', 'box': [0.05, 0.05, 0.13], 'center': [0.6, 0.075, 0.065]},
    ],
}


def scene_from_dict(data: dict) -> Scene:
    """The Scene message of ``data`` (upright objects, yaw 0): SolidPrimitive shapes + poses."""
    msg = Scene(scenario_name=data['name'])
    msg.header.frame_id = 'j2s7s300_link_base'
    for entry in data['objects']:
        kind = 'cylinder' if 'cylinder' in entry else 'box'
        shape = SolidPrimitive(type=getattr(SolidPrimitive, kind.upper()), dimensions=entry[kind])
        role = getattr(ObjectState, f'ROLE_{entry["role"].upper()}')
        obj = ObjectState(id=entry['id'], role=role, shape=shape)
        obj.pose.position.x, obj.pose.position.y, obj.pose.position.z = entry['center']
        msg.objects.append(obj)
    zone = data['drop_zone']
    msg.drop_zone.position.x, msg.drop_zone.position.y, msg.drop_zone.position.z = zone['center']
    msg.drop_zone_size.x, msg.drop_zone_size.y, msg.drop_zone_size.z = zone['size']
    return msg


def call(node, client, request, timeout_s: float = 60.0):
    """Wait for the service, call it and wait for the answer (None if none came)."""
    if not client.wait_for_service(timeout_sec=timeout_s):
        raise SystemExit(f'{client.srv_name} is not available: is the graph running?')
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=timeout_s)
    return future.result()


def main() -> int:
    """Set the scene, ask one relocation, run a goal; exit code 0 on success."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--execute', action='store_true', help='run the learned sequence')
    parser.add_argument('--max-episodes', type=int, default=500)
    args = parser.parse_args()
    rclpy.init()
    node = rclpy.create_node('example_client')
    answer = call(node, node.create_client(SetScene, '/jaco2_sim/set_scene'),
                  SetScene.Request(scene=scene_from_dict(SCENE)))  # fmt: skip
    print(f'set_scene: success={answer.success} {answer.message}')
    if not answer.success:
        return 1
    check = call(node, node.create_client(RelocateObject, '/relocate_object'),
                 RelocateObject.Request(object_id='O2', scene_name=SCENE['name']))  # fmt: skip
    print(f'relocate O2: feasible={check.feasible} reason={check.reason} {check.message}')
    action = ActionClient(node, RetrieveTarget, '/retrieve_target')
    if not action.wait_for_server(timeout_sec=60.0):
        raise SystemExit('/retrieve_target is not available: is the task planner running?')
    goal = RetrieveTarget.Goal(policy='H-EG-SET', max_episodes=args.max_episodes,
                               execute=args.execute, feedback_every=25)  # fmt: skip
    feedback = lambda f: print(f'  episode {f.feedback.episode}: best {f.feedback.best_sequence}')  # noqa: E731
    sent = action.send_goal_async(goal, feedback_callback=feedback)
    rclpy.spin_until_future_complete(node, sent)
    if not sent.result().accepted:
        raise SystemExit('retrieve_target: goal rejected')
    result_future = sent.result().get_result_async()
    rclpy.spin_until_future_complete(node, result_future)
    result = result_future.result().result
    print(f'retrieve_target: success={result.success} sequence={list(result.sequence)} '
          f'episodes={result.episodes} mp_calls={result.mp_calls} {result.message}')  # fmt: skip
    node.destroy_node()
    rclpy.shutdown()
    return 0 if result.success else 1


if __name__ == '__main__':
    raise SystemExit(main())
