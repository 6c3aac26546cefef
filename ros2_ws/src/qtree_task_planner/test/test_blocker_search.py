"""BLOCKER-SEARCH: optimality on hand-built scenes, agreement with the exact search, budgets."""

import contextlib
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_task_planner.blocker_search import (
    BUDGET_EXPANSIONS,
    BUDGET_RUNS,
    BUDGET_TIME,
    STATUS_BUDGET,
    STATUS_OPTIMAL,
    STATUS_UNSOLVABLE,
    BlockerSearch,
    BlockerSearchConfig,
    blocker_search,
    smallest_hitting_set,
)
from qtree_task_planner.exact import solve_exact
from qtree_task_planner.exceptions import InvalidParameterError, InvalidScenarioError
from qtree_task_planner.oracle import (
    REASON_IK_NOT_CONVERGED,
    FeasibilityAnswer,
    MemoOracle,
    MotionPlannerOracle,
    TableOracle,
    approach_blockers_of,
    recheck_config,
)
from qtree_task_planner.testing import (
    TOY_OBSTACLES,
    TOY_OPTIMAL_LEVEL,
    TOY_REQUIREMENTS,
    decoy_requirements,
    random_requirements,
)


def _feasible_order(sequence, requirements) -> bool:
    oracle = TableOracle(requirements)
    return all(oracle.feasible(sequence[:i], o) for i, o in enumerate(sequence))


def test_toy_scene_optimum_is_certified() -> None:
    result = blocker_search(TOY_OBSTACLES, 'T', TableOracle(TOY_REQUIREMENTS))
    assert result.status == STATUS_OPTIMAL and result.certified and not result.budget_hit
    assert len(result.sequence) == TOY_OPTIMAL_LEVEL == result.lower_bound
    assert set(result.sequence) == {'O1', 'O2', 'O3', 'T'}  # the unique optimal set
    assert _feasible_order(result.sequence, TOY_REQUIREMENTS)


def test_decoys_are_never_asked_about() -> None:
    obstacles, requirements = decoy_requirements(3, 15)
    oracle = TableOracle(requirements)
    result = blocker_search(obstacles, 'T', oracle)
    assert result.sequence == ('C3', 'C2', 'C1', 'T') and result.status == STATUS_OPTIMAL
    assert result.planner_runs == oracle.planner_runs <= 7  # 4 failures + 3 steps of the chain
    assert result.relevant == 3  # the decoys never entered a constraint
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    assert exact.level == 4 and exact.queries > 100 * result.planner_runs


@pytest.mark.parametrize(
    ('requirements', 'reason'),
    [
        ({'T': []}, 'target blocked by nothing movable'),
        ({'T': [{'O1'}], 'O1': [{'O2'}], 'O2': [{'O1'}]}, 'a cycle'),
        ({'T': [{'O1'}], 'O1': []}, 'its only blocker cannot move'),
    ],
)
def test_unsolvable_scenes_are_proven(requirements, reason) -> None:
    for report in ('union', 'fewest', 'none'):
        result = blocker_search(('O1', 'O2'), 'T', TableOracle(requirements, report=report))
        assert result.status == STATUS_UNSOLVABLE, reason
        assert result.sequence == () and result.lower_bound == 0 and result.certified


def test_free_target_and_no_obstacles() -> None:
    assert blocker_search((), 'T', TableOracle({})).sequence == ('T',)
    assert blocker_search((), 'T', TableOracle({'T': []})).status == STATUS_UNSOLVABLE
    result = blocker_search(('O1',), 'T', TableOracle({}))
    assert result.sequence == ('T',) and result.planner_runs == 1


@settings(max_examples=60, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(1, 8),
    report=st.sampled_from(['union', 'fewest', 'none']),
)
def test_same_optimal_level_as_the_exact_search(seed, n, report) -> None:
    obstacles, requirements = random_requirements(n, np.random.default_rng(seed), p_blocked=0.6)
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    result = blocker_search(obstacles, 'T', TableOracle(requirements, report=report))
    assert result.certified and result.status != STATUS_BUDGET
    assert len(result.sequence) == exact.level
    if result.sequence:
        assert _feasible_order(result.sequence, requirements)


def test_unverified_partial_reports_are_a_heuristic() -> None:
    # T: {O1, O2} or {O3}; the 'fewest' report names only O3, which is blocked for good
    requirements = {'T': [{'O1', 'O2'}, {'O3'}], 'O3': [{'O4'}], 'O4': []}
    obstacles = ('O1', 'O2', 'O3', 'O4')
    oracle = TableOracle(requirements, report='fewest')
    heuristic = blocker_search(obstacles, 'T', oracle, BlockerSearchConfig(verify='never'))
    assert not heuristic.certified and heuristic.status == STATUS_UNSOLVABLE  # wrong, and says so
    verified = blocker_search(obstacles, 'T', TableOracle(requirements, report='fewest'))
    assert verified.certified and verified.sequence == ('O1', 'O2', 'T') and verified.verifications


def test_budgets_stop_the_search_and_say_which() -> None:
    obstacles, requirements = random_requirements(12, np.random.default_rng(1), p_blocked=0.6)
    oracle = TableOracle(requirements, report='none')
    runs = blocker_search(obstacles, 'T', oracle, BlockerSearchConfig(max_planner_runs=5))
    assert runs.status == STATUS_BUDGET and runs.budget_hit == BUDGET_RUNS
    assert runs.planner_runs == 5 and runs.sequence == ()
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    assert exact.level == 7 and 1 <= runs.lower_bound <= exact.level  # the bound stays valid
    few = BlockerSearchConfig(max_expansions=1)
    expansions = blocker_search(TOY_OBSTACLES, 'T', TableOracle(TOY_REQUIREMENTS), few)
    assert expansions.budget_hit == BUDGET_EXPANSIONS
    quick = BlockerSearchConfig(time_limit_s=1e-9)
    timed = blocker_search(TOY_OBSTACLES, 'T', TableOracle(TOY_REQUIREMENTS), quick)
    assert timed.budget_hit == BUDGET_TIME and timed.status == STATUS_BUDGET


def test_memo_oracle_passes_reports_through() -> None:
    memo = MemoOracle(TableOracle(TOY_REQUIREMENTS))
    assert memo.sound_blockers
    assert memo.answer((), 'T') == (False, ('O1', 'O2', 'O3', 'O4', 'O5'))
    assert memo.answer((), 'T').blocking_ids and memo.planner_runs == 1
    result = blocker_search(TOY_OBSTACLES, 'T', memo)
    assert len(result.sequence) == TOY_OPTIMAL_LEVEL
    runs = memo.planner_runs
    assert memo.clear_zone_feasible((), 'T') is False  # a table has no drop zone: same answer
    assert memo.planner_runs == runs  # and no second run for it


@pytest.mark.parametrize(
    'field',
    [('max_planner_runs', 0), ('time_limit_s', 0.0), ('max_expansions', -1), ('verify', 'x')],
)
def test_bad_config_is_rejected_with_the_field_name(field) -> None:
    name, value = field
    with pytest.raises(InvalidParameterError, match=name):
        BlockerSearchConfig(**{name: value})


def test_bad_scenes_are_rejected() -> None:
    with pytest.raises(InvalidScenarioError, match='target'):
        blocker_search(('O1', 'T'), 'T', TableOracle({}))
    with pytest.raises(InvalidScenarioError, match='duplicate'):
        blocker_search(('O1', 'O1'), 'T', TableOracle({}))


class _DropZoneOracle:
    """T needs O1 gone; the report for T wrongly names O2. A full drop zone (≥ 3 objects
    relocated) makes every ordinary answer infeasible, as far drop slots do on the real planner;
    ``clear_zone_feasible`` answers with the empty drop zone (monotone)."""

    def __init__(self, clear_zone: bool) -> None:
        self.planner_runs = 0
        if not clear_zone:
            self.clear_zone_feasible = None  # ask_clear then falls back to feasible()

    def _clutter(self, relocated: tuple[str, ...], object_id: str) -> bool:
        return object_id != 'T' or 'O1' in relocated

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        return self.answer(relocated, object_id).feasible

    def answer(self, relocated, object_id):
        from qtree_task_planner.oracle import FeasibilityAnswer

        self.planner_runs += 1
        ok = len(relocated) < 3 and self._clutter(relocated, object_id)
        return FeasibilityAnswer(ok, () if ok else ('O2',))

    def clear_zone_feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        self.planner_runs += 1
        return self._clutter(relocated, object_id)


def test_verification_uses_the_empty_drop_zone() -> None:
    """Before: the verification (T after O1, O3, O4) hit the full drop zone and confirmed the
    wrong report {O2}, so the certified optimum (O1, T) was missed."""
    obstacles = ('O1', 'O2', 'O3', 'O4')
    found = blocker_search(obstacles, 'T', _DropZoneOracle(clear_zone=True))
    assert found.status == 'optimal' and found.sequence == ('O1', 'T')
    assert found.verifications >= 1
    wrong = blocker_search(obstacles, 'T', _DropZoneOracle(clear_zone=False))
    assert wrong.sequence != ('O1', 'T')  # the failure mode the clear-zone query removes


class _OrderEffectOracle:
    """O2 is free at first but infeasible once O1 is gone (reported blocked by O3): an order
    effect no set-based constraint can express. T needs O2 gone."""

    sound_blockers = True

    def __init__(self) -> None:
        self.planner_runs = 0

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        return self.answer(relocated, object_id).feasible

    def answer(self, relocated, object_id):
        from qtree_task_planner.oracle import FeasibilityAnswer

        self.planner_runs += 1
        if object_id == 'O2':
            ok = 'O1' not in relocated or 'O3' in relocated
            return FeasibilityAnswer(ok, () if ok else ('O3',))
        if object_id == 'T':
            ok = 'O2' in relocated
            return FeasibilityAnswer(ok, () if ok else ('O2',))
        return FeasibilityAnswer(True, ())


def test_a_contradicted_constraint_uncertifies_the_result() -> None:
    """Before: 'O2 needs O3 first' was kept as sound although O2 was feasible after nothing."""
    search = BlockerSearch(('O1', 'O2', 'O3'), 'T', _OrderEffectOracle())
    search.query((), 'O2')
    search.query(('O1',), 'O2')  # the order effect
    result = search.run()
    assert result.contradictions == 1 and result.certified is False
    clean = blocker_search(('O1', 'O2', 'O3'), 'T', _OrderEffectOracle())
    assert clean.certified and clean.contradictions == 0 and clean.sequence == ('O2', 'T')


def test_smallest_hitting_set() -> None:
    rank = {o: i for i, o in enumerate(('O1', 'O2', 'O3', 'O4', 'O5'))}
    shared = [frozenset({'O2', 'O1'}), frozenset({'O1', 'O3'}), frozenset({'O4', 'O1'})]
    assert smallest_hitting_set(shared, rank) == {'O1'}
    apart = [frozenset({'O1'}), frozenset({'O2', 'O3'}), frozenset({'O3', 'O4'})]
    assert smallest_hitting_set(apart, rank) == {'O1', 'O3'}
    greedy = smallest_hitting_set(apart, rank, exact_up_to=0)  # the fallback for large sets
    assert all(b & greedy for b in apart) and greedy == {'O1', 'O3'}


class _UnionReportOnly:
    """A TableOracle seen without its per-approach blockers (what the ROS service gives)."""

    def __init__(self, inner: TableOracle) -> None:
        self.inner = inner
        self.sound_blockers = inner.sound_blockers

    @property
    def planner_runs(self) -> int:
        return self.inner.planner_runs

    def answer(self, relocated, object_id):
        return self.inner.answer(relocated, object_id)

    def feasible(self, relocated, object_id) -> bool:
        return self.inner.feasible(relocated, object_id)


@pytest.mark.parametrize('report', ['union', 'fewest'])
def test_per_approach_blockers_narrow_the_constraint_to_a_hitting_set(report) -> None:
    # every approach of T passes O1, and one more object of O2..O6 each; O1 needs O7 gone
    requirements = {'T': [{'O1', f'O{i}'} for i in range(2, 7)], 'O1': [{'O7'}]}
    obstacles = tuple(f'O{i}' for i in range(1, 9))
    narrowed = BlockerSearch(obstacles, 'T', TableOracle(requirements, report=report))
    result = narrowed.run()
    assert narrowed.constraints['T'][0] == {'O1'}  # not the union O1..O6
    plain = blocker_search(
        obstacles, 'T', _UnionReportOnly(TableOracle(requirements, report=report))
    )
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    assert result.certified and len(result.sequence) == len(plain.sequence) == exact.level == 4
    assert _feasible_order(result.sequence, requirements)
    assert result.planner_runs < plain.planner_runs


def test_per_approach_blockers_of_results_and_responses() -> None:
    result = SimpleNamespace(approach_blockers=(('O1',), ('O1', 'O4'), ('O2', 'O1', 'O5')))
    assert approach_blockers_of(result, ('O5',), 'T') == ({'O1'}, {'O1', 'O4'}, {'O1', 'O2'})
    assert approach_blockers_of(result, ('O1',), 'T') is None  # approach 1 clear: no model
    flat = SimpleNamespace(  # a RelocateObject response: ids cut by the counts
        approach_blocking_ids=['O1', 'O1', 'O4', 'O2', 'O1', 'O5'],
        approach_blocker_counts=[1, 2, 3],
    )
    assert approach_blockers_of(flat, (), 'T') == ({'O1'}, {'O1', 'O4'}, {'O1', 'O2', 'O5'})
    broken = SimpleNamespace(approach_blocking_ids=['O1'], approach_blocker_counts=[1, 2])
    assert approach_blockers_of(broken, (), 'T') is None  # counts do not add up
    assert approach_blockers_of(SimpleNamespace(), (), 'T') is None  # no report
    assert approach_blockers_of(SimpleNamespace(approach_blockers=()), (), 'T') is None


def test_planner_oracle_keeps_the_per_approach_blockers_of_each_answer() -> None:
    answer = SimpleNamespace(
        feasible=False,
        from_cache=False,
        planning_time=0.1,
        blocking_ids=('O1', 'O2'),
        blocked_by_immovable=False,
        approach_blockers=(('O1', 'O2'), ('O1', 'O4')),
    )
    still_blocked = SimpleNamespace(feasible=False, planning_time=0.1)
    planner = SimpleNamespace(
        check=lambda obj, relocated: answer,
        plan=lambda obj, relocated, slot_index: still_blocked,  # the verification query
        blockers=None,
    )
    oracle = MotionPlannerOracle(scenario=None, planner=planner)
    assert oracle.approach_blockers((), 'T') is None  # not asked yet
    assert oracle.answer((), 'T') == (False, ('O1', 'O2'))
    assert oracle.approach_blockers((), 'T') == ({'O1', 'O2'}, {'O1', 'O4'})
    search = BlockerSearch(('O1', 'O2', 'O3', 'O4'), 'T', MemoOracle(oracle))
    search.query((), 'T')
    assert search.constraints['T'] == [{'O1'}]  # the verification (all but O1 gone) failed


def test_a_hitting_set_outside_a_one_approach_report_is_verified_and_kept() -> None:
    # 'fewest' names O1, O2 (one approach); T can also go once O4, O5 are gone: that report fails
    # its check, while {O1, O4} meets every approach and passes it
    requirements = {'T': [{'O1', 'O2'}, {'O1', 'O3'}, {'O4', 'O5'}]}
    obstacles = ('O1', 'O2', 'O3', 'O4', 'O5')
    search = BlockerSearch(obstacles, 'T', TableOracle(requirements, report='fewest'))
    result = search.run()
    assert search.constraints['T'][0] == {'O1', 'O4'}
    assert result.certified and len(result.sequence) == 3
    assert _feasible_order(result.sequence, requirements)


class _StandingObjectHelps:
    """Not monotone, like the planner on generate_clutter(50, 0.3, 8): relocating O2 frees T only
    while O3 still stands. Reports name O3, O4 at first, then O4 alone, then O3 (wrong)."""

    sound_blockers = False

    def __init__(self) -> None:
        self.planner_runs = 0

    def answer(self, relocated, object_id):
        self.planner_runs += 1
        done = set(relocated)
        if object_id != 'T' or ('O2' in done and 'O3' not in done):
            return FeasibilityAnswer(True, ())
        report = ('O3', 'O4') if not done else ('O4',) if 'O4' not in done else ('O3',)
        return FeasibilityAnswer(False, report)

    def feasible(self, relocated, object_id) -> bool:
        return self.answer(relocated, object_id).feasible


def test_a_constraint_refuted_by_a_verification_is_weakened_and_the_optimum_found() -> None:
    # T with O3, O4 standing (O1, O2 gone) is feasible; later "only O4 standing" is not: the
    # verified constraint {O4} would hide the optimum (O2, T) and certify (O4, O2, T)
    result = blocker_search(('O1', 'O2', 'O3', 'O4'), 'T', _StandingObjectHelps())
    assert result.sequence == ('O2', 'T')
    assert not result.certified and result.contradictions >= 1  # and says it is a heuristic


def test_mutually_blocked_clutter_is_proven_unsolvable_without_enumerating_it() -> None:
    # nothing can go first: every obstacle needs another one gone (generated clutter where no
    # object is graspable at the start). Branching over the cycles took 131 101 DFS nodes at
    # N = 14 (and hit the 200 000 budget at N = 50); the reachable set proves it at once.
    obstacles = tuple(f'O{i}' for i in range(1, 15))
    requirements = {'T': [{o} for o in obstacles]}
    requirements |= {o: [{p} for p in obstacles if p != o] for o in obstacles}
    result = blocker_search(obstacles, 'T', TableOracle(requirements))
    assert result.status == STATUS_UNSOLVABLE and result.certified
    assert result.planner_runs == 15 and result.expansions < 100


# -- issue #30 item 4: anytime answers, nothing movable, rechecks --


def test_a_budget_returns_the_incumbent_with_its_bound() -> None:
    obstacles, requirements = random_requirements(10, np.random.default_rng(5), p_blocked=0.6)
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    full = blocker_search(obstacles, 'T', TableOracle(requirements, report='none'))
    assert full.status == STATUS_OPTIMAL and len(full.sequence) == exact.level == 5
    assert full.completions == 0 and full.bound == full.lower_bound == exact.level
    assert full.certified and full.bound_certified
    oracle = TableOracle(requirements, report='none')
    config = BlockerSearchConfig(max_planner_runs=full.planner_runs // 2)
    cut = blocker_search(obstacles, 'T', oracle, config)
    assert cut.status == STATUS_BUDGET and cut.budget_hit == BUDGET_RUNS and cut.completions
    assert cut.sequence and _feasible_order(cut.sequence, requirements)  # an incumbent
    assert len(cut.sequence) >= exact.level >= cut.bound == cut.lower_bound >= 1
    assert not cut.certified and cut.bound_certified  # the bound is proven, the length not
    assert oracle.planner_runs == cut.planner_runs <= config.max_planner_runs


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(2, 10),
    report=st.sampled_from(['union', 'fewest', 'none']),
    runs=st.integers(1, 40),
)
def test_a_budgeted_search_returns_nothing_or_a_feasible_sequence_above_its_bound(
    seed, n, report, runs
) -> None:
    obstacles, requirements = random_requirements(n, np.random.default_rng(seed), p_blocked=0.6)
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    oracle = TableOracle(requirements, report=report)
    result = blocker_search(obstacles, 'T', oracle, BlockerSearchConfig(max_planner_runs=runs))
    assert oracle.planner_runs <= runs
    if result.status != STATUS_BUDGET:
        assert result.certified and len(result.sequence) == exact.level
        return
    assert not result.certified and result.bound_certified
    assert result.bound <= exact.level or not exact.solvable  # the bound is sound
    if result.sequence:
        assert _feasible_order(result.sequence, requirements)
        assert len(result.sequence) >= max(exact.level, result.bound)


_STUCK = {  # no obstacle can go first: O1 cannot move, O2 and O3 block each other, O4 needs O1
    'T': [{'O1'}, {'O2', 'O3'}],
    'O1': [],
    'O2': [{'O3'}],
    'O3': [{'O2'}],
    'O4': [{'O1'}],
}


@pytest.mark.parametrize('verify', ['auto', 'always'])
@pytest.mark.parametrize('report', ['union', 'fewest', 'none'])
def test_nothing_movable_costs_no_more_runs_than_the_exact_search(report, verify) -> None:
    """Before: the verifications of 'fewest' (and of 'union' with verify='always') cost 10 and
    8 runs where the exact search stops after 5 (the target and each obstacle after nothing)."""
    obstacles = ('O1', 'O2', 'O3', 'O4')
    exact_oracle = TableOracle(_STUCK)
    assert not solve_exact(obstacles, 'T', exact_oracle).solvable
    oracle = TableOracle(_STUCK, report=report)
    result = blocker_search(obstacles, 'T', oracle, BlockerSearchConfig(verify=verify))
    assert result.status == STATUS_UNSOLVABLE and result.certified
    assert oracle.planner_runs <= exact_oracle.planner_runs == 5


def _stuck_planner() -> MemoOracle:
    """The in-process planner's oracle on a scene where nothing moves (per-approach blockers
    that are not sound, verifications in the empty drop zone)."""
    answer = SimpleNamespace(
        feasible=False,
        from_cache=False,
        planning_time=0.1,
        blocking_ids=('O1', 'O2'),
        blocked_by_immovable=False,
        approach_blockers=(('O1', 'O2'), ('O1', 'O4')),
    )
    planner = SimpleNamespace(
        check=lambda obj, relocated: answer,
        plan=lambda obj, relocated, slot_index: SimpleNamespace(feasible=False),
        blockers=None,
    )
    return MemoOracle(MotionPlannerOracle(scenario=None, planner=planner))


def test_nothing_movable_for_the_planner_costs_no_more_runs_than_the_exact_search() -> None:
    """Before: 6 runs (3 verifications) against the exact search's 5."""
    obstacles = ('O1', 'O2', 'O3', 'O4')
    exact_oracle = _stuck_planner()
    assert not solve_exact(obstacles, 'T', exact_oracle).solvable
    oracle = _stuck_planner()
    result = blocker_search(obstacles, 'T', oracle)
    assert result.status == STATUS_UNSOLVABLE and result.certified and not result.verifications
    assert oracle.planner_runs <= exact_oracle.planner_runs == 5


@settings(max_examples=40, deadline=None, derandomize=True)
@given(data=st.data(), n=st.integers(1, 7), report=st.sampled_from(['union', 'fewest', 'none']))
def test_nothing_movable_never_costs_more_than_the_exact_search(data, n, report) -> None:
    obstacles = tuple(f'O{i}' for i in range(1, n + 1))
    ids = st.sampled_from([*obstacles, 'T'])
    requirements = {}
    for obj in (*obstacles, 'T'):  # every object needs another gone, or cannot move ([])
        others = ids.filter(lambda o, obj=obj: o not in (obj, 'T'))
        sets = st.lists(st.sets(others, min_size=1, max_size=2), max_size=2)
        requirements[obj] = data.draw(sets) if n > 1 else []
    exact_oracle = TableOracle(requirements)
    assert not solve_exact(obstacles, 'T', exact_oracle).solvable
    oracle = TableOracle(requirements, report=report)
    result = blocker_search(obstacles, 'T', oracle)
    assert result.status == STATUS_UNSOLVABLE and result.certified
    assert oracle.planner_runs <= exact_oracle.planner_runs


class _FalseNoOracle:
    """T needs O1 gone; the first answer "O1 after nothing" is a false IK_NOT_CONVERGED "no"
    (blocked by nothing movable); a recheck plans O1. O2 always moves but never helps."""

    sound_blockers = True

    def __init__(self, can_recheck: bool = True) -> None:
        self.planner_runs = 0
        self.rechecked: list[tuple[tuple[str, ...], str]] = []
        if not can_recheck:
            self.recheck = None  # an oracle without rechecks

    def _truth(self, relocated, object_id) -> FeasibilityAnswer:
        ok = object_id != 'T' or 'O1' in relocated
        return FeasibilityAnswer(ok, () if ok else ('O1',))

    def answer(self, relocated, object_id) -> FeasibilityAnswer:
        self.planner_runs += 1
        if object_id == 'O1':
            return FeasibilityAnswer(False, (), REASON_IK_NOT_CONVERGED)
        return self._truth(relocated, object_id)

    def feasible(self, relocated, object_id) -> bool:
        return self.answer(relocated, object_id).feasible

    def recheck(self, relocated, object_id) -> FeasibilityAnswer:
        self.planner_runs += 1
        self.rechecked.append((tuple(relocated), object_id))
        return self._truth(relocated, object_id)


def test_a_false_ik_no_is_rechecked_before_it_proves_the_scene_unsolvable() -> None:
    oracle = _FalseNoOracle()
    result = blocker_search(('O1', 'O2'), 'T', oracle)
    assert result.status == STATUS_OPTIMAL and result.sequence == ('O1', 'T') and result.certified
    assert result.rechecks == 1 and oracle.rechecked == [((), 'O1')]
    assert result.planner_runs == oracle.planner_runs  # the recheck is a run too
    memo = MemoOracle(_FalseNoOracle())  # passed through a memo, which learns the new answer
    assert blocker_search(('O1', 'O2'), 'T', memo).sequence == ('O1', 'T')
    assert memo.feasible((), 'O1') and memo.answer((), 'O1').feasible
    without = blocker_search(('O1', 'O2'), 'T', _FalseNoOracle(can_recheck=False))
    assert without.status == STATUS_UNSOLVABLE and without.rechecks == 0  # as before


def test_only_the_answers_a_certificate_relies_on_are_rechecked() -> None:
    # O1's false "no" is asked first, but T can also go after O2: the optimum (O2, T) and its
    # bound ("T cannot go first") do not rely on O1's answer
    class _Either(_FalseNoOracle):
        def _truth(self, relocated, object_id) -> FeasibilityAnswer:
            ok = object_id != 'T' or bool({'O1', 'O2'} & set(relocated))
            return FeasibilityAnswer(ok, () if ok else ('O1', 'O2'))

    oracle = _Either()
    result = blocker_search(('O1', 'O2'), 'T', oracle)
    assert result.sequence == ('O2', 'T') and result.status == STATUS_OPTIMAL
    assert result.rechecks == 0 and oracle.rechecked == []
    assert MemoOracle(TableOracle({})).can_recheck is False  # a memo offers only inner's


def test_planner_oracle_rechecks_with_more_effort_and_keeps_its_reason() -> None:
    config_module = pytest.importorskip('stpik_motion_planner.config')
    config = config_module.PlannerConfig()
    seen = []
    plans = iter([SimpleNamespace(feasible=True, planning_time=0.5)])
    stpik = SimpleNamespace(config=config)
    cache = SimpleNamespace(entries=[], put=lambda obj, rel, res: cache.entries.append(obj))

    def plan(obj, relocated):
        seen.append((planner.config, stpik.config))
        return next(plans)

    @contextlib.contextmanager
    def configured(effort):  # MotionPlanner.configured: the planner and its STPIK solver
        planner.config = stpik.config = effort
        try:
            yield
        finally:
            planner.config = stpik.config = config

    planner = SimpleNamespace(
        config=config,
        stpik=stpik,
        cache=cache,
        blockers=None,
        plan=plan,
        configured=configured,
        check=lambda obj, relocated: SimpleNamespace(
            feasible=False, reason=REASON_IK_NOT_CONVERGED, blocking_ids=(), planning_time=0.1
        ),
    )
    oracle = MotionPlannerOracle(scenario=None, planner=planner)
    first = oracle.answer((), 'O1')
    assert first == (False, None) and first.reason == REASON_IK_NOT_CONVERGED
    assert oracle.recheck((), 'O1') == (True, ()) and cache.entries == ['O1']
    effort = seen[0][0]
    assert seen[0][1] is effort and planner.config is config and stpik.config is config
    assert effort.ik_restarts == 20 and effort.time_limit_s == 20.0
    assert effort.max_iterations == 24 and effort.rrt_iterations == 4000
    assert recheck_config(effort).ik_restarts == 50  # capped at the top of its range
    assert oracle.planner_runs == 2
