"""Issue #14, item 5: the incremental H-EG-SET bookkeeping gives the same trainings as before.

The reference below is the pre-#14 code kept verbatim: V(s) and the untried value recomputed by
recursion on every call, and ``best_known_sequence`` re-sorting every node after every episode.
A training with the reference and one with the incremental code must agree float for float on
every episode's statistics and on every final Q value, for several seeds and scenes.
"""

from __future__ import annotations

import numpy as np
import pytest
from qtree_task_planner import training
from qtree_task_planner.extraction import best_known_sequence
from qtree_task_planner.oracle import TableOracle
from qtree_task_planner.rewards import REWARD_TARGET
from qtree_task_planner.testing import (
    TOY_OBSTACLES,
    TOY_REQUIREMENTS,
    decoy_requirements,
    random_requirements,
    synthetic_scenario,
)
from qtree_task_planner.training import QTreeTrainer, TrainingConfig
from qtree_task_planner.tree import Edge, NodeKey, QTree


class ReferenceQTree(QTree):
    """The Q-Tree with the old, unmemoised V(s) (pre-#14 ``tree.py``)."""

    def value(self, key: NodeKey) -> float:
        node = self._nodes[key]
        best = max((edge.q for edge in node.children.values()), default=None)
        if self.optimistic_over is not None and not node.terminal:
            for action in self.optimistic_over:
                if action not in node.children and action not in node.sequence:
                    bound = self.untried_value(key, action)
                    best = bound if best is None else max(best, bound)
        return 0.0 if best is None else best

    def untried_value(self, key: NodeKey, action: str) -> float:
        if self.optimistic_over is None:
            return 0.0
        if action == self.target_id:
            return REWARD_TARGET
        child = self.key_of((*self._nodes[key].sequence, action))
        if child in self._nodes:
            return self.gamma * self.value(child)
        return self.gamma * REWARD_TARGET


def reference_best_known_sequence(tree: QTree) -> tuple[str, ...]:
    """The old ``best_known_sequence``: a full deepest-first pass over every node."""
    gamma = tree.gamma
    value: dict[NodeKey, float] = {}
    choice: dict[NodeKey, Edge] = {}
    for node in sorted(tree.nodes(), key=lambda n: n.depth, reverse=True):
        best: Edge | None = None
        best_value = 0.0
        for edge in node.children.values():
            if edge.feasible and edge.action != tree.target_id:
                q = edge.reward + gamma * value.get(edge.child, 0.0)
            else:
                q = edge.reward
            if best is None or q > best_value:
                best, best_value = edge, q
        value[node.key] = best_value
        if best is not None:
            choice[node.key] = best
    sequence: list[str] = []
    key: NodeKey = ()
    while key in choice:
        edge = choice[key]
        sequence.append(edge.action)
        if edge.action == tree.target_id:
            return tuple(sequence) if edge.feasible else ()
        if not edge.feasible:
            return ()
        key = edge.child
    return ()


def _scene(name: str) -> tuple[tuple[str, ...], dict]:
    if name == 'toy':
        return TOY_OBSTACLES, TOY_REQUIREMENTS
    if name == 'decoy':
        return decoy_requirements(3, 6)
    if name.startswith('random'):
        return random_requirements(8, np.random.default_rng(int(name[6:])), p_blocked=0.6)
    return synthetic_scenario(name)


def _run(scene: str, policy: str, seed: int, reference: bool, monkeypatch) -> tuple:
    obstacles, requirements = _scene(scene)
    movable = (*obstacles, 'T')
    config = TrainingConfig(policy=policy, seed=seed, max_episodes=1500)
    trainer = QTreeTrainer(movable, 'T', TableOracle(requirements), config)
    if reference:
        old = trainer.tree
        trainer.tree = ReferenceQTree(
            'T',
            old.alpha,
            old.gamma,
            share_sets=old.share_sets,
            optimistic_over=old.optimistic_over,
        )
        monkeypatch.setattr(training, 'best_known_sequence', reference_best_known_sequence)
    else:
        monkeypatch.setattr(training, 'best_known_sequence', best_known_sequence)
    result = trainer.run()
    edges = [(e.parent, e.action, e.child, e.reward, e.q, e.visits) for e in trainer.tree.edges()]
    return result, edges


@pytest.mark.parametrize('scene', ['toy', 'decoy', 's1', 'random1', 'random2'])
@pytest.mark.parametrize('seed', [0, 1, 2])
def test_incremental_bookkeeping_gives_identical_trainings(scene, seed, monkeypatch) -> None:
    old, old_edges = _run(scene, 'H-EG-SET', seed, True, monkeypatch)
    new, new_edges = _run(scene, 'H-EG-SET', seed, False, monkeypatch)
    assert new.history == old.history  # every episode: sequence, q_bar, best sequence, ...
    assert (new.sequence, new.episodes, new.mp_calls, new.stop_reason) == (
        old.sequence,
        old.episodes,
        old.mp_calls,
        old.stop_reason,
    )
    assert new_edges == old_edges  # every Q value, float for float
    assert any(s.best_sequence for s in new.history)  # the comparison is not vacuous


@pytest.mark.parametrize('policy', ['H-EG', 'H-EG-SET-PLAIN'])
def test_non_optimistic_policies_are_unchanged(policy, monkeypatch) -> None:
    old, old_edges = _run('toy', policy, 3, True, monkeypatch)
    new, new_edges = _run('toy', policy, 3, False, monkeypatch)
    assert new.history == old.history and new_edges == old_edges


def test_known_values_follow_new_edges_through_shared_nodes() -> None:
    movable = ('O1', 'O2', 'T')
    tree = QTree('T', 0.5, 0.9, share_sets=True, optimistic_over=movable)
    tree.add_edge((), 'O1', 0.0)
    tree.add_edge((), 'O2', 0.0)
    assert best_known_sequence(tree) == () and tree.known_value(()) == 0.0
    tree.add_edge(('O2',), 'O1', 0.0)  # reaches the shared node ('O1', 'O2')
    tree.add_edge(('O1', 'O2'), 'T', REWARD_TARGET)  # its value reaches both parents
    assert tree.known_value(('O1',)) == 0.0  # O1 -> O2 was never tried
    assert tree.known_value(('O2',)) == pytest.approx(90.0)
    assert best_known_sequence(tree) == ('O2', 'O1', 'T')
    assert best_known_sequence(tree) == reference_best_known_sequence(tree)
    tree.add_edge(('O1',), 'T', REWARD_TARGET)
    assert best_known_sequence(tree) == ('O1', 'T') == reference_best_known_sequence(tree)
