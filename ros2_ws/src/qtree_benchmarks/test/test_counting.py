"""Eq. (7) counts and the difficulty metrics of Sect. 3.2.2."""

import itertools

import pytest
from qtree_benchmarks.task.counting import difficulty, num_target_sequences, num_tree_nodes


@pytest.mark.parametrize(('n_obstacles', 'expected'), [(1, 1), (2, 4), (3, 15), (4, 64), (5, 325)])
def test_eq7_counts(n_obstacles: int, expected: int) -> None:
    assert num_target_sequences(n_obstacles) == expected


@pytest.mark.parametrize('n_obstacles', [1, 2, 3, 4, 5])
def test_eq7_matches_brute_force_enumeration(n_obstacles: int) -> None:
    obstacles = range(n_obstacles)
    brute = sum(1 for k in range(1, n_obstacles + 1) for _ in itertools.permutations(obstacles, k))
    assert num_target_sequences(n_obstacles) == brute


def test_paper_scenario_sizes() -> None:
    # Sect. 4: N_o = 10 and 15 give the 1e-5 % and 1e-11 % optimal shares quoted in the paper.
    assert num_target_sequences(10) == 9_864_100
    assert 1 / num_target_sequences(15) * 100 == pytest.approx(2.8e-11, rel=0.05)


def test_tree_nodes() -> None:
    assert [num_tree_nodes(n) for n in range(4)] == [2, 4, 10, 32]


def test_difficulty_scenario1() -> None:
    optimal, feasible = difficulty(1, 10, 5)
    assert optimal * 100 == pytest.approx(0.31, abs=0.01)  # "0.3 %" in Sect. 4
    assert feasible * 100 == pytest.approx(3.1, abs=0.05)  # "about 3 %"


def test_negative_counts_rejected() -> None:
    with pytest.raises(ValueError, match='n_obstacles'):
        num_target_sequences(-1)
    with pytest.raises(ValueError, match='n_obstacles'):
        num_tree_nodes(-2)
