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


def _train_level(
    requirements: dict, obstacles: tuple[str, ...], policy: str, seed: int
) -> tuple[int, int]:
    """(learned sequence length, exact optimum level) of one training on a table."""
    exact = solve_exact(obstacles, 'T', TableOracle(requirements))
    result = train(
        (*obstacles, 'T'),
        'T',
        TableOracle(requirements),
        TrainingConfig(policy=policy, seed=seed, steady_episodes=100),
    )
    return len(result.sequence), exact.level


@SETTINGS
@given(
    table_seed=st.integers(0, 10_000),
    n_obstacles=st.integers(2, 6),
    seed=st.integers(0, 2**31),
)
def test_epsilon_greedy_set_finds_the_exact_optimum_level(
    table_seed: int, n_obstacles: int, seed: int
) -> None:
    obstacles, requirements = random_requirements(n_obstacles, np.random.default_rng(table_seed))
    learned, exact = _train_level(requirements, tuple(obstacles), 'H-EG-SET', seed)
    assert learned == exact


def test_paper_epsilon_greedy_can_settle_one_level_long() -> None:
    """The paper's H-εG is a heuristic: on this table it settles on a feasible sequence with an
    unneeded free object first (level 5, optimum 4), where H-εG-SET finds the optimum (#26:
    hypothesis drew this example and the old property, optimum for H-εG too, failed)."""
    obstacles, requirements = random_requirements(6, np.random.default_rng(53))
    assert _train_level(requirements, tuple(obstacles), 'H-EG', 3359447) == (5, 4)
    assert _train_level(requirements, tuple(obstacles), 'H-EG-SET', 3359447) == (4, 4)


def test_paper_epsilon_greedy_is_optimal_on_most_random_tables() -> None:
    """30 fixed random tables: H-εG reached the optimum on 30 (300 of 300 random draws too);
    at least 27 asserted, so one heuristic miss like the one above does not fail it."""
    rng = np.random.default_rng(2026)
    optimal = 0
    for _ in range(30):
        table_seed, n_obstacles = int(rng.integers(0, 10_000)), int(rng.integers(2, 7))
        obstacles, requirements = random_requirements(
            n_obstacles, np.random.default_rng(table_seed)
        )
        learned, exact = _train_level(
            requirements, tuple(obstacles), 'H-EG', int(rng.integers(0, 2**31))
        )
        optimal += learned == exact
    assert optimal >= 27


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
