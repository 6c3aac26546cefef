"""Scene events and re-plans as timeline lines (#32 item 5; no ROS graph)."""

from __future__ import annotations

from types import SimpleNamespace

from qtree_msgs.msg import PlanningEvent, ReplanEvent
from qtree_recorder.world_changes import REPLAN_TOPIC, WorldChanges, replan_line, timeline
from qtree_scene.message import scene_msg
from qtree_scene.scenario import load_scenario

S1 = load_scenario('s1')
UP = (0, 0, 0, 1)


def test_scene_events_are_clutter_changes_not_relocations() -> None:
    world = WorldChanges()
    assert world.on_message('/scene', scene_msg(S1)) == []  # the first scene: the baseline
    carried = scene_msg(S1, {'O2': ((0.0, 0.5, 0.3), UP)}, {'O2': 'grasped'})
    assert world.on_message('/scene', carried) == []  # O2 leaves the clutter in the hand
    moved = scene_msg(
        S1, {'O2': ((0.0, 0.5, 0.3), UP), 'O5': ((0.9, -0.2, 0.06), UP)}, {'O2': 'grasped'}
    )
    (line,) = world.on_message('/scene', moved)
    assert line.startswith("scene: 'O5' moved ")
    put_back = scene_msg(S1, {'O5': ((0.9, -0.2, 0.06), UP)})  # the undone relocation
    assert world.on_message('/scene', put_back) == []
    assert world.on_message('/scene', put_back) == []
    o5 = next(o for o in S1.objects if o.id == 'O5')
    without = S1.__class__(**{**S1.__dict__, 'objects': tuple(o for o in S1.objects if o != o5)})
    assert world.on_message('/scene', scene_msg(without)) == ["scene: 'O5' removed"]


def test_world_answers_and_replans() -> None:
    world = WorldChanges()
    answer = PlanningEvent(object_id='T', reason=304, message="'O5' moved; undone")
    assert world.on_message('/motion_planner/events', answer) == [
        "motion planner: SCENE_CHANGED relocating 'T': 'O5' moved; undone"
    ]
    assert world.on_message('/motion_planner/events', PlanningEvent(reason=205)) == []
    started = ReplanEvent(replan=2, phase='started', cause='GRASP_FAILED x', kept_ids=[])
    assert replan_line(started) == 're-plan 2 started: GRASP_FAILED x (done so far: none)'
    failed = ReplanEvent(
        replan=2, phase='failed', kept_ids=['O1'], reused_answers=0, planner_runs=7
    )
    assert world.on_message(REPLAN_TOPIC, failed) == [
        "re-plan 2 failed: kept ['O1'], then (none); 0 answers reused, 7 planner runs"
    ]


def test_bad_messages_give_a_line_not_an_exception() -> None:
    world = WorldChanges()
    assert world.on_message('/scene', SimpleNamespace())[0].startswith('unreadable /scene')
    assert world.on_message('/other', None) == []
    items = [
        SimpleNamespace(
            topic=REPLAN_TOPIC,
            log_time_ns=2_500_000_000,
            message=ReplanEvent(replan=1, phase='started', cause='c'),
        )
    ]
    assert list(timeline(items, 1_000_000_000)) == [
        '  +1.500 s  re-plan 1 started: c (done so far: none)'
    ]
