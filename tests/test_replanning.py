"""Retrieve through a changing world (#32), end to end through the ROS graph.

The simulator's ``scene_events`` (set at run time through its parameter service) move an object
into the target's path while the arm approaches the target, or refuse a grasp; the motion
planner stops and undoes the relocation (``SCENE_CHANGED`` / ``GRASP_FAILED``), the task planner
keeps the relocations done, re-plans the rest and succeeds, or ends with ``REPLAN_LIMIT`` once
``max_replans`` is used up. Scenario s1 (optimum O2, O3, O1, T in some order of O2 / O3).
"""

from __future__ import annotations

import json
import time
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.timeout(900)

READY_TIMEOUT_S = 90.0
GOAL_TIMEOUT_S = 700.0  # training + 4-6 closed-loop relocations of ~20 s on a loaded machine
IN_FRONT_OF_T = [0.7, 0.0]  # O1's place: on the target's approach once O1 is gone [m]


class Graph:
    """Sim (s1), motion planner and task planner, and the test node's clients."""

    def __init__(self, launch: Any, ros_node: Any) -> None:
        from qtree_msgs.action import RetrieveTarget
        from qtree_msgs.msg import Scene, TrackingState
        from rcl_interfaces.srv import SetParameters
        from rclpy.action import ActionClient
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState

        self.nodes = [
            launch('jaco2_sim', 'sim_node', parameters={'scenario': 's1'}),
            launch(  # full joint speed: the same paths in half the time (CI stays under 20 min)
                'stpik_motion_planner',
                'motion_planner_node',
                parameters={'time_limit_s': 30.0, 'velocity_scale': 1.0},
            ),
            launch(
                'qtree_task_planner', 'task_planner_node', parameters={'execute_timeout_s': 240.0}
            ),
        ]
        for node in self.nodes:
            node.wait_for_log('ready', timeout_s=READY_TIMEOUT_S)
        self.node, self.action = ros_node, RetrieveTarget
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.scenes: list[Any] = []
        self.tracking: list[Any] = []
        self.states: list[np.ndarray] = []
        self.feedback: list[Any] = []
        ros_node.create_subscription(Scene, '/scene', self.scenes.append, latched)
        tracking = ros_node.create_subscription(
            TrackingState, '/motion_planner/tracking', self.tracking.append, 100
        )
        states = ros_node.create_subscription(
            JointState, '/joint_states', lambda m: self.states.append(np.array(m.position[:7])), 10
        )
        self.params = ros_node.create_client(SetParameters, '/jaco2_sim/set_parameters')
        self.client = ActionClient(ros_node, RetrieveTarget, '/retrieve_target')
        ros_node.wait_matched(tracking, states, self.params)
        ros_node.wait_action_answering(self.client)  # a goal sent earlier may be lost

    def set_events(self, entries: list[dict]) -> Any:
        """Set the sim's ``scene_events`` (JSON); the SetParametersResult. Re-sent while no
        answer comes (a reply written before the server matched our reader is lost)."""
        from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
        from rcl_interfaces.srv import SetParameters

        value = ParameterValue(
            type=ParameterType.PARAMETER_STRING, string_value=json.dumps(entries)
        )
        request = SetParameters.Request(parameters=[Parameter(name='scene_events', value=value)])
        for _ in range(10):
            future = self.params.call_async(request)
            if self.node.spin_until(future.done, 3.0):
                return future.result().results[0]
            self.params.remove_pending_request(future)
        raise AssertionError('/jaco2_sim/set_parameters never answered')

    def send(self, **fields: Any) -> Any:
        """Send a RetrieveTarget goal (H-EG-SET, seed 0, executed); the result future."""
        goal = self.action.Goal(policy='H-EG-SET', seed=0, execute=True, **fields)
        sent = self.client.send_goal_async(
            goal, feedback_callback=lambda m: self.feedback.append(m.feedback)
        )
        assert self.node.spin_until(sent.done, 30.0) and sent.result().accepted
        return sent.result().get_result_async()

    def result(self, done: Any) -> tuple[int, Any]:
        """(goal status, result) once the goal ended."""
        assert self.node.spin_until(done.done, GOAL_TIMEOUT_S), 'the goal did not end'
        return done.result().status, done.result().result

    def relocated(self) -> set[str]:
        from qtree_msgs.msg import ObjectState

        last = self.scenes[-1].objects
        return {o.id for o in last if o.status == ObjectState.STATUS_RELOCATED}

    def arm_rests_at(self, q: np.ndarray, tolerance_rad: float = 0.02) -> bool:
        """Whether the arm stands still (1 s) at ``q`` [rad]."""
        self.node.spin_until(lambda: False, 1.0)
        held = self.states[-1]
        self.node.spin_until(lambda: False, 1.0)
        still = float(np.max(np.abs(self.states[-1] - held))) < 1e-3
        return still and float(np.max(np.abs(held - q))) < tolerance_rad

    def serving(self) -> bool:
        return all(node.alive() for node in self.nodes)


def home() -> np.ndarray:
    from qtree_scene.scenario import load_scenario

    return np.asarray(load_scenario('s1').home, dtype=float)


def test_an_object_moved_into_the_path_is_replanned_and_retrieved(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus

    graph = Graph(launch, ros_node)
    bad = graph.set_events([{'kind': 'move', 'object': 'O5', 'xy': [0.8, 0.0], 'at_s': 0}])
    assert not bad.successful and "scene_events[0].xy: 'O5' overlaps 'T'" in bad.reason
    done = graph.send()
    # While the arm starts for the target (its blockers gone), O5 jumps in front of it.
    assert ros_node.spin_until(
        lambda: any(t.object_id == 'T' for t in graph.tracking) or done.done(), GOAL_TIMEOUT_S
    ), 'the target was never approached'
    assert not done.done(), done.result().result.message
    move = {'kind': 'move', 'object': 'O5', 'xy': IN_FRONT_OF_T, 'at_s': 0.3}
    armed = graph.set_events([move])
    assert armed.successful, armed.reason
    status, result = graph.result(done)
    print(f'\n[replan] {result.message}\n[replan] causes: {list(result.replan_causes)}')
    assert status == GoalStatus.STATUS_SUCCEEDED, result.message
    assert result.success and result.executed and result.replans == 1
    cause = result.replan_causes[0]
    assert cause.startswith("SCENE_CHANGED relocating 'T'") and "'O5' moved" in cause, cause
    assert 'undone' in cause
    executed = list(result.executed_ids)
    assert set(executed[:3]) == {'O1', 'O2', 'O3'}, executed  # kept, not done again
    assert executed[3:] == ['O5', 'T'], executed  # O5 now blocks T: moved first
    assert list(result.sequence) == executed
    assert ros_node.spin_until(lambda: {'O5', 'T'} <= graph.relocated(), 10.0)
    assert any(f.replans == 1 for f in graph.feedback), 'no feedback reported the re-plan'
    # item 4: one count per re-plan (how many depends on where O5's footprints fall)
    print(f'[replan] reused answers: {list(result.reused_answers)}')
    assert len(result.reused_answers) == 1 and result.reused_answers[0] >= 0
    assert graph.serving()


def test_a_grasp_failure_on_the_first_attempt_is_replanned_and_retrieved(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus

    graph = Graph(launch, ros_node)
    armed = graph.set_events([{'kind': 'grasp_failure', 'object': 'O1', 'attempt': 1}])
    assert armed.successful, armed.reason
    status, result = graph.result(graph.send())
    print(f'\n[grasp] {result.message}\n[grasp] causes: {list(result.replan_causes)}')
    assert status == GoalStatus.STATUS_SUCCEEDED, result.message
    assert result.replans == 1
    cause = result.replan_causes[0]
    assert cause.startswith("GRASP_FAILED relocating 'O1'") and 'attempt 1' in cause, cause
    executed = list(result.executed_ids)
    assert executed[-2:] == ['O1', 'T'] and executed.count('O1') == 1, executed
    # item 4: a refused grasp changes no geometry, so the planner kept its whole cache and the
    # re-plan's questions after the kept prefix were answered from it
    print(f'[grasp] reused answers: {list(result.reused_answers)}')
    assert len(result.reused_answers) == 1 and result.reused_answers[0] >= 1
    assert {'O1', 'O2', 'O3', 'T'} <= graph.relocated()
    assert graph.serving()


def test_max_replans_exceeded_ends_with_replan_limit(launch, ros_node) -> None:
    from action_msgs.msg import GoalStatus

    graph = Graph(launch, ros_node)
    # Either may come first in the learned sequence; max_replans=0: its refused grasp is one
    # re-plan too many (one re-plan and a second failure took 4.4 min of CI for the same check).
    fail_first = [{'kind': 'grasp_failure', 'object': o, 'attempt': 1} for o in ('O2', 'O3')]
    assert graph.set_events(fail_first).successful
    started = time.monotonic()
    status, result = graph.result(graph.send(max_replans=0))
    print(f'\n[limit] {result.message} ({time.monotonic() - started:.0f} s)')
    assert status == GoalStatus.STATUS_ABORTED
    assert result.error_code == graph.action.Result.REPLAN_LIMIT and not result.success
    assert result.message.startswith('max_replans=0 re-plans made, one more needed: GRASP_')
    assert result.replans == 0 and len(result.replan_causes) == 0
    assert 'T' not in result.executed_ids
    assert graph.arm_rests_at(home()), 'the arm is not back home after the undone grasp'
    assert graph.serving()
