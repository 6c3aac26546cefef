"""Q-Tree structure and the eq. (5) update, checked by hand."""

import pytest
from qtree_task_planner.tree import QTree


def test_new_edge_is_initialised_to_its_reward() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    edge, created = tree.add_edge((), 'O1', -1.0)
    assert created and edge.q == -1.0 and edge.child == ('O1',)
    target, _ = tree.add_edge((), 'T', 100.0)
    assert target.q == 100.0
    assert tree.num_edges == 2 and tree.num_nodes == 3
    assert tree.q_bar == 101.0  # eq. (10)


def test_hand_computed_eq5_step() -> None:
    # root --O1 (r=0, Q=0)--> (O1) --T (r=100, Q=100)--> (O1, T); alpha=0.5, gamma=0.9.
    tree = QTree('T', alpha=0.5, gamma=0.9)
    first, _ = tree.add_edge((), 'O1', 0.0)
    tree.add_edge(('O1',), 'T', 100.0)
    delta = tree.update(first)
    # Q <- 0 + 0.5 * (0 + 0.9 * 100 - 0) = 45
    assert delta == pytest.approx(45.0)
    assert first.q == pytest.approx(45.0)
    # second visit: 45 + 0.5 * (90 - 45) = 67.5; eq. (12) form: 0.5*45 + 0 + 0.5*0.9*100
    tree.update(first)
    assert first.q == pytest.approx(67.5)
    assert first.visits == 3
    assert tree.q_bar == pytest.approx(167.5)


def test_eq5_on_edge_to_leaf_uses_zero_max() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    edge, _ = tree.add_edge((), 'O1', 0.0)
    assert tree.update(edge) == 0.0
    failed, _ = tree.add_edge((), 'O2', -1.0)
    tree.update(failed)
    assert failed.q == pytest.approx(-1.0)  # -1 + 0.5 * (-1 + 0 - (-1))


def test_terminal_nodes() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    tree.add_edge((), 'O1', 0.0)
    tree.add_edge((), 'O2', -1.0)
    tree.add_edge((), 'T', -1.0)
    tree.add_edge(('O1',), 'T', 100.0)
    assert not tree.node(('O1',)).terminal
    assert tree.node(('O2',)).terminal  # infeasible obstacle
    assert tree.node(('T',)).terminal  # target tried, infeasible
    assert tree.node(('O1', 'T')).terminal  # target tried, feasible
    assert tree.failed_actions(()) == {'O2', 'T'}
    with pytest.raises(ValueError, match='terminal'):
        tree.add_edge(('O2',), 'O1', 0.0)


def test_add_edge_rejects_duplicates_and_relocated_objects() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    tree.add_edge((), 'O1', 0.0)
    with pytest.raises(ValueError, match='exists'):
        tree.add_edge((), 'O1', 0.0)
    with pytest.raises(ValueError, match='already relocated'):
        tree.add_edge(('O1',), 'O1', 0.0)


def test_set_sharing_merges_permutations_but_not_failures() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9, share_sets=True)
    tree.add_edge((), 'A', 0.0)
    tree.add_edge((), 'B', 0.0)
    ab, created_ab = tree.add_edge(('A',), 'B', 0.0)
    ba, created_ba = tree.add_edge(('B',), 'A', 0.0)
    assert created_ab and not created_ba
    assert ab.child == ba.child == ('A', 'B')
    # a failure from {A} must not be merged with the feasible node {A, C} reached from {C}
    failed, _ = tree.add_edge(('A',), 'C', -1.0)
    tree.add_edge((), 'C', 0.0)
    feasible, _ = tree.add_edge(('C',), 'A', 0.0)
    assert failed.child != feasible.child
    assert tree.node(failed.child).terminal and not tree.node(feasible.child).terminal


def test_q_bar_incremental_equals_recomputed() -> None:
    tree = QTree('T', alpha=0.3, gamma=0.7)
    e1, _ = tree.add_edge((), 'O1', 0.0)
    tree.add_edge(('O1',), 'T', 100.0)
    tree.add_edge((), 'O2', -1.0)
    for _ in range(7):
        tree.update(e1)
    incremental = tree.q_bar
    assert tree.recompute_q_bar() == pytest.approx(incremental, abs=1e-9)


def test_optimistic_values_bound_untried_actions() -> None:
    movable = ('O1', 'O2', 'T')
    tree = QTree('T', alpha=0.5, gamma=0.9, share_sets=True, optimistic_over=movable)
    assert tree.value(()) == 100.0  # the target is untried at the root
    tree.add_edge((), 'T', -1.0)
    assert tree.value(()) == pytest.approx(90.0)  # an untried obstacle, then the target
    edge, _ = tree.add_edge((), 'O1', 0.0)
    assert edge.q == pytest.approx(90.0)  # new obstacle edge: 0 + gamma * V(child) = 0.9 * 100
    tree.add_edge(('O1',), 'T', -1.0)
    tree.update(edge)  # V(O1) = 0.9 * 100 (O2 untried) -> Q = 90 + 0.5 (81 - 90)
    assert edge.q == pytest.approx(85.5)
    # the transposition {O1, O2} is valued through the shared child once it exists
    tree.add_edge(('O1',), 'O2', 0.0)
    tree.add_edge(('O1', 'O2'), 'T', -1.0)
    assert tree.untried_value(('O2',) if ('O2',) in tree else (), 'O2') == pytest.approx(90.0)
    assert tree.value(('O1', 'O2')) == -1.0  # every action tried: no optimism left


def test_without_optimism_untried_actions_count_zero() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    assert tree.untried_value((), 'T') == 0.0 and tree.value(()) == 0.0
