"""PlannerService (the motion-planner node's core): scenes from /scene, answers, executions."""

from __future__ import annotations

import time

from qtree_scene.conversions import scene_msg
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
    assert logs[-1] == ('info', "scene 's1': planner rebuilt")
    first = _answer(service, 'O2')
    assert first.feasible and not first.from_cache
    # O2 carried to the drop zone (GRASPED, then RELOCATED): the same scene, the cache kept.
    for status in ('grasped', 'relocated'):
        moved = scene_msg(scenario, {'O2': ((0.0, 0.5, 0.1), (0, 0, 0, 1))}, {'O2': status})
        service.on_scene(moved)
    assert len(logs) == 2
    assert _answer(service, 'O2').from_cache
    # Moving an object that is still IN_CLUTTER is a new scene.
    service.on_scene(scene_msg(scenario, {'O5': ((0.9, -0.2, 0.06), (0, 0, 0, 1))}))
    assert len(logs) == 3 and not _answer(service, 'O2').from_cache


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
    assert logs[-1] == ('info', "scene 's2': planner rebuilt")
