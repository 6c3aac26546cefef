"""Exact BFS over sets and the counts of feasible sequences."""

import itertools

import pytest
from qtree_task_planner.exact import count_feasible_sequences, solve_exact
from qtree_task_planner.exceptions import SearchLimitExceededError
from qtree_task_planner.oracle import TableOracle
from qtree_task_planner.testing import TOY_OBSTACLES as OBSTACLES
from qtree_task_planner.testing import TOY_REQUIREMENTS, synthetic_scenario


def _brute_force_counts(requirements: dict, obstacles: tuple[str, ...]) -> dict[int, int]:
    """Enumerate every ordered sequence (eq. 7 space) and keep the feasible ones by level."""
    oracle = TableOracle(requirements)
    by_level: dict[int, int] = {}
    for k in range(len(obstacles) + 1):
        for order in itertools.permutations(obstacles, k):
            ok = all(oracle.feasible(order[:i], o) for i, o in enumerate(order))
            if ok and oracle.feasible(order, 'T'):
                by_level[k + 1] = by_level.get(k + 1, 0) + 1
    return by_level


def test_toy_optimum() -> None:
    toy_oracle = TableOracle(TOY_REQUIREMENTS)
    solution = solve_exact(OBSTACLES, 'T', toy_oracle)
    assert solution.level == 4
    assert solution.sequence == ('O2', 'O1', 'O3', 'T')
    assert solution.queries == toy_oracle.planner_runs  # every query is a distinct (set, o)


def test_target_free_is_level_one() -> None:
    solution = solve_exact(OBSTACLES, 'T', TableOracle({}))
    assert solution.sequence == ('T',) and solution.level == 1 and solution.queries == 1


def test_unsolvable_scene() -> None:
    solution = solve_exact(OBSTACLES, 'T', TableOracle({'T': []}))
    assert not solution.solvable and solution.level == 0
    assert solution.sets_explored == 2 ** len(OBSTACLES)  # every set was reachable


def test_counts_match_brute_force() -> None:
    counts = count_feasible_sequences(OBSTACLES, 'T', TableOracle(TOY_REQUIREMENTS))
    assert counts.by_level == _brute_force_counts(TOY_REQUIREMENTS, OBSTACLES)
    assert counts.by_level == {4: 2, 5: 33, 6: 45}
    assert (counts.feasible, counts.optimal) == (80, 2)


def test_search_budget() -> None:
    with pytest.raises(SearchLimitExceededError, match='3'):
        solve_exact(OBSTACLES, 'T', TableOracle({'T': []}), max_sets=3)


@pytest.mark.parametrize(('name', 'level'), [('s1', 4), ('s2', 5), ('s3', 6)])
def test_synthetic_scenarios_have_the_papers_optimal_levels(name: str, level: int) -> None:
    obstacles, requirements = synthetic_scenario(name)
    assert len(obstacles) == {'s1': 5, 's2': 10, 's3': 15}[name]
    assert solve_exact(obstacles, 'T', TableOracle(requirements)).level == level
