"""Eq. (19) extraction, eq. (17)/(18) steady-state values on hand-built trees."""

import pytest
from qtree_task_planner.extraction import (
    best_known_sequence,
    extract_sequence,
    greedy_path,
    path_values_at_steady_state,
    steady_state_root_q,
)
from qtree_task_planner.tree import QTree


def _chain(tree: QTree, sequence: tuple[str, ...]) -> None:
    """Add the edges of a feasible sequence (obstacles reward 0, target reward 100)."""
    for i, action in enumerate(sequence):
        parent = tree.key_of(sequence[:i])
        if action not in tree.node(parent).children:
            tree.add_edge(parent, action, 100.0 if action == tree.target_id else 0.0)


def _sweep_until_steady(tree: QTree, paths: list[tuple[str, ...]], sweeps: int = 200) -> None:
    """Revisit every edge of the paths, deepest first, like many converged episodes."""
    for _ in range(sweeps):
        for path in paths:
            for i in range(len(path)):
                tree.update(tree.node(tree.key_of(path[:i])).children[path[i]])


def test_steady_state_weights_are_gamma_power_times_reward() -> None:
    # optimal path at level m = 3 (two obstacles then T): root edge -> gamma^2 * 100 (eq. 17)
    tree = QTree('T', alpha=0.5, gamma=0.9)
    path = ('O1', 'O2', 'T')
    _chain(tree, path)
    _sweep_until_steady(tree, [path])
    values = [e.q for e in greedy_path(tree)]
    assert values == pytest.approx([81.0, 90.0, 100.0], abs=1e-6)
    assert values == pytest.approx(path_values_at_steady_state(3, 0.9), abs=1e-6)
    assert steady_state_root_q(3, 0.9) == pytest.approx(81.0)


def test_extraction_prefers_optimal_over_suboptimal_branch() -> None:
    # optimal (O3, T) at level 2 vs sub-optimal (O1, O2, T) at level 3 (eq. 18)
    tree = QTree('T', alpha=0.5, gamma=0.9)
    optimal, suboptimal = ('O3', 'T'), ('O1', 'O2', 'T')
    _chain(tree, suboptimal)  # the sub-optimal branch is created first (wins ties)
    _chain(tree, optimal)
    tree.add_edge((), 'T', -1.0)
    _sweep_until_steady(tree, [suboptimal, optimal])
    root = tree.node(()).children
    assert root['O3'].q == pytest.approx(90.0) and root['O1'].q == pytest.approx(81.0)
    assert root['O3'].q > root['O1'].q  # eq. (18)
    assert extract_sequence(tree) == optimal


def test_extraction_empty_without_a_reached_target() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    assert extract_sequence(tree) == ()
    tree.add_edge((), 'O1', 0.0)
    tree.add_edge((), 'T', -1.0)
    tree.add_edge(('O1',), 'T', -1.0)
    assert extract_sequence(tree) == ()


def test_extraction_on_a_set_shared_tree() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9, share_sets=True)
    path = ('B', 'A', 'T')
    _chain(tree, path)
    _sweep_until_steady(tree, [path])
    assert extract_sequence(tree) == path


def test_level_must_be_positive() -> None:
    with pytest.raises(ValueError, match='level'):
        steady_state_root_q(0, 0.9)


def test_best_known_sequence_ignores_optimism_and_matches_the_sweep() -> None:
    movable = ('O1', 'O2', 'O3', 'T')
    tree = QTree('T', alpha=0.5, gamma=0.9, share_sets=True, optimistic_over=movable)
    _chain(tree, ('O1', 'O2', 'T'))
    _chain(tree, ('O3', 'T'))
    tree.add_edge((), 'T', -1.0)
    tree.add_edge(('O1', 'O2'), 'O3', 0.0)  # optimistic edge into an unexplored node
    assert best_known_sequence(tree) == ('O3', 'T')
    before = [e.q for e in tree.edges()]
    best_known_sequence(tree)
    assert [e.q for e in tree.edges()] == before  # read-only
    tree.sweep()
    assert extract_sequence(tree) == ('O3', 'T')
    assert best_known_sequence(QTree('T', 0.5, 0.9)) == ()


def test_extract_falls_back_to_the_best_known_sequence_when_eq19_finds_none() -> None:
    from qtree_task_planner.extraction import extract, path_of

    tree = QTree('T', 0.5, 0.9)
    tree.add_edge((), 'O2', 0.0)  # first root edge: greedy ties go here
    tree.add_edge(('O2',), 'T', -1.0)  # ... and end in a failed target
    tree.add_edge((), 'O1', 0.0)
    tree.add_edge(('O1',), 'O3', 0.0)
    tree.add_edge(('O1', 'O3'), 'T', 100.0)
    tree.add_edge(('O1',), 'T', 100.0)
    assert extract_sequence(tree) == ()
    assert extract(tree) == (('O1', 'T'), 'best-known-fallback')
    assert [e.action for e in path_of(tree, ('O1', 'T'))] == ['O1', 'T']
    tree.node(()).children['O1'].q = 81.0  # values propagated: eq. (19) finds it
    assert extract(tree) == (('O1', 'T'), 'eq19')
    empty = QTree('T', 0.5, 0.9)
    empty.add_edge((), 'T', -1.0)
    assert extract(empty) == ((), 'none')
