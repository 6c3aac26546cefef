"""PlannerService (the motion-planner node's core): scenes from /scene, answers, executions."""

from __future__ import annotations

import time

from qtree_scene.message import scene_msg
from qtree_scene.scenario import load_scenario
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.result import Reason
from stpik_motion_planner.service import PlannerService


def _service() -> tuple[PlannerService, list[tuple[str, str]]]:
    logs: list[tuple[str, str]] = []
    return PlannerService(PlannerConfig, lambda level, line: logs.append((level, line))), logs


def _answer(service: PlannerService, object_id: str, relocated: list[str] = ()):
    return service.answer(object_id, list(relocated), time.monotonic(), 10.0)


def test_scene_contract_frame_and_relocated_objects() -> None:
    service, logs = _service()
    assert _answer(service, 'T').reason == Reason.NO_SCENE
    wrong = scene_msg(load_scenario('s1'))
    wrong.header.frame_id = 'camera_link'
    service.on_scene(wrong)
    rejected = _answer(service, 'T')
    assert rejected.reason == Reason.INVALID_SCENE and 'header.frame_id' in rejected.message
    assert logs[-1][0] == 'warning'
    scenario = load_scenario('s1')
    service.on_scene(scene_msg(scenario))
    assert logs[-1] == ('info', "scene 's1': planner rebuilt, no cached answers")
    first = _answer(service, 'O2')
    assert first.feasible and not first.from_cache
    # O2 carried to the drop zone (GRASPED, then RELOCATED): the same scene, the cache kept.
    for status in ('grasped', 'relocated'):
        moved = scene_msg(scenario, {'O2': ((0.0, 0.5, 0.1), (0, 0, 0, 1))}, {'O2': status})
        service.on_scene(moved)
    assert len(logs) == 2
    assert _answer(service, 'O2').from_cache
    # Moving an object that is still IN_CLUTTER is a new scene; O2's answer is kept only if O5's
    # old and new footprints are clear of its motion (#32 item 4), as the log line says.
    service.on_scene(scene_msg(scenario, {'O5': ((0.9, -0.2, 0.06), (0, 0, 0, 1))}))
    assert len(logs) == 3 and 'changed: O5' in logs[-1][1]
    kept = 'kept 1 of 1' in logs[-1][1]
    assert kept or 'kept 0 of 1' in logs[-1][1]
    assert _answer(service, 'O2').from_cache == kept
    # Moving O2 itself drops its answer.
    service.on_scene(scene_msg(scenario, {'O2': ((0.9, 0.2, 0.06), (0, 0, 0, 1))}))
    assert 'changed: O2' in logs[-1][1] and not _answer(service, 'O2').from_cache


def test_scene_during_execution_is_applied_after_it() -> None:
    service, logs = _service()
    service.on_scene(scene_msg(load_scenario('s1')))
    plan = _answer(service, 'O2')

    def follow(result):
        service.on_scene(scene_msg(load_scenario('s2')))  # deferred: nothing rebuilt yet
        assert len(logs) == 1
        again = service.execute(result, lambda r: r)
        assert again.reason == Reason.EXECUTION_FAILED and 'another relocation' in again.message
        return result

    assert service.execute(plan, follow).feasible
    assert logs[-1][1].startswith("scene 's2': planner rebuilt, kept 0 of 1")


def test_a_request_waits_for_the_first_scene_and_for_the_scene_it_names() -> None:
    """A question sent just after a scene was set (CI: the example client asked before /scene
    arrived, NO_SCENE) waits for it up to scene_wait_s; a named scene the planner does not have
    is NO_SCENE naming both scenes."""
    import threading

    service, _ = _service()
    late = threading.Timer(0.3, service.on_scene, [scene_msg(load_scenario('s1'))])
    late.start()
    started = time.monotonic()
    answer = service.answer('O2', [], started, 10.0, '', scene_wait_s=20.0)
    assert answer.feasible and 0.25 < time.monotonic() - started < 15.0
    stale = service.answer('O2', [], time.monotonic(), 10.0, 's2', scene_wait_s=0.2)
    assert stale.reason == Reason.NO_SCENE and "'s2'" in stale.message and "'s1'" in stale.message
    threading.Timer(0.3, service.on_scene, [scene_msg(load_scenario('s2'))]).start()
    named = service.answer('O3', [], time.monotonic(), 10.0, 's2', scene_wait_s=20.0)
    assert named.reason != Reason.NO_SCENE, named.message
    assert service.answer('T', [], time.monotonic(), 10.0, 's2').reason != Reason.NO_SCENE


def test_no_scene_is_answered_after_scene_wait_s_and_a_rejected_scene_at_once() -> None:
    service, _ = _service()
    started = time.monotonic()
    assert service.answer('T', [], started, 10.0, '', 0.3).reason == Reason.NO_SCENE
    assert time.monotonic() - started >= 0.3
    wrong = scene_msg(load_scenario('s1'))
    wrong.header.frame_id = 'camera_link'
    service.on_scene(wrong)
    started = time.monotonic()
    assert service.answer('T', [], started, 10.0, '', 30.0).reason == Reason.INVALID_SCENE
    assert time.monotonic() - started < 5.0


def test_a_request_without_an_object_id_is_answered_at_once_without_a_scene() -> None:
    """The nodes' probe (empty object id) waited scene_wait_s for a scene and was never answered
    within its 2 s attempts (suite of 9ffde18): bad requests need no scene."""
    service, _ = _service()
    started = time.monotonic()
    answer = service.answer('', [], started, 10.0, '', scene_wait_s=30.0)
    assert answer.reason == Reason.INVALID_REQUEST and 'object_id' in answer.message
    assert time.monotonic() - started < 1.0
