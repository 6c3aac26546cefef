"""The node's RelocateObject oracle against a scripted client (no ROS graph needed)."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_msgs.srv import RelocateObject
from qtree_task_planner.exceptions import OracleUnavailableError
from qtree_task_planner.retry import Backoff
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
    unknown = ScriptedClient(Response(reason=404, message='from a newer planner'))
    with pytest.raises(OracleUnavailableError, match=r'reason 404.*newer planner'):
        RosPlannerOracle(unknown, 1.0, 1.0).feasible((), 'O1')  # never learned as -1
    silent = ScriptedClient(None, None)  # a lost reply is asked again once
    with pytest.raises(OracleUnavailableError, match=r'no answer in 0\.1 s'):
        RosPlannerOracle(silent, 0.1, 1.0).feasible((), 'O1')
    no_scene = ScriptedClient(*[Response(reason=Response.NO_SCENE, message='none')] * 5)
    with pytest.raises(OracleUnavailableError, match='none'):
        RosPlannerOracle(no_scene, 1.0, scene_wait_s=0.3).feasible((), 'O1')


FAST = Backoff(retries=3, missing_retries=1, first_s=0.001, cap_s=0.002)
BUSY = Response(reason=Response.PLANNER_BUSY, message='planner busy: 8 requests are waiting')
TIMED_OUT = Response(reason=Response.TIMEOUT, message='planning took 2.1 s')


def test_busy_and_timeout_are_asked_again_never_learned_as_infeasible() -> None:
    client = ScriptedClient(BUSY, TIMED_OUT, BUSY, Response(feasible=True, reason=0))
    oracle = RosPlannerOracle(client, 1.0, 1.0, backoff=FAST)
    assert oracle.feasible((), 'O1') is True  # was False: 303/301 were learned as -1
    assert oracle.retries == 3 and len(client.requests) == 4
    lost_then_blocked = ScriptedClient(None, Response(reason=Response.SCENE_COLLISION))
    oracle = RosPlannerOracle(lost_then_blocked, 0.05, 1.0, backoff=FAST)
    assert oracle.feasible((), 'T') is False
    assert oracle.retries == 1


def test_a_dead_planner_is_reported_within_one_timeout_naming_the_service() -> None:
    """#26: was two whole waits (10.2 s with a 5 s time-out); a lost reply is asked again in it."""
    import time

    silent = ScriptedClient(None, None, None)
    silent.srv_name = '/relocate_object'
    oracle = RosPlannerOracle(silent, 0.4, 1.0)
    start = time.monotonic()
    with pytest.raises(OracleUnavailableError, match=r'/relocate_object: no answer in 0\.4 s'):
        oracle.feasible((), 'O1')
    elapsed = time.monotonic() - start
    assert 0.4 <= elapsed < 0.75 and len(silent.requests) == 2  # the copy at 0.32 s, one wait


def test_a_busy_answer_to_the_copy_does_not_replace_the_pending_first() -> None:
    first = Future()  # planned slowly: answered after the copy was refused as busy
    client = ScriptedClient(BUSY)
    calls = [first]
    original = client.call_async
    client.call_async = lambda request: calls.pop(0) if calls else original(request)
    import threading

    threading.Timer(0.9, lambda: first.set_result(Response(feasible=True, reason=0))).start()
    oracle = RosPlannerOracle(client, 1.0, 1.0, backoff=FAST)  # the copy at 0.8 s
    assert oracle.feasible((), 'O1') is True and oracle.retries == 1


def test_busy_beyond_the_bound_gives_up_with_the_retries_counted() -> None:
    client = ScriptedClient(*[BUSY] * 4)
    oracle = RosPlannerOracle(client, 1.0, 1.0, backoff=FAST)
    with pytest.raises(OracleUnavailableError, match=r'reason 303.*gave up after 3 retries'):
        oracle.feasible(('O2',), 'O1')
    assert oracle.retries == 3 and len(client.requests) == 4


def test_backoff_doubles_up_to_its_cap() -> None:
    backoff = Backoff(retries=6, first_s=0.1, cap_s=1.0)
    assert [backoff.delay(k) for k in range(6)] == [0.1, 0.2, 0.4, 0.8, 1.0, 1.0]
    assert backoff.total_s() == pytest.approx(3.5)
    with pytest.raises(ValueError):
        Backoff(first_s=2.0, cap_s=1.0)


@settings(max_examples=60, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(
    feasible=st.booleans(),
    before=st.lists(st.sampled_from(['busy', 'timeout', 'lost']), max_size=6),
)
def test_a_loaded_planner_never_gives_a_wrong_answer(feasible: bool, before: list[str]) -> None:
    """Any mix of busy / timed-out / lost answers before the true one: the true answer, or an
    error (the goal aborts) - never the opposite of what an idle planner answers."""
    scripted = {'busy': BUSY, 'timeout': TIMED_OUT, 'lost': None}
    truth = Response(
        feasible=feasible, reason=Response.SUCCESS if feasible else Response.NO_CARTESIAN_PATH
    )
    client = ScriptedClient(*[scripted[b] for b in before], truth)
    oracle = RosPlannerOracle(client, 0.01, 1.0, backoff=FAST)
    try:
        answer = oracle.feasible((), 'O1')
    except OracleUnavailableError:
        too_many_busy = sum(b != 'lost' for b in before) > FAST.retries
        assert too_many_busy or 'lost' in before  # a copy of a lost question met a busy one
        return
    assert answer is feasible


def test_answer_reads_blocking_ids() -> None:
    blocked = Response.SCENE_COLLISION
    client = ScriptedClient(
        Response(feasible=True, reason=Response.SUCCESS),
        Response(blocking_ids=['O1', 'O3', 'O2'], feasible=False, reason=blocked),
        Response(blocked_by_immovable=True, feasible=False, reason=Response.JOINT_LIMIT),
        Response(feasible=False, reason=blocked),
    )
    oracle = RosPlannerOracle(client, 1.0, 1.0)
    assert oracle.answer((), 'O1') == (True, ())
    assert oracle.answer(('O3',), 'T') == (False, ('O1', 'O2'))  # relocated ids dropped
    assert oracle.answer((), 'T') == (False, ())  # blocked by nothing movable
    assert oracle.answer((), 'T') == (False, None)  # no blocker named: no report


def test_answer_keeps_the_per_approach_blockers() -> None:
    blocked = Response.SCENE_COLLISION
    client = ScriptedClient(
        Response(
            blocking_ids=['O1'],
            approach_blocking_ids=['O1', 'O1', 'O2'],
            approach_blocker_counts=[1, 2],
            feasible=False,
            reason=blocked,
        ),
        Response(  # malformed: the counts name more ids than sent
            blocking_ids=['O1'],
            approach_blocking_ids=['O1'],
            approach_blocker_counts=[1, 2],
            feasible=False,
            reason=blocked,
        ),
    )
    oracle = RosPlannerOracle(client, 1.0, 1.0)
    assert oracle.approach_blockers((), 'T') is None  # nothing asked yet
    assert oracle.answer((), 'T') == (False, ('O1',))
    assert oracle.approach_blockers((), 'T') == ({'O1'}, {'O1', 'O2'})
    assert oracle.answer(('O3',), 'T') == (False, ('O1',))
    assert oracle.approach_blockers(('O3',), 'T') is None  # the report is dropped, not guessed
