"""Request validation: size limits, short messages for huge requests, precheck (no ROS import)."""

from __future__ import annotations

import time

import pytest
from stpik_motion_planner.exceptions import InvalidRequest, PlanningTimeout
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason
from stpik_motion_planner.scene_checks import (
    MAX_ID_CHARS,
    MAX_RELOCATED_IDS,
    SHOWN_ID_CHARS,
    check_request_size,
    format_id,
    format_ids,
    validate_request,
)

MESSAGE_CHARS = 200  # every validation message stays below this, whatever the request


@pytest.fixture
def planner(boxed_scene, robot) -> MotionPlanner:
    return MotionPlanner(boxed_scene, model=robot)


def test_format_ids_shows_five_then_the_count():
    assert format_ids(['O1', 'O2']) == "['O1', 'O2']"
    text = format_ids([f'X{i}' for i in range(10_000)])
    assert text == "['X0', 'X1', 'X2', 'X3', 'X4', … (10000 ids)]"
    assert format_ids([]) == '[]'


def test_format_id_cuts_long_ids():
    assert format_id('O1') == "'O1'"
    text = format_id('O' * 100_000)
    assert text.startswith("'" + 'O' * SHOWN_ID_CHARS + "…'") and '100000 characters' in text
    assert len(text) < SHOWN_ID_CHARS + 30
    assert len(format_ids(['O' * 100_000] * 10_000)) < 6 * (SHOWN_ID_CHARS + 30)


@pytest.mark.parametrize(
    ('object_id', 'relocated', 'reason', 'fragment'),
    [
        ('T', ['O1'] * 10_000, Reason.INVALID_REQUEST, f'at most {MAX_RELOCATED_IDS}'),
        ('T', [f'X{i}' for i in range(10_000)], Reason.UNKNOWN_OBJECT, "unknown object 'X0'"),
        ('T', [''] * 10_000, Reason.INVALID_REQUEST, 'non-empty strings'),
        ('O' * 100_000, [], Reason.UNKNOWN_OBJECT, '100000 characters'),
        ('T', ['O' * 100_000] * 300, Reason.UNKNOWN_OBJECT, '100000 characters'),
        (
            'T',
            ['O1', 'O2', 'O1', 'O2'],
            Reason.INVALID_REQUEST,
            "['O1', 'O2'] (4 ids, 2 distinct)",
        ),
    ],
    ids=['10000 copies', '10000 unknown', '10000 empty', '100 kB id', '300 huge ids', 'dups'],
)
def test_huge_requests_get_short_messages(planner, object_id, relocated, reason, fragment):
    start = time.process_time()
    result = planner.check(object_id, relocated)
    assert time.process_time() - start < 0.5
    assert (result.feasible, result.reason) == (False, reason)
    assert fragment in result.message and len(result.message) < MESSAGE_CHARS, result.message
    assert planner.cache.misses == 0


def test_size_limits_without_a_scene():
    check_request_size('T', ['O1'] * MAX_RELOCATED_IDS)
    check_request_size('O' * MAX_ID_CHARS, [])
    with pytest.raises(InvalidRequest, match=f'at most {MAX_RELOCATED_IDS}') as info:
        check_request_size('T', ['O1'] * (MAX_RELOCATED_IDS + 1))
    assert info.value.reason == Reason.INVALID_REQUEST
    with pytest.raises(InvalidRequest, match=f'at most {MAX_ID_CHARS} characters'):
        check_request_size('T', ['O1', 'O' * (MAX_ID_CHARS + 1)])


def test_validate_request_order_keeps_the_documented_codes(boxed_scene):
    # An unknown id is UNKNOWN_OBJECT even in a list above the size limit (docs/RELIABILITY.md).
    with pytest.raises(InvalidRequest) as info:
        validate_request(boxed_scene, 'T', ['O1'] * 300 + ['ghost'])
    assert info.value.reason == Reason.UNKNOWN_OBJECT


def test_precheck_answers_bad_requests_and_cache_hits_only(planner):
    assert planner.precheck('ghost', []).reason == Reason.UNKNOWN_OBJECT
    assert planner.precheck('T', ['O1', 'O0']) is None  # needs planning
    first = planner.check('T', ['O1', 'O0'])
    again = planner.precheck('T', ['O0', 'O1'])
    assert again is not None and again.from_cache and again.reason == first.reason


def test_planning_timeout_past_reports_the_elapsed_time():
    limit_s = 0.05
    deadline = time.perf_counter() - 0.01  # started 0.06 s ago, 0.01 s over the limit
    err = PlanningTimeout.past(deadline, limit_s)
    assert 0.06 <= err.elapsed_s < 0.5 and err.limit_s == limit_s
    assert str(err).startswith('planning took 0.0') and '> time limit 0.050 s' in str(err)


def test_reason_families_follow_the_hundreds_of_the_srv() -> None:
    from stpik_motion_planner.result import Reason, ReasonFamily, reason_family

    assert reason_family(Reason.SUCCESS) == ReasonFamily.SUCCESS
    assert reason_family(Reason.NO_SCENE) == ReasonFamily.REQUEST_ERROR
    assert reason_family(Reason.CARRIED_COLLISION) == ReasonFamily.PLANNING_FAILURE
    assert reason_family(Reason.PLANNER_BUSY) == ReasonFamily.RUNTIME_FAILURE
    assert reason_family(250) == ReasonFamily.PLANNING_FAILURE  # a newer planner's 2xx code
    assert reason_family(400) == ReasonFamily.UNKNOWN
    assert reason_family(-1) == ReasonFamily.UNKNOWN
    assert {reason_family(r) for r in Reason} == set(ReasonFamily) - {ReasonFamily.UNKNOWN}
