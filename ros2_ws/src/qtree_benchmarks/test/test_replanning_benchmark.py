"""The replanning benchmark's core (#32 item 6): the events it applies, its rows, one real run."""

from __future__ import annotations

import math

import numpy as np
import pytest
from qtree_benchmarks.task.clutter import make_planner
from qtree_benchmarks.task.replanning import (
    ADDED_ID,
    EVENTS,
    RunOutcome,
    apply_event,
    learn,
    run_event,
    summary_rows,
)
from qtree_scene.scenario import load_scenario, validate_scenario

S1 = load_scenario('s1')
SEQUENCE = ('O2', 'O3', 'O1', 'T')  # s1's optimum


def _moved(before, after) -> set[str]:
    old = {o.id: o for o in before.objects}
    return {o.id for o in after.objects if old.get(o.id) != o}


@pytest.mark.parametrize('event', EVENTS)
@pytest.mark.parametrize('step', [0, 1, 2])
def test_every_event_gives_a_valid_scene_changing_one_object(event: str, step: int) -> None:
    changed = apply_event(S1, event, SEQUENCE, step, np.random.default_rng(step))
    assert changed is not None, (event, step)
    scene, what = changed
    validate_scenario(scene)  # raises on overlaps, objects off the table or floating
    ids = _moved(S1, scene)
    if event == 'grasp_failure':
        assert ids == set() and SEQUENCE[step] in what
        return
    assert len(ids) == 1, ids
    (moved,) = ids
    assert moved not in SEQUENCE[:step], 'an object already relocated was moved'
    if event == 'object_added':
        assert moved == ADDED_ID and len(scene.objects) == len(S1.objects) + 1
    elif event == 'target_moved':
        assert moved == 'T' and math.dist(S1.target.position, scene.target.position) >= 0.05
    elif event == 'moved_out_of_way':
        assert moved in SEQUENCE[step:-1]  # a blocker the plan still had to remove
    else:
        assert moved != SEQUENCE[step]
    if event in ('moved_into_path', 'object_added'):  # between the next object and the base
        next_xy = np.asarray(S1.object(SEQUENCE[step]).position[:2])
        new_xy = np.asarray(scene.object(moved).position[:2])
        assert np.linalg.norm(new_xy) < np.linalg.norm(next_xy)
        assert np.linalg.norm(new_xy - next_xy) < 0.25


def test_an_event_with_nothing_to_move_is_skipped() -> None:
    # the last step: no blocker left to move out of the way
    assert apply_event(S1, 'moved_out_of_way', SEQUENCE, 3, np.random.default_rng(0)) is None


def _outcome(**changes) -> RunOutcome:
    base = dict(
        scenario='s', event='grasp_failure', seed=0, step=0, changed='', solvable=True,
        decided_by='',
        retrieved=True, replans=1, extra_planner_runs=2, cached=10, reused=5, recovery_s=1.0,
        violations=0, sequence=(),
    )  # fmt: skip
    return RunOutcome(**{**base, **changes})


def test_rows_have_the_issue_keys_and_count_retrieved_among_solvable_runs() -> None:
    outcomes = [
        _outcome(recovery_s=1.0, reused=10),
        _outcome(recovery_s=3.0, retrieved=False, solvable=True, reused=0),
        _outcome(recovery_s=2.0, retrieved=False, solvable=False, cached=0, reused=0),
    ]
    (row,) = summary_rows(outcomes)
    assert list(row) == [
        'scenario', 'event', 'runs', 'retrieved', 'replans_mean', 'extra_planner_runs_mean',
        'reused_answers_share', 'recovery_s_median',
    ]  # fmt: skip
    assert row['runs'] == 3 and row['retrieved'] == 0.5  # the unsolvable run is left out
    assert row['recovery_s_median'] == 2.0
    assert row['reused_answers_share'] == pytest.approx(
        (1.0 + 0.0 + 1.0) / 3, abs=1e-3
    )  # 0 cached: 1


@pytest.fixture(scope='module')
def learned():
    planner = make_planner(S1)
    result = learn(planner, (), [o.id for o in S1.obstacles], 'T')
    return planner, result


def test_a_run_recovers_verified_after_the_change(learned) -> None:
    planner, first = learned
    assert first.status == 'optimal' and len(first.sequence) == 4
    outcome = run_event(planner, first.sequence, 'moved_out_of_way', 1, make_planner)
    assert outcome is not None and outcome.retrieved and outcome.solvable
    assert outcome.violations == 0
    moved = outcome.changed.split("'")[1]
    assert moved not in outcome.sequence[outcome.step :]  # out of the way: no longer removed
    assert outcome.sequence[-1] == 'T' and outcome.cached == len(planner.cache)
    again = run_event(planner, first.sequence, 'grasp_failure', 0, make_planner)
    assert (
        again.reused == again.cached
        and again.sequence[: again.step] == first.sequence[: again.step]
    )
