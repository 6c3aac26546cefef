"""The node's RelocateObject oracle against a scripted client (no ROS graph needed)."""

import pytest
from qtree_msgs.srv import RelocateObject
from qtree_task_planner.exceptions import OracleUnavailableError
from qtree_task_planner.ros_oracle import RosPlannerOracle
from rclpy.task import Future

Response = RelocateObject.Response


class ScriptedClient:
    """Answers call_async with the next scripted response (None: never answers)."""

    def __init__(self, *responses: Response | None) -> None:
        self.responses = list(responses)
        self.requests: list = []

    def call_async(self, request) -> Future:
        self.requests.append(request)
        future = Future()
        response = self.responses.pop(0)
        if response is not None:
            future.set_result(response)
        return future


def test_feasible_and_cache_counting() -> None:
    client = ScriptedClient(
        Response(feasible=True, reason=Response.SUCCESS),
        Response(feasible=False, reason=Response.SCENE_COLLISION, from_cache=True),
    )
    oracle = RosPlannerOracle(client, timeout_s=1.0, scene_wait_s=1.0)
    assert oracle.feasible(('O1',), 'O2') is True
    assert oracle.feasible((), 'T') is False  # a planning failure is -1, not an error
    assert oracle.planner_runs == 1  # the second answer came from the planner's cache
    assert client.requests[0].relocated_ids == ['O1'] and not client.requests[0].execute


def test_no_scene_is_retried_then_answered() -> None:
    client = ScriptedClient(
        Response(reason=Response.NO_SCENE, message='no /scene'),
        Response(feasible=True, reason=Response.SUCCESS),
    )
    assert RosPlannerOracle(client, 1.0, scene_wait_s=2.0).feasible((), 'O1') is True
    assert len(client.requests) == 2


def test_request_errors_and_timeouts_raise() -> None:
    rejected = ScriptedClient(Response(reason=Response.UNKNOWN_OBJECT, message="no 'X'"))
    with pytest.raises(OracleUnavailableError, match=r"reason 101.*no 'X'"):
        RosPlannerOracle(rejected, 1.0, 1.0).feasible((), 'X')
    silent = ScriptedClient(None)
    with pytest.raises(OracleUnavailableError, match=r'no answer in 0\.1 s'):
        RosPlannerOracle(silent, 0.1, 1.0).feasible((), 'O1')
    no_scene = ScriptedClient(*[Response(reason=Response.NO_SCENE, message='none')] * 5)
    with pytest.raises(OracleUnavailableError, match='none'):
        RosPlannerOracle(no_scene, 1.0, scene_wait_s=0.3).feasible((), 'O1')


class _WithBlockers(Response):
    """A response carrying the issue #14 blocker fields (until they land in the .srv)."""

    def __init__(self, blocking_ids=(), blocked_by_immovable=False, **kw) -> None:
        super().__init__(**kw)
        self.__dict__['_ids'] = list(blocking_ids)
        self.__dict__['_immovable'] = blocked_by_immovable

    @property
    def blocking_ids(self):
        return self.__dict__['_ids']

    @property
    def blocked_by_immovable(self):
        return self.__dict__['_immovable']


def test_answer_reads_blocking_ids() -> None:
    blocked = Response.SCENE_COLLISION
    client = ScriptedClient(
        Response(feasible=True, reason=Response.SUCCESS),
        _WithBlockers(['O1', 'O3', 'O2'], feasible=False, reason=blocked),
        _WithBlockers([], True, feasible=False, reason=Response.JOINT_LIMIT),
        Response(feasible=False, reason=Response.TIMEOUT),
        _WithBlockers([], feasible=False, reason=blocked),
    )
    oracle = RosPlannerOracle(client, 1.0, 1.0)
    assert oracle.answer((), 'O1') == (True, ())
    assert oracle.answer(('O3',), 'T') == (False, ('O1', 'O2'))  # relocated ids dropped
    assert oracle.answer((), 'T') == (False, ())  # blocked by nothing movable
    assert oracle.answer((), 'T') == (False, None)  # a time-out reports nobody
    assert oracle.answer((), 'T') == (False, None)  # no blocker named: no report
