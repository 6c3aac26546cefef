"""Answers kept across a scene change (#32 item 4): the rule, its geometry and the service."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.answer_reuse import (
    carry_over,
    clear_of_changes,
    kept_because,
    reuse_answers,
)
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.verifier import Carried

FEASIBLE = PlanResult(True, Reason.SUCCESS, 'ok')
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


@pytest.fixture(scope='module')
def planned(make_cylinder, make_scenario, robot):
    scene = make_scenario(
        make_cylinder('T', 0.65, 0.0, 'target'),
        make_cylinder('O1', 0.55, 0.0),
        make_cylinder('O2', 0.45, -0.35),
        make_cylinder('O3', 0.5, 0.3),
    )
    planner = MotionPlanner(scene, PlannerConfig(time_limit_s=60.0), model=robot)
    for object_id, relocated in [('T', []), ('O1', []), ('T', ['O1']), ('O2', []), ('O3', [])]:
        planner.check(object_id, relocated)
    return planner


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
    kept, why = reuse_answers(old, new, entries, lambda k, r: True)
    assert kept == {} and 'another scene' in why


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
    old = MotionPlanner(scene, PlannerConfig(time_limit_s=60.0), model=robot)
    for object_id, relocated in [('T', []), ('T', ['O2']), ('O1', [])]:
        old.check(object_id, relocated)
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
    for changed in (_moved(scene, 'O9', 0.55, 0.08), _moved(scene, 'O3', 0.5, 0.35)):
        planner = MotionPlanner(changed, old.config, model=robot)
        carry_over(old, planner)
        assert planner.cache.get('T', []) is None and planner.cache.get('T', ['O2']) is None
