"""Cross-process tests of the motion_planner node with the jaco2_sim node."""

from __future__ import annotations

import pytest
from qtree_msgs.msg import ObjectState, PlanningEvent, Scene
from qtree_msgs.srv import RelocateObject
from qtree_scene.placement import slot_position
from qtree_scene.scenario import load_scenario
from stpik_motion_planner.result import Reason


def test_reason_codes_equal_the_service_constants():
    for reason in Reason:
        assert getattr(RelocateObject.Response, reason.name) == reason.value


@pytest.fixture
def graph(launch, ros_node):
    """sim_node (scenario s1) and motion_planner_node running, a client and the last scene."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    sim = launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1', 'sim_rate_hz': 100.0})
    planner = launch('stpik_motion_planner', 'motion_planner_node')
    sim.wait_for_log('ready', 30.0)
    planner.wait_for_log('ready', 30.0)
    planner.wait_for_log('planner rebuilt', 30.0)
    state = {'scene': None, 'events': []}
    qos = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    ros_node.create_subscription(Scene, '/scene', lambda m: state.update(scene=m), qos)
    events = ros_node.create_subscription(
        PlanningEvent, '/motion_planner/events', lambda m: state['events'].append(m), 10
    )
    client = ros_node.create_client(RelocateObject, '/relocate_object')
    ros_node.wait_matched(client, events)  # a request sent before the match is lost
    return ros_node, client, state, planner


def _call(node, client, object_id, relocated=(), execute=False, timeout_s=30.0):
    request = RelocateObject.Request(
        object_id=object_id, relocated_ids=list(relocated), execute=execute
    )
    return node.call(client, request, timeout_s)


def test_feasible_infeasible_and_bad_requests(graph):
    node, client, state, planner = graph
    every_obstacle = ['O1', 'O2', 'O3', 'O4', 'O5']
    ok = _call(node, client, 'T', every_obstacle)
    assert ok.feasible and ok.reason == Reason.SUCCESS, ok.message
    assert len(ok.trajectory.points) > 10 and len(ok.trajectory.joint_names) == 7
    assert ok.planning_time > 0 and not ok.from_cache
    again = _call(node, client, 'T', list(reversed(every_obstacle)))
    assert again.from_cache and again.feasible
    blocked = _call(node, client, 'T')
    assert not blocked.feasible and blocked.reason == Reason.NO_CARTESIAN_PATH
    for object_id, relocated, reason in [
        ('nope', [], Reason.UNKNOWN_OBJECT),
        ('O1', ['O1'], Reason.ALREADY_RELOCATED),
        ('O1', ['T'], Reason.INVALID_REQUEST),
        ('', [], Reason.INVALID_REQUEST),
        ('T', ['O2', 'O2'], Reason.INVALID_REQUEST),
    ]:
        answer = _call(node, client, object_id, relocated)
        assert (answer.feasible, answer.reason) == (False, reason), answer.message
    assert node.spin_until(lambda: len(state['events']) >= 8, 5.0)
    assert planner.alive()


def test_execute_relocates_the_object_in_the_sim(graph):
    node, client, state, _ = graph
    answer = _call(node, client, 'T', ['O1', 'O2', 'O3', 'O4', 'O5'], execute=True, timeout_s=120)
    assert answer.feasible, answer.message

    def relocated() -> bool:
        scene = state['scene']
        return scene is not None and any(
            o.id == 'T' and o.status == ObjectState.STATUS_RELOCATED for o in scene.objects
        )

    assert node.spin_until(relocated, 10.0)
    target = next(o for o in state['scene'].objects if o.id == 'T')
    # Released on drop slot 5, the sixth relocation the plan was asked for (the sim, where O1-O5
    # still stand, counts it as its first relocation and leaves it where the hand released it).
    scenario = load_scenario('s1')
    slot = slot_position(scenario, 5, scenario.object('T'))
    position = target.pose.position
    assert abs(position.x - slot[0]) < 0.012 and abs(position.y - slot[1]) < 0.012


def test_bad_requests_do_not_wait_for_planning(graph):
    node, client, _, planner = graph
    assert client.wait_for_service(timeout_sec=30.0)  # was missing: requests were lost (#18)
    planning = [('O1', []), ('O2', []), ('O3', []), ('O4', []), ('O5', [])]
    planning.append(('T', ['O1', 'O2', 'O3', 'O4', 'O5']))
    futures = [
        client.call_async(RelocateObject.Request(object_id=o, relocated_ids=r))
        for o, r in planning
    ]
    bad = client.call_async(RelocateObject.Request(object_id='ghost'))
    assert node.spin_until(bad.done, 10.0)
    pending = sum(not f.done() for f in futures)
    assert node.spin_until(lambda: all(f.done() for f in futures), 60.0)
    assert bad.result().reason == Reason.UNKNOWN_OBJECT
    assert pending > 0, 'the bad request was answered only after every planning request'
    assert all(f.result().reason != Reason.TIMEOUT for f in futures)
    assert planner.alive()


def test_huge_request_is_answered_logged_and_published_short(graph):
    node, client, state, planner = graph
    mark = len(planner.log_text())
    answer = _call(node, client, 'T', ['O1'] * 10_000)
    assert (answer.feasible, answer.reason) == (False, Reason.INVALID_REQUEST)
    assert 'at most 256' in answer.message and len(answer.message) < 200, answer.message
    assert node.spin_until(lambda: state['events'], 5.0)
    event = state['events'][-1]
    assert len(event.relocated_ids) == 256 and event.message == answer.message
    assert node.spin_until(lambda: '(10000 ids)' in planner.log_text()[mark:], 5.0)
    assert len(planner.log_text()[mark:]) < 1000


def test_grasp_families_parameter_adds_top_grasps_named_in_the_answer(graph):
    """#30: the paper's side grasp by default (answers name 'side'); with grasp_families
    ['top', 'side'] the planner, rebuilt, takes O4 of s1 from above (O2 blocks its side
    approaches) and says so."""
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    node, client, _, planner = graph
    side = _call(node, client, 'T', ['O1', 'O2', 'O3', 'O4', 'O5'])
    assert side.feasible and side.grasp_family == 'side', side.message
    blocked = _call(node, client, 'T')
    assert not blocked.feasible and blocked.grasp_family == ''
    no_side = _call(node, client, 'O4')
    assert not no_side.feasible and 'O2' in no_side.blocking_ids, no_side.message
    params = AsyncParameterClient(node, 'motion_planner')
    assert params.wait_for_services(10.0)
    future = params.set_parameters([Parameter('grasp_families', value=['top', 'side'])])
    assert node.spin_until(future.done, 10.0)
    assert all(r.successful for r in future.result().results)
    top = _call(node, client, 'O4')
    assert top.feasible and top.grasp_family == 'top', top.message
    assert 'top grasp' in top.message and not top.from_cache
    assert planner.alive()


def test_a_top_grasp_executes_and_stands_the_object_on_its_top_slot(graph):
    """#30: executed on the simulator, a top grasp of O4 (s1) leaves O4 upright on the first
    top slot (placement.top_place_slots), relocated."""
    from qtree_scene.placement import slot_centre, top_place_slots
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    node, client, state, planner = graph
    params = AsyncParameterClient(node, 'motion_planner')
    assert params.wait_for_services(10.0)
    future = params.set_parameters([Parameter('grasp_families', value=['top'])])
    assert node.spin_until(future.done, 10.0)
    answer = _call(node, client, 'O4', execute=True, timeout_s=120)
    assert answer.feasible and answer.grasp_family == 'top', answer.message

    def relocated() -> bool:
        scene = state['scene']
        return scene is not None and any(
            o.id == 'O4' and o.status == ObjectState.STATUS_RELOCATED for o in scene.objects
        )

    assert node.spin_until(relocated, 10.0)
    scenario = load_scenario('s1')
    _, top_slots = top_place_slots(scenario)
    slot = slot_centre(scenario, top_slots[0], scenario.object('O4'))
    pose = next(o for o in state['scene'].objects if o.id == 'O4').pose
    assert abs(pose.position.x - slot[0]) < 0.012 and abs(pose.position.y - slot[1]) < 0.012
    assert abs(pose.position.z - slot[2]) < 0.01  # standing on the table, upright
    assert abs(pose.orientation.x) < 0.05 and abs(pose.orientation.y) < 0.05
    assert planner.alive()
