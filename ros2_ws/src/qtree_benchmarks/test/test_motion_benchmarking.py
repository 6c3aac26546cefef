"""Benchmark modules: verification of planner answers in several orders, JSON block shape."""

from __future__ import annotations

import pytest
from qtree_benchmarks.motion import verification
from qtree_scene.placement import slot_position
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.verifier import TrajectoryVerifier


def test_placed_objects_stand_on_their_slots_in_order(boxed_scene):
    placed, approximated = verification.placed_objects(boxed_scene, ['O3', 'O0'])
    assert [o.id for o in placed] == ['O3', 'O0'] and approximated == 2
    for index, obj in enumerate(placed):
        assert obj.position == pytest.approx(tuple(slot_position(boxed_scene, index, obj)))


def test_placed_objects_stand_where_their_own_answer_released_them(free_scene, robot):
    """#29: the benchmark stood placed objects on their slot with their original yaw, not
    where (and turned as) the hand released them."""
    planner = MotionPlanner(free_scene, model=robot)
    planner.blockers.enabled = False
    first = planner.check('T', [])
    assert first.feasible, first.message
    answers = {(frozenset(), 'T'): first}
    placed, approximated = verification.placed_objects(free_scene, ['T'], answers, robot)
    assert approximated == 0
    expected = verification.released(free_scene.object('T'), first, robot)
    assert placed[0] == expected
    q_release = first.joint_trajectory[first.release_index]
    assert placed[0].position[:2] == pytest.approx(
        tuple(robot.ee_pose(q_release).translation[:2]), abs=0.05
    )


def test_feasible_answers_pass_in_every_order(boxed_scene, robot):
    planner = MotionPlanner(boxed_scene, model=robot)
    planner.blockers.enabled = False
    relocated = ['O0', 'O1', 'O2', 'O3', 'O4', 'O5']
    result = planner.check('T', relocated)
    assert result.feasible, result.message
    items = [((frozenset(relocated), 'T'), result)]
    part = verification.verify_results(boxed_scene, items, TrajectoryVerifier(robot))
    assert part['trajectories'] == 1
    assert part['colliding'] == 0 and part['limit_violations'] == 0, part['examples']
    merged = verification.merge([part], planner_rejections=0)
    for key in ('trajectories', 'colliding', 'limit_violations'):
        assert isinstance(merged[key], int)
    assert merged['min_clearance_mm'] > 0.0 and 0.0 <= merged['carried_tilt_max_deg'] < 90.0
    assert merged['max_gap_mm'] <= 10.0 + 1e-9
