"""Property tests on random feasibility tables (hypothesis)."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from qtree_task_planner.exact import count_feasible_sequences, solve_exact
from qtree_task_planner.oracle import TableOracle
from qtree_task_planner.testing import random_requirements
from qtree_task_planner.training import TrainingConfig, train

SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _is_feasible(oracle: TableOracle, sequence: tuple[str, ...]) -> bool:
    return all(oracle.feasible(sequence[:i], obj) for i, obj in enumerate(sequence))


@SETTINGS
@given(
    table_seed=st.integers(0, 10_000),
    n_obstacles=st.integers(1, 5),
    policy=st.sampled_from(['LRND', 'H-LRND', 'H-EG', 'H-EG-SET']),
    seed=st.integers(0, 2**31),
)
def test_extracted_sequence_is_feasible_and_never_shorter_than_exact(
    table_seed: int, n_obstacles: int, policy: str, seed: int
) -> None:
    obstacles, requirements = random_requirements(n_obstacles, np.random.default_rng(table_seed))
    oracle = TableOracle(requirements)
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    result = train(
        (*obstacles, 'T'), 'T', oracle, TrainingConfig(policy=policy, seed=seed, max_episodes=1500)
    )
    if result.sequence:
        assert result.sequence[-1] == 'T' and len(set(result.sequence)) == len(result.sequence)
        assert _is_feasible(TableOracle(requirements), result.sequence)
        assert len(result.sequence) >= exact.level > 0
    else:
        assert not exact.solvable or result.stop_reason == 'max_episodes'
    assert result.mp_calls == result.history[-1].edges
    assert result.planner_runs <= result.mp_calls


@SETTINGS
@given(
    table_seed=st.integers(0, 10_000),
    n_obstacles=st.integers(2, 6),
    policy=st.sampled_from(['H-EG', 'H-EG-SET']),
    seed=st.integers(0, 2**31),
)
def test_epsilon_greedy_finds_the_exact_optimum_level(
    table_seed: int, n_obstacles: int, policy: str, seed: int
) -> None:
    obstacles, requirements = random_requirements(n_obstacles, np.random.default_rng(table_seed))
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    result = train(
        (*obstacles, 'T'),
        'T',
        TableOracle(requirements),
        TrainingConfig(policy=policy, seed=seed, steady_episodes=100),
    )
    assert len(result.sequence) == exact.level


@SETTINGS
@given(table_seed=st.integers(0, 10_000), n_obstacles=st.integers(1, 5))
def test_exact_level_equals_shortest_counted_level(table_seed: int, n_obstacles: int) -> None:
    obstacles, requirements = random_requirements(n_obstacles, np.random.default_rng(table_seed))
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    counts = count_feasible_sequences(obstacles, 'T', TableOracle(requirements))
    assert exact.level == (min(counts.by_level) if counts.by_level else 0)
    if exact.solvable:
        assert _is_feasible(TableOracle(requirements), exact.sequence)
        assert counts.optimal >= 1
