"""Answers kept across a scene change (#32 item 4): the rule, its geometry and the service."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.answer_reuse import (
    Boxes,
    _subdivided,
    carry_over,
    footprint,
    kept_because,
    reuse_answers,
    swept_volume,
)
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult, Reason

FEASIBLE = PlanResult(True, Reason.SUCCESS, 'ok')
coord = st.floats(-1.0, 1.0, allow_nan=False)


def _moved(scene, object_id: str, x: float, y: float):
    objs = tuple(
        dataclasses.replace(o, position=(x, y, o.position[2])) if o.id == object_id else o
        for o in scene.objects
    )
    return dataclasses.replace(scene, objects=objs)


@st.composite
def boxes(draw, n_max: int = 6):
    n = draw(st.integers(0, n_max))
    lo = np.array([[draw(coord) for _ in range(3)] for _ in range(n)]).reshape(n, 3)
    size = np.array([[draw(st.floats(0.0, 0.5)) for _ in range(3)] for _ in range(n)])
    return Boxes(lo, lo + size.reshape(n, 3))


@settings(max_examples=200, deadline=None)
@given(boxes(), boxes(3), st.sets(st.sampled_from(['A', 'B', 'C'])), st.booleans())
def test_a_kept_feasible_answer_never_meets_a_changed_footprint(volume, prints, changed, big):
    """Property: kept => no swept box intersects any changed footprint, and the answer's object
    and its relocated set are untouched."""
    footprints = list(zip(prints.lo, prints.hi, strict=True))
    relocated = frozenset({'B'}) if big else frozenset()
    why = kept_because((relocated, 'A'), FEASIBLE, changed, footprints, lambda: volume, 5)
    brute = any(
        np.all(vlo <= fhi) and np.all(flo <= vhi)
        for vlo, vhi in zip(volume.lo, volume.hi, strict=True)
        for flo, fhi in footprints
    )
    if why:
        assert not brute and 'A' not in changed and not relocated & changed
    else:
        assert brute or 'A' in changed or relocated & changed


def test_infeasible_answers_kept_only_when_independent_of_movable_objects() -> None:
    far = [(np.full(3, 5.0), np.full(3, 6.0))]
    key = (frozenset(), 'A')
    never = lambda: pytest.fail('an infeasible answer has no sweep')  # noqa: E731
    blocked = PlanResult(False, Reason.SCENE_COLLISION, 'no', blocking_ids=('B',))
    assert kept_because(key, blocked, {'B'}, far, never, 5) == ''
    immovable = PlanResult(False, Reason.NO_CARTESIAN_PATH, 'no', blocked_by_immovable=True)
    assert 'statics-only' in kept_because(key, immovable, {'B'}, far, never, 5)
    assert kept_because(key, immovable, {'B'}, far, never, 0) == ''  # slot 0 changed
    big = PlanResult(False, Reason.OBJECT_TOO_BIG, 'no')
    assert kept_because(key, big, {'B'}, far, never, 5)
    assert kept_because(key, big, {'A'}, far, never, 5) == ''


def test_footprint_of_a_turned_box_holds_its_corners() -> None:
    box = ObjectSpec('B', 'obstacle', 'box', (0.5, 0.1, 0.05), yaw=0.7, size=(0.1, 0.04, 0.1))
    lo, hi = footprint(box, 0.025)
    c, s = np.cos(0.7), np.sin(0.7)
    for dx in (-0.05, 0.05):
        for dy in (-0.02, 0.02):
            corner = np.array([0.5 + c * dx - s * dy, 0.1 + s * dx + c * dy])
            assert np.all(lo[:2] + 0.025 - 1e-12 <= corner) and np.all(
                corner <= hi[:2] - 0.025 + 1e-12
            )
    assert hi[2] - lo[2] == pytest.approx(0.1 + 0.05)


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


def test_swept_volume_holds_the_arm_between_samples(planned, robot) -> None:
    result = planned.cache.get('O1', [])
    assert result.feasible
    volume = swept_volume(robot, planned.verifier.reach, result, planned.scenario.object('O1'))
    q, _, _ = _subdivided(result)
    rng = np.random.default_rng(0)
    n_geoms = len(robot.geometry_model.geometryObjects)
    for k in rng.integers(0, len(q) - 1, 40):
        robot.forward(q[k] + rng.random() * (q[k + 1] - q[k]))
        for placement in robot.geometry_data.oMg:
            p = placement.translation
            assert np.any(np.all((volume.lo <= p) & (p <= volume.hi), axis=1))
    assert len(volume.lo) >= (len(q) - 1) * n_geoms  # one box per segment and link at least


def test_carry_over_keeps_answers_away_from_the_change(planned, robot) -> None:
    far = MotionPlanner(_moved(planned.scenario, 'O2', 0.40, -0.45), planned.config, robot)
    summary = carry_over(planned, far)
    kept = {(tuple(sorted(r)), o) for (r, o), _ in far.cache.items()}
    assert kept == {((), 'O1'), ((), 'O3')}, summary  # O2's own answer and T's near its old pose
    assert summary == 'kept 2 of 5 cached answers (changed: O2)'
    assert far.check('O1', []).from_cache and not far.check('O2', []).from_cache
    into = MotionPlanner(_moved(planned.scenario, 'O2', 0.60, -0.06), planned.config, robot)
    carry_over(planned, into)
    assert ((), 'O1') not in {(tuple(sorted(r)), o) for (r, o), _ in into.cache.items()}
    target = MotionPlanner(_moved(planned.scenario, 'T', 0.66, 0.02), planned.config, robot)
    assert carry_over(planned, target) == "kept 0 of 5 cached answers: target 'T' changed"
    assert len(target.cache) == 0


def test_reuse_needs_the_same_scene(make_cylinder, make_scenario) -> None:
    old = make_scenario(make_cylinder('T', 0.65, 0.0, 'target'))
    new = dataclasses.replace(old, name='other')
    entries = {(frozenset(), 'T'): FEASIBLE}
    kept, why = reuse_answers(
        old, new, entries, 0.025, lambda k, r: Boxes(np.zeros((0, 3)), np.zeros((0, 3)))
    )
    assert kept == {} and 'another scene' in why
