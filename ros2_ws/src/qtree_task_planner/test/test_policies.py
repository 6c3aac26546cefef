"""Selection rules of Sect. 3.2.1 and the eq. (9) schedule."""

from collections import Counter

import numpy as np
import pytest
from qtree_task_planner.exceptions import InvalidParameterError, UnknownPolicyError
from qtree_task_planner.policies import available_actions, epsilon_schedule, make_policy
from qtree_task_planner.tree import QTree

MOVABLE = ('O1', 'O2', 'O3', 'T')


def _tree() -> QTree:
    """Root with O1 feasible (Q=0), O2 failed (-1); node (O1) with T failed."""
    tree = QTree('T', alpha=0.5, gamma=0.9)
    tree.add_edge((), 'O1', 0.0)
    tree.add_edge((), 'O2', -1.0)
    tree.add_edge(('O1',), 'T', -1.0)
    return tree


def _counts(policy_name: str, tree: QTree, key: tuple[str, ...], n: int = 2000, **kw) -> Counter:
    policy = make_policy(policy_name, MOVABLE, 'T', **kw)
    rng = np.random.default_rng(3)
    return Counter(policy.select(tree, key, rng, kw.get('max_episodes', 5000)) for _ in range(n))


def test_available_actions_skip_relocated_and_failed() -> None:
    tree = _tree()
    assert available_actions(tree, (), MOVABLE) == ['O1', 'O3', 'T']
    assert available_actions(tree, ('O1',), MOVABLE) == ['O2', 'O3']


def test_lrnd_uniform_over_available() -> None:
    counts = _counts('LRND', _tree(), ())
    assert set(counts) == {'O1', 'O3', 'T'}
    assert all(abs(c / 2000 - 1 / 3) < 0.05 for c in counts.values())


def test_hlrnd_tries_target_first_then_uniform() -> None:
    tree = _tree()
    assert _counts('H-LRND', tree, ()) == Counter({'T': 2000})  # T untried at the root
    tree.add_edge((), 'T', -1.0)
    counts = _counts('H-LRND', tree, ())
    assert set(counts) == {'O1', 'O3'}  # tried O1 (reward 0) or untried O3; never failed O2/T
    assert abs(counts['O1'] / 2000 - 0.5) < 0.05


def test_heg_exploits_max_q_when_epsilon_is_small() -> None:
    tree = _tree()
    tree.add_edge((), 'T', -1.0)
    tree.add_edge((), 'O3', 0.0)
    tree.add_edge(('O3',), 'T', 100.0)
    tree.update(tree.node(()).children['O3'])  # Q(root, O3) = 45
    counts = _counts('H-EG', tree, (), epsilon0=1e-4, epsilon_min=1e-4)
    assert counts == Counter({'O3': 2000})


def test_heg_explores_with_heuristic_when_epsilon_is_one() -> None:
    counts = _counts('H-EG', _tree(), (), epsilon0=1.0, epsilon_min=1.0)
    assert counts == Counter({'T': 2000})  # the heuristic's target-first rule


def test_heg_exploit_breaks_ties_randomly() -> None:
    tree = _tree()
    tree.add_edge((), 'T', -1.0)
    counts = _counts('H-EG', tree, (), epsilon0=1e-4, epsilon_min=1e-4)
    assert set(counts) == {'O1', 'O3'}  # Q(O1)=0 and untried O3 counts as 0


def test_rnd_ignores_failures() -> None:
    counts = _counts('RND', _tree(), ())
    assert set(counts) == {'O1', 'O2', 'O3', 'T'}


def test_dead_end_returns_none() -> None:
    tree = QTree('T', alpha=0.5, gamma=0.9)
    tree.add_edge((), 'O1', -1.0)
    tree.add_edge((), 'T', -1.0)
    policy = make_policy('H-EG', ('O1', 'T'), 'T')
    assert policy.select(tree, (), np.random.default_rng(0), 1) is None


def test_epsilon_schedule_eq9() -> None:
    assert epsilon_schedule(1, 1.0, 1e-4, 5000) == 1.0
    assert epsilon_schedule(5000, 1.0, 1e-4, 5000) == pytest.approx(1e-4)
    assert epsilon_schedule(2500.5, 1.0, 1e-4, 5000) == pytest.approx(1e-2)  # geometric midpoint
    assert epsilon_schedule(7, 0.5, 0.1, 1) == 0.5
    assert make_policy('LRND', MOVABLE, 'T').epsilon(10) == 1.0


def test_policy_names_and_validation() -> None:
    assert make_policy('h-εg', MOVABLE, 'T').name == 'H-EG'
    assert make_policy('H-EG-SET', MOVABLE, 'T').share_sets
    with pytest.raises(UnknownPolicyError, match='policy'):
        make_policy('GREEDY', MOVABLE, 'T')
    with pytest.raises(InvalidParameterError, match='epsilon_min'):
        make_policy('H-EG', MOVABLE, 'T', epsilon0=0.1, epsilon_min=0.5)
    with pytest.raises(InvalidParameterError, match='epsilon0'):
        make_policy('H-EG', MOVABLE, 'T', epsilon0=0.0)


def test_positive_q_rule_prefers_untried_and_positive_edges_with_a_fallback() -> None:
    """H-LRND, reading 'positive-q': among tried candidates only Q > 0 edges qualify."""
    import numpy as np
    from qtree_task_planner.policies import make_policy
    from qtree_task_planner.tree import QTree

    tree = QTree('T', 0.5, 0.9)
    tree.add_edge((), 'T', -1.0)
    tree.add_edge((), 'A', 0.0)
    edge_b, _ = tree.add_edge((), 'B', 0.0)
    movable = ('A', 'B', 'C', 'T')
    positive = make_policy('H-LRND', movable, 'T', hlrnd_rule='positive-q')
    plain = make_policy('H-LRND', movable, 'T')
    rng = np.random.default_rng(0)
    assert {positive.select(tree, (), rng, 1) for _ in range(50)} == {'C'}  # the untried one
    assert {plain.select(tree, (), rng, 1) for _ in range(50)} == {'A', 'B', 'C'}
    tree.add_edge((), 'C', 0.0)  # every candidate tried, none positive: all qualify
    assert {positive.select(tree, (), rng, 1) for _ in range(50)} == {'A', 'B', 'C'}
    edge_b.q = 45.0
    assert {positive.select(tree, (), rng, 1) for _ in range(50)} == {'B'}


def test_episode_coin_is_drawn_once_per_episode() -> None:
    import numpy as np
    from qtree_task_planner.policies import make_policy

    step = make_policy('H-EG', ('A', 'T'), 'T')
    episode = make_policy('H-EG', ('A', 'T'), 'T', epsilon_coin='episode')
    rng = np.random.default_rng(0)
    assert step.episode_coin(rng, 1) is None
    state = rng.bit_generator.state
    assert episode.episode_coin(rng, 1) is True  # eps(1) = 1: always explore
    assert rng.bit_generator.state != state
    late = make_policy('H-EG', ('A', 'T'), 'T', epsilon_coin='episode', max_episodes=2)
    assert late.episode_coin(rng, 2) is False or late.epsilon(2) > 0.0
