"""Benchmark modules: verification of planner answers in several orders, JSON block shape."""

from __future__ import annotations

import pytest
from qtree_scene.placement import slot_position
from stpik_motion_planner.benchmarking import verification
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.verifier import TrajectoryVerifier


def test_placed_objects_stand_on_their_slots_in_order(boxed_scene):
    placed = verification.placed_objects(boxed_scene, ['O3', 'O0'])
    assert [o.id for o in placed] == ['O3', 'O0']
    for index, obj in enumerate(placed):
        assert obj.position == pytest.approx(tuple(slot_position(boxed_scene, index, obj)))


def test_feasible_answers_pass_in_every_order(boxed_scene, robot):
    planner = MotionPlanner(boxed_scene, model=robot)
    planner.blockers.annotate = lambda result, *_: result
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
    assert merged['max_gap_mm'] <= 10.0 + 1e-9
