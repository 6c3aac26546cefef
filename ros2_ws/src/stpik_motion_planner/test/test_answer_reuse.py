"""Answers kept across a scene change (#32 item 4): the rule, its geometry and the service."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.answer_reuse import (
    DROPPED_NOT_CLEAR,
    DROPPED_OBJECT,
    DROPPED_PLAN,
    DROPPED_RELOCATED,
    HARDER,
    REPLAYED,
    carry_over,
    carry_over_answers,
    clear_of_changes,
    judge,
    only_gains,
    reuse_answers,
)
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.footprint import PlannedAnswer, Region
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.verifier import Carried

FEASIBLE = PlanResult(True, Reason.SUCCESS, 'ok')


def kept_because(*args, **kwargs) -> str:
    """Why :func:`judge` keeps the answer, '' when it drops it."""
    verdict = judge(*args, **kwargs)
    return verdict.why if verdict.kept else ''


coord = st.floats(-1.0, 1.0, allow_nan=False)


def _moved(scene, object_id: str, x: float, y: float):
    objs = tuple(
        dataclasses.replace(o, position=(x, y, o.position[2])) if o.id == object_id else o
        for o in scene.objects
    )
    return dataclasses.replace(scene, objects=objs)


@settings(max_examples=200, deadline=None)
@given(
    st.booleans(),
    st.sets(st.sampled_from(['A', 'B', 'C'])),
    st.frozensets(st.sampled_from(['B', 'C', 'D'])),
    st.integers(0, 4),
)
def test_a_kept_feasible_answer_is_clear_of_the_change_and_untouched(clear, changed, rel, slots):
    """Property: kept <=> its motion is clear of the changed objects now, neither its object nor
    its relocated set changed, and its drop slot (|R|) is among the unchanged ones."""
    why = kept_because((rel, 'A'), FEASIBLE, changed, lambda: clear, slots)
    expected = clear and 'A' not in changed and not rel & changed and len(rel) < slots
    assert bool(why) == expected


def test_infeasible_answers_kept_by_size_or_when_their_plan_replays() -> None:
    key = (frozenset(), 'A')
    never = lambda: pytest.fail('an infeasible answer has no motion to verify')  # noqa: E731
    replays, differs = (lambda: True), (lambda: False)
    blocked = PlanResult(False, Reason.SCENE_COLLISION, 'no', blocking_ids=('B',))
    assert kept_because(key, blocked, {'B'}, never, 5, differs) == ''
    assert 'same scene queries' in kept_because(key, blocked, {'B'}, never, 5, replays)
    assert kept_because(key, blocked, {'B'}, never, 0, replays) == ''  # its drop slot changed
    # The statics-only sweeps alone do not keep it (they try every other approach only).
    immovable = PlanResult(False, Reason.NO_CARTESIAN_PATH, 'no', blocked_by_immovable=True)
    assert kept_because(key, immovable, {'B'}, never, 5, differs) == ''
    big = PlanResult(False, Reason.OBJECT_TOO_BIG, 'no')
    assert kept_because(key, big, {'B'}, never, 5)
    assert kept_because(key, big, {'A'}, never, 5, replays) == ''


def _asked(scene, robot, questions) -> MotionPlanner:
    """A planner of ``scene`` that answered ``questions`` ((object id, relocated) pairs)."""
    planner = MotionPlanner(scene, PlannerConfig(time_limit_s=60.0), model=robot)
    for object_id, relocated in questions:
        planner.check(object_id, relocated)
    return planner


@pytest.fixture(scope='module')
def planned(make_cylinder, make_scenario, robot):
    scene = make_scenario(
        make_cylinder('T', 0.65, 0.0, 'target'),
        make_cylinder('O1', 0.55, 0.0),
        make_cylinder('O2', 0.45, -0.35),
        make_cylinder('O3', 0.5, 0.3),
    )
    return _asked(scene, robot, [('T', []), ('O1', []), ('T', ['O1']), ('O2', []), ('O3', [])])


def test_clear_of_changes_is_the_verifier_among_the_changed_objects(planned) -> None:
    """A body put on the hand's path fails the check; one far away, or none, passes."""
    result = planned.cache.get('O1', [])
    assert result.feasible
    on_path = ObjectSpec('X', 'obstacle', 'cylinder', (0.55, 0.0, 0.1), radius=0.03, height=0.2)
    far = dataclasses.replace(on_path, position=(0.3, 0.6, 0.1))
    assert not clear_of_changes(planned, result, 'O1', [on_path])  # where O1 is grasped
    assert clear_of_changes(planned, result, 'O1', [far])
    assert clear_of_changes(planned, result, 'O1', [])


def test_carry_over_keeps_answers_away_from_the_change(planned, robot) -> None:
    far = MotionPlanner(_moved(planned.scenario, 'O2', 0.40, -0.45), planned.config, robot)
    summary = carry_over(planned, far)
    kept = {(tuple(sorted(r)), o) for (r, o), _ in far.cache.items()}
    # O2's own answer goes; T's, planned past O2's old pose, stays (O2 moved away from it)
    assert kept == {((), 'O1'), ((), 'O3'), (('O1',), 'T')}, summary
    assert summary == 'kept 3 of 5 cached answers (changed: O2)'
    for (relocated, object_id), result in far.cache.items():  # each passes a full verification
        standing = far.planning_scene(object_id, relocated)
        carried = Carried(far.scenario.object(object_id), result.grasp_index, result.release_index)
        trajectory = np.asarray(result.joint_trajectory)
        assert far.verifier.verify(trajectory, standing, carried).ok, (relocated, object_id)
    assert far.check('O1', []).from_cache and not far.check('O2', []).from_cache
    # O2 put where the hand passes on its way to O1 (7 cm or more from O1's centre)
    result = planned.cache.get('O1', [])
    q, o1 = np.asarray(result.joint_trajectory), np.asarray(planned.scenario.object('O1').position)
    for k in range(result.grasp_index, -1, -1):
        xy = np.asarray(robot.ee_pose(q[k]))[:2, 3]
        if np.linalg.norm(xy - o1[:2]) > 0.07:
            break
    into = MotionPlanner(_moved(planned.scenario, 'O2', *xy), planned.config, robot)
    carry_over(planned, into)
    assert ((), 'O1') not in {(tuple(sorted(r)), o) for (r, o), _ in into.cache.items()}


def test_a_moved_target_keeps_the_answers_of_the_others(planned, robot) -> None:
    """The target is an object like the others for the answers of the others: T moved by 1 cm
    drops T's own two answers and keeps the rest that are clear of it, each as a fresh planner
    in the new scene answers it (feasible, verified) (before: 'target changed', 0 kept)."""
    moved = MotionPlanner(_moved(planned.scenario, 'T', 0.66, 0.02), planned.config, robot)
    summary = carry_over(planned, moved)
    kept = {(tuple(sorted(r)), o) for (r, o), _ in moved.cache.items()}
    assert kept == {((), 'O1'), ((), 'O2'), ((), 'O3')}, summary
    assert summary == 'kept 3 of 5 cached answers (changed: T)'
    fresh = MotionPlanner(moved.scenario, planned.config, robot)
    for (relocated, object_id), result in moved.cache.items():
        standing = moved.planning_scene(object_id, relocated)
        carried = Carried(
            moved.scenario.object(object_id), result.grasp_index, result.release_index
        )
        trajectory = np.asarray(result.joint_trajectory)
        assert moved.verifier.verify(trajectory, standing, carried).ok, object_id
        assert fresh.check(object_id, sorted(relocated)).feasible == result.feasible
    assert not moved.check('T', []).from_cache


def test_reuse_needs_the_same_scene(make_cylinder, make_scenario) -> None:
    old = make_scenario(make_cylinder('T', 0.65, 0.0, 'target'))
    new = dataclasses.replace(old, name='other')
    entries = {(frozenset(), 'T'): FEASIBLE}
    reuse = reuse_answers(old, new, entries, lambda k, r: True)
    assert reuse.kept == {} and 'another scene' in reuse.summary


def test_an_infeasible_answer_is_kept_only_where_its_plan_goes_as_it_went(
    make_cylinder, make_scenario, robot
) -> None:
    """T, behind O1, is infeasible; its plan's queries found O1, O2 and O3 but never O9. O9
    moved farther: T's answers are kept and equal, message and blockers included, what a fresh
    planner answers in the new scene. O9 put beside O1, or O3 moved: they are planned again."""
    scene = make_scenario(
        make_cylinder('T', 0.65, 0.0, 'target'),
        make_cylinder('O1', 0.55, 0.0),
        make_cylinder('O2', 0.45, -0.35),
        make_cylinder('O3', 0.5, 0.3),
        make_cylinder('O9', 0.2, 0.55),
    )
    old = _asked(scene, robot, [('T', []), ('T', ['O2']), ('O1', [])])
    assert not old.cache.get('T', []).feasible and old.cache.get('T', []).blocking_ids == ('O1',)
    met = {o.id for o in old.footprints[(frozenset(), 'T')].region.met}
    assert 'O9' not in met and 'O1' in met

    farther = _moved(scene, 'O9', 0.15, 0.6)
    new = MotionPlanner(farther, old.config, model=robot)
    assert carry_over(old, new) == 'kept 3 of 3 cached answers (changed: O9)'
    fresh = MotionPlanner(farther, old.config, model=robot)
    for relocated in ([], ['O2']):
        kept, again = new.check('T', relocated), fresh.check('T', relocated)
        assert kept.from_cache and not again.from_cache
        assert (kept.reason, kept.message, kept.blocking_ids, kept.approach_blockers) == (
            again.reason,
            again.message,
            again.blocking_ids,
            again.approach_blockers,
        )
    # O3 moved: the plan met it where it stood, so the plan could go otherwise: planned again
    planner = MotionPlanner(_moved(scene, 'O3', 0.5, 0.35), old.config, model=robot)
    carry_over(old, planner)
    assert planner.cache.get('T', []) is None and planner.cache.get('T', ['O2']) is None


def test_an_infeasible_answer_is_kept_where_its_scene_only_gained_bodies(
    make_cylinder, make_scenario, robot
) -> None:
    """O9, never met by T's plan, put beside O1 (in reach of that plan): T's planning scene only
    gained a body, so T stays infeasible (kept by only_gains, before: planned again), with its
    blockers derived again: O9 is now one of them, as a fresh planner in the new scene finds."""
    scene = make_scenario(
        make_cylinder('T', 0.65, 0.0, 'target'),
        make_cylinder('O1', 0.55, 0.0),
        make_cylinder('O2', 0.45, -0.35),
        make_cylinder('O9', 0.2, 0.55),
    )
    old = _asked(scene, robot, [('T', []), ('T', ['O2']), ('O1', [])])
    assert not old.cache.get('T', []).feasible and old.cache.get('T', []).blocking_ids == ('O1',)
    beside = _moved(scene, 'O9', 0.55, 0.08)
    new = MotionPlanner(beside, old.config, model=robot)
    reuse = carry_over_answers(old, new)
    kept = reuse.kept
    assert kept[(frozenset(), 'T')] == HARDER and kept[(frozenset({'O2'}), 'T')] == HARDER
    # O1's grasp passes where O9 stands now
    assert reuse.dropped == {(frozenset(), 'O1'): DROPPED_NOT_CLEAR}, reuse.summary
    fresh = MotionPlanner(beside, old.config, model=robot)
    for relocated in ([], ['O2']):
        answer, again = new.check('T', relocated), fresh.check('T', relocated)
        assert answer.from_cache and not again.feasible
        assert 'O9' in answer.blocking_ids
        assert set(answer.blocking_ids) == set(again.blocking_ids), relocated
    # its recorded queries no longer show what it looked at: never replayed after that
    assert not new.footprints[(frozenset(), 'T')].region.complete
    # O9 taken away again: its scene lost a body, so it is planned again
    back = MotionPlanner(scene, old.config, model=robot)
    assert carry_over_answers(new, back).dropped[(frozenset(), 'T')] == DROPPED_PLAN


def test_a_relocated_object_that_moved_on_the_table_keeps_the_answers_it_is_relocated_in(
    planned, robot
) -> None:
    """O1 moved on the table: (R, o) with O1 in R plans around O1's envelope in its drop slot,
    wherever O1 stood, so T's answer after O1 is kept (before: dropped, 'R changed'); O1's own
    answer goes. The kept answer passes a full verification in the new scene."""
    moved = MotionPlanner(_moved(planned.scenario, 'O1', 0.56, 0.01), planned.config, robot)
    reuse = carry_over_answers(planned, moved)
    assert (frozenset({'O1'}), 'T') in reuse.kept, reuse.summary
    assert reuse.dropped[(frozenset(), 'O1')] == DROPPED_OBJECT
    result = moved.cache.get('T', ['O1'])
    standing = moved.planning_scene('T', ['O1'])
    carried = Carried(moved.scenario.object('T'), result.grasp_index, result.release_index)
    assert moved.verifier.verify(np.asarray(result.joint_trajectory), standing, carried).ok
    # resized, it is not the same envelope: dropped
    bigger = tuple(
        dataclasses.replace(o, radius=o.radius + 0.004) if o.id == 'O1' else o
        for o in planned.scenario.objects
    )
    resized = MotionPlanner(
        dataclasses.replace(planned.scenario, objects=bigger), planned.config, robot
    )
    dropped = carry_over_answers(planned, resized).dropped
    assert dropped[(frozenset({'O1'}), 'T')] == DROPPED_RELOCATED


@settings(max_examples=200, deadline=None)
@given(
    st.sets(st.sampled_from(['A', 'B', 'C'])),
    st.sets(st.sampled_from(['B', 'C'])),
    st.frozensets(st.sampled_from(['B', 'C', 'D'])),
    st.booleans(),
)
def test_a_relocated_object_may_have_moved_but_not_otherwise_changed(changed, moved, rel, clear):
    """Property: with the moved-only ids, R may hold those that moved, never the others."""
    moved &= changed
    why = kept_because((rel, 'A'), FEASIBLE, changed, lambda: clear, 4, moved=moved)
    assert bool(why) == (clear and 'A' not in changed and not rel & (changed - moved))


def test_only_planning_failures_get_harder() -> None:
    key = (frozenset(), 'A')
    yes, no = (lambda: True), (lambda: False)
    failure = PlanResult(False, Reason.IK_NOT_CONVERGED, 'no')
    assert kept_because(key, failure, {'B'}, no, 5, no, harder=yes) == HARDER
    assert kept_because(key, failure, {'B'}, no, 5, yes, harder=yes) == REPLAYED
    assert kept_because(key, failure, {'B'}, no, 5, no, harder=no) == ''
    assert kept_because(key, failure, {'B'}, no, 0, no, harder=yes) == ''  # its slot changed
    timeout = PlanResult(False, Reason.TIMEOUT, 'late')
    assert kept_because(key, timeout, {'B'}, no, 5, no, harder=yes) == ''
    assert kept_because(key, FEASIBLE, {'B'}, no, 5, no, harder=yes) == ''


def test_only_gains_needs_every_replaced_body_unmet(make_cylinder) -> None:
    a, b = make_cylinder('A', 0.5, 0.0), make_cylinder('B', 0.3, 0.3)
    b_moved = dataclasses.replace(b, position=(0.5, 0.1, b.position[2]))
    region = Region(np.zeros((0, 3)), np.zeros(0), frozenset({a}), complete=True)
    planned = PlannedAnswer(PlanResult(False, Reason.NO_CARTESIAN_PATH, 'no'), region)
    assert only_gains(planned, [], [b])  # added
    assert only_gains(planned, [b], [b_moved])  # moved from where the plan never looked
    assert not only_gains(planned, [a], [b_moved])  # A was met where it stood
    assert not only_gains(planned, [b], [])  # only taken away: replays decides
    incomplete = PlannedAnswer(planned.result, dataclasses.replace(region, complete=False))
    assert only_gains(incomplete, [], [b]) and not only_gains(incomplete, [b], [b_moved])
    assert not only_gains(None, [], [b])
