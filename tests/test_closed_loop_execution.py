"""Cross-process tests of closed-loop execution: motion_planner (execution_mode) with jaco2_sim
(streamed /joint_command, disturbances)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from jaco2_description.model import ARM_JOINTS
from qtree_msgs.msg import ObjectState, Scene, TrackingState
from qtree_msgs.srv import RelocateObject, ResetScene
from qtree_scene.scenario import load_scenario
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from shape_msgs.msg import SolidPrimitive
from stpik_motion_planner.closed_loop import PlannedMotion
from stpik_motion_planner.planner import MotionPlanner

EVERY_OBSTACLE = ['O1', 'O2', 'O3', 'O4', 'O5']
LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
OFFSET = [0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0]


@pytest.fixture(scope='module')
def plan():
    """The in-process plan of T once every obstacle is gone (what the node plans too)."""
    planner = MotionPlanner(load_scenario('s1'))
    result = planner.check('T', EVERY_OBSTACLE)
    assert result.feasible, result.message
    motion = PlannedMotion(result.times, result.joint_trajectory, planner.robot)
    obj = load_scenario('s1').object('T')
    grasp = motion.ee_of(result.joint_trajectory[result.grasp_index])
    release = motion.ee_of(result.joint_trajectory[result.release_index])
    start = grasp.actInv(pin.SE3(np.eye(3), np.asarray(obj.position, dtype=float)))
    return result, motion, (release * start).translation


def _graph(launch, ros_node, sim_parameters=None, planner_parameters=None):
    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1', **(sim_parameters or {})})
    mp = launch(
        'stpik_motion_planner',
        'motion_planner_node',
        parameters={'execution_timeout_s': 120.0, **(planner_parameters or {})},
    )
    sim.wait_for_log('ready', 30.0)
    mp.wait_for_log('ready', 30.0)
    mp.wait_for_log('planner rebuilt', 30.0)
    seen: dict[str, Any] = {'scene': None, 'tracking': []}
    ros_node.create_subscription(Scene, '/scene', lambda m: seen.update(scene=m), LATCHED)
    ros_node.create_subscription(
        TrackingState, '/motion_planner/tracking', seen['tracking'].append, 100
    )
    client = ros_node.create_client(RelocateObject, '/relocate_object')
    return sim, mp, client, seen


def _released_position(ros_node, seen) -> np.ndarray:
    def relocated() -> bool:
        scene = seen['scene']
        return scene is not None and any(
            o.id == 'T' and o.status == ObjectState.STATUS_RELOCATED for o in scene.objects
        )

    assert ros_node.spin_until(relocated, 10.0)
    p = next(o for o in seen['scene'].objects if o.id == 'T').pose.position
    return np.array([p.x, p.y, p.z])


def _set(ros_node, node_name: str, **values) -> None:
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    client = AsyncParameterClient(ros_node, node_name)
    assert client.wait_for_services(10.0)
    future = client.set_parameters([Parameter(n, value=v) for n, v in values.items()])
    assert ros_node.spin_until(future.done, 10.0)
    results = future.result().results
    assert all(r.successful for r in results), [r.reason for r in results]


def _hand_error(ros_node, states: list, result, motion) -> float:
    """Distance [m] of the hand at rest after the execution from the plan's last sample."""
    count = len(states)
    assert ros_node.spin_until(lambda: len(states) > count + 5, 10.0), 'no /joint_states'
    planned = motion.ee_of(result.joint_trajectory[-1]).translation
    return float(np.linalg.norm(motion.ee_of(states[-1]).translation - planned))


def test_closed_loop_removes_a_joint_offset_open_loop_does_not(launch, ros_node, plan):
    result, motion, planned = plan
    sim, mp, client, seen = _graph(launch, ros_node, {'joint_offset_rad': OFFSET})
    states: list[np.ndarray] = []
    ros_node.create_subscription(
        JointState, '/joint_states', lambda m: states.append(np.array(m.position[:7])), 10
    )
    request = RelocateObject.Request(object_id='T', relocated_ids=EVERY_OBSTACLE, execute=True)
    answer = ros_node.call(client, request, 400.0)
    assert answer.feasible, answer.message
    closed_error = float(np.linalg.norm(_released_position(ros_node, seen) - planned))
    closed_hand = _hand_error(ros_node, states, result, motion)

    # The reply can arrive before the last /tracking message (a topic, not the reply): under
    # load the final 'done' tick was still in flight (node tests, run 2 of this session). Every
    # segment ends with a 'done' tick, so wait for the LAST tick to be one (waiting for any
    # 'done' returned at an earlier segment's: full suite of 2026-12-03, last tick 'tracking').
    def last_is_done() -> bool:
        ticks = [t for t in seen['tracking'] if t.phase != 'stopped']
        return bool(ticks) and ticks[-1].phase == 'done'

    assert ros_node.spin_until(last_is_done, 10.0)
    ticks = [t for t in seen['tracking'] if t.phase != 'stopped']
    assert len(ticks) > 100 and list(ticks[0].joint_names) == list(ARM_JOINTS)
    # #26: one streamed reference per tick; each was logged 'trajectory finished' at INFO
    assert sim.log_text().count('trajectory finished') == 0
    assert ticks[-1].phase == 'done' and ticks[-1].error_m < 0.005
    # Same relocation in open loop (goal tolerance above the offset so that it completes).
    _set(ros_node, 'motion_planner', execution_mode='open_loop', goal_tolerance_rad=0.1)
    reset = ros_node.create_client(ResetScene, '/jaco2_sim/reset_scene')
    assert ros_node.call(reset, ResetScene.Request(), 30.0).success
    assert ros_node.spin_until(
        lambda: (
            seen['scene'] is not None
            and all(o.status == ObjectState.STATUS_IN_CLUTTER for o in seen['scene'].objects)
        ),
        10.0,
    )
    answer = ros_node.call(client, request, 400.0)
    assert answer.feasible, answer.message
    open_error = float(np.linalg.norm(_released_position(ros_node, seen) - planned))
    open_hand = _hand_error(ros_node, states, result, motion)
    print(f'\n[closed loop] with a 0.05 rad offset on joint 2: placement error closed loop '
          f'{closed_error * 1e3:.1f} mm, open loop {open_error * 1e3:.1f} mm; hand at the end '
          f'{closed_hand * 1e3:.1f} mm / {open_hand * 1e3:.1f} mm from the plan')  # fmt: skip
    assert closed_error < 0.01
    # The hand, not the placement: with a constant joint offset the hand is off at the grasp and
    # at the release alike, and the two can nearly cancel in the placement (3.7-4.1 mm on
    # today's plan of T, 20 mm on an earlier one); the hand at rest stays off by the offset.
    # Thresholds with a 2x margin over what was measured (docs/RELIABILITY.md): the closed loop
    # settles within 1 mm (settle_tolerance_m; 0.0 mm measured, was 5.07 mm under load before
    # #26), the open loop keeps the offset (15.6 mm measured).
    assert closed_hand < 0.005
    assert open_hand > 0.0075
    assert sim.alive() and mp.alive()


@pytest.mark.parametrize('change', ['added', 'target moved'])
def test_a_scene_change_before_the_grasp_stops_the_arm_and_undoes_it(
    launch, ros_node, plan, change
):
    """An object put on the path just ahead of the hand, or the target itself moved under its
    approach (#32: it was ignored, the hand went on to an empty grasp), stops the arm with
    SCENE_CHANGED naming the change; the relocation is undone. (The goal-level re-plan of each
    kind took 4-15 min of CI per goal: the task planner's handling of the cause is the same
    for every kind, tested end to end in test_replanning.py.)"""
    result, motion, _ = plan
    sim, mp, client, seen = _graph(launch, ros_node)
    assert ros_node.spin_until(lambda: seen['scene'] is not None, 10.0)
    states: list[np.ndarray] = []
    ros_node.create_subscription(
        JointState, '/joint_states', lambda m: states.append(np.array(m.position[:7])), 10
    )
    publisher = ros_node.create_publisher(Scene, '/scene', LATCHED)
    # Matched before sending: a request, or the intruder's scene, written earlier is lost (#18).
    ros_node.wait_answering(client)  # a probe answered: both directions match
    # Our own /scene subscription counts as one reader: wait for the motion planner's too.
    assert ros_node.spin_until(lambda: publisher.get_subscription_count() >= 2, 30.0)
    request = RelocateObject.Request(object_id='T', relocated_ids=EVERY_OBSTACLE, execute=True)
    future = client.call_async(request)
    assert ros_node.spin_until(lambda: len(seen['tracking']) > 20, 60.0)
    scene = seen['scene']
    if change == 'added':  # a box where the hand will be just before the grasp
        ahead = motion.ee_of(result.joint_trajectory[result.grasp_index - 2]).translation
        intruder = ObjectState(
            id='intruder',
            role=ObjectState.ROLE_OBSTACLE,
            shape=SolidPrimitive(type=SolidPrimitive.BOX, dimensions=[0.05, 0.05, 0.05]),
            status=ObjectState.STATUS_IN_CLUTTER,
        )
        intruder.pose.position.x, intruder.pose.position.y, intruder.pose.position.z = (
            float(v) for v in ahead
        )
        intruder.pose.orientation.w = 1.0
        scene.objects.append(intruder)
        named, expected = 'intruder', "'intruder' added"
    else:  # the target 10 cm aside of where the hand is going
        target = next(o for o in scene.objects if o.id == 'T')
        target.pose.position.y += 0.1
        named, expected = "'T'", "'T' moved 0.100 m"
    publisher.publish(scene)
    assert ros_node.spin_until(future.done, 300.0), 'no answer'
    answer = future.result()
    print(f'\n[closed loop] {change}: {answer.message}')
    assert not answer.feasible
    # #32: a change of the scene under the execution is named, and the relocation undone
    assert answer.reason == RelocateObject.Response.SCENE_CHANGED, answer.message
    assert expected in answer.message and 'undone' in answer.message
    assert ros_node.spin_until(
        lambda: any(t.phase == 'stopped' and named in t.message for t in seen['tracking']),
        5.0,
    )
    # The arm went back to the start of the plan and holds there: once it has braked (0.5 s; a
    # soak run under load saw 0.012 rad of braking within the first second), it stays still.
    assert ros_node.spin_until(lambda: len(states) > 10, 5.0)
    ros_node.spin_until(lambda: False, 0.5)
    held = states[-1]
    ros_node.spin_until(lambda: False, 1.0)
    assert np.max(np.abs(states[-1] - held)) < 0.01
    assert np.max(np.abs(held - result.joint_trajectory[0])) < 0.02, held
    again = ros_node.call(client, RelocateObject.Request(object_id='O3'), 30.0)
    assert again.reason in (0, 201, 202, 203, 204, 205), again.message  # still serving
    assert sim.alive() and mp.alive()


def test_bad_execution_and_disturbance_parameters_are_refused(launch, ros_node):
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    sim, mp, _, _ = _graph(launch, ros_node)
    for node_name, name, value in [
        ('motion_planner', 'control_rate_hz', 5000.0),
        ('motion_planner', 'control_rate_hz', math.nan),
        ('motion_planner', 'execution_mode', 'sideways'),
        ('jaco2_sim', 'command_latency_s', -0.1),
        ('jaco2_sim', 'measurement_noise_rad', math.nan),
        ('jaco2_sim', 'joint_offset_rad', [0.0, math.nan, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ('jaco2_sim', 'joint_offset_rad', [0.1]),
    ]:
        client = AsyncParameterClient(ros_node, node_name)
        assert client.wait_for_services(10.0)
        future = client.set_parameters([Parameter(name, value=value)])
        assert ros_node.spin_until(future.done, 10.0)
        result = future.result().results[0]
        assert not result.successful, (name, value)
        assert result.reason, (name, value)
    assert sim.alive() and mp.alive()


def test_a_scene_change_while_carrying_puts_the_object_back_and_goes_home(launch, ros_node, plan):
    """#32: the carry is undone too: back to the grasp, the object put down there, then home."""
    import json

    result, _, _ = plan
    sim, mp, client, seen = _graph(launch, ros_node)
    assert ros_node.spin_until(lambda: seen['scene'] is not None, 10.0)
    start = next(o for o in seen['scene'].objects if o.id == 'T').pose.position
    states: list[np.ndarray] = []
    ros_node.create_subscription(
        JointState, '/joint_states', lambda m: states.append(np.array(m.position[:7])), 10
    )
    _set(ros_node, '/jaco2_sim', scene_events='')  # the parameter service answers
    ros_node.wait_answering(client)
    request = RelocateObject.Request(object_id='T', relocated_ids=EVERY_OBSTACLE, execute=True)
    future = client.call_async(request)
    t_grasp = float(result.times[result.grasp_index])
    carrying = lambda: any(t.plan_time > t_grasp + 0.5 for t in seen['tracking'])  # noqa: E731
    assert ros_node.spin_until(lambda: carrying() or future.done(), 300.0)
    assert not future.done(), future.result().message
    # O4 (still in the sim's clutter, left out of the request) moves aside: a change of the scene
    move = {'kind': 'move', 'object': 'O4', 'xy': [0.45, -0.3], 'at_s': 0.0}
    _set(ros_node, '/jaco2_sim', scene_events=json.dumps([move]))
    assert ros_node.spin_until(future.done, 300.0), 'no answer'
    answer = future.result()
    print(f'\n[closed loop] change while carrying: {answer.message}')
    assert answer.reason == RelocateObject.Response.SCENE_CHANGED, answer.message
    assert "'O4' moved" in answer.message and "'T' put back in the clutter" in answer.message

    def put_back() -> bool:
        t = next(o for o in seen['scene'].objects if o.id == 'T')
        return t.status == ObjectState.STATUS_IN_CLUTTER and seen['scene'].attached_id == ''

    assert ros_node.spin_until(put_back, 10.0), 'T is not back in the clutter'
    now = next(o for o in seen['scene'].objects if o.id == 'T').pose.position
    moved = math.dist((now.x, now.y, now.z), (start.x, start.y, start.z))
    assert moved < 0.005, f'T put down {moved * 1e3:.1f} mm from where it was grasped'
    ros_node.spin_until(lambda: False, 1.0)
    assert np.max(np.abs(states[-1] - result.joint_trajectory[0])) < 0.02, states[-1]
    assert sim.alive() and mp.alive()
