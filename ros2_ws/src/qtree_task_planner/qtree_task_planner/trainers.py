"""Every task planner the RetrieveTarget goal can name: the Q-Tree policies and BLOCKER-SEARCH.

:func:`make_trainer` gives the ``task_planner`` node one object with the
:class:`~qtree_task_planner.training.QTreeTrainer` surface (``run(callback)``, ``result()``,
``tree``, ``episode``, ``policy.name``) whatever the planner. For BLOCKER-SEARCH (ours,
:mod:`qtree_task_planner.blocker_search`) an "episode" is one tested candidate set, the goal's
``max_episodes`` is the budget of real planner runs, ``converged`` means the optimum was
certified, and the tree holds the tested orders (set-shared, rewards of eq. 8, Q = reward).
"""

from __future__ import annotations

from types import SimpleNamespace

from qtree_task_planner.blocker_search import (
    STATUS_OPTIMAL,
    BlockerSearch,
    BlockerSearchConfig,
    BlockerSearchResult,
)
from qtree_task_planner.exceptions import UnknownPolicyError
from qtree_task_planner.oracle import FeasibilityOracle
from qtree_task_planner.policies import POLICY_NAMES, canonical_policy_name
from qtree_task_planner.rewards import reward
from qtree_task_planner.training import (
    STOP_CANCELLED,
    EpisodeCallback,
    EpisodeStats,
    QTreeTrainer,
    TrainerBase,
    TrainingConfig,
    TrainingResult,
)
from qtree_task_planner.tree import QTree

BLOCKER_SEARCH = 'BLOCKER-SEARCH'
PLANNER_NAMES = (*POLICY_NAMES, BLOCKER_SEARCH)
DEFAULT_TIME_LIMIT_S = 600.0  # BLOCKER-SEARCH wall-time cap when the config sets none [s]


def canonical_planner_name(name: str) -> str:
    """Canonical spelling of a Q-Tree policy or of ``BLOCKER-SEARCH``.

    Raises:
        UnknownPolicyError: not one of :data:`PLANNER_NAMES`.
    """
    if str(name).strip().upper() == BLOCKER_SEARCH:
        return BLOCKER_SEARCH
    try:
        return canonical_policy_name(name)
    except UnknownPolicyError:
        raise UnknownPolicyError(name, PLANNER_NAMES) from None


class BlockerSearchTrainer(TrainerBase):
    """BLOCKER-SEARCH behind the trainer surface of :class:`QTreeTrainer`.

    Args:
        movable_ids: obstacles then the target.
        target_id: the target.
        oracle: feasibility oracle (blocker reports read when it has them).
        config: ``max_episodes`` = planner-run budget, ``time_limit_s`` = wall-time cap.
    """

    def _build(self, movable_ids: tuple[str, ...], target_id: str) -> None:
        """The tree of tested orders and the search (see the class)."""
        config, oracle = self.config, self.oracle
        self.policy = SimpleNamespace(name=BLOCKER_SEARCH, learns=True)
        self.tree = QTree(target_id, config.alpha, config.gamma, share_sets=True)
        self.search_result: BlockerSearchResult | None = None
        obstacles = tuple(o for o in movable_ids if o != target_id)
        budget = BlockerSearchConfig(
            max_planner_runs=config.max_episodes,
            time_limit_s=config.time_limit_s or DEFAULT_TIME_LIMIT_S,
        )
        self.search = BlockerSearch(obstacles, target_id, oracle, budget, self._on_candidate)
        self._callback: EpisodeCallback | None = None
        self._best: tuple[str, ...] = ()

    def _on_candidate(self, walked: tuple[str, ...], reached: bool) -> bool:
        new_edges = 0
        key = self.tree.root.key
        for i, obj in enumerate(walked):
            node = self.tree.node(key)
            if node.terminal:
                break
            edge = node.children.get(obj)
            if edge is None:
                answer = self.search.answers.get((frozenset(walked[:i]), obj))
                feasible = answer is not None and answer.feasible
                edge, _ = self.tree.add_edge(key, obj, reward(obj, self.tree.target_id, feasible))
                new_edges += 1
            if not edge.feasible:
                break
            key = edge.child
        if reached:
            self._best = walked
        stats = EpisodeStats(
            episode=self.episode + 1,
            nodes=self.tree.num_nodes,
            edges=self.tree.num_edges,
            mp_calls=self.search.queries,
            planner_runs=self.search.oracle.planner_runs - self.search._runs0,
            q_bar=self.tree.q_bar,
            epsilon=0.0,
            sequence=walked,
            reached_target=reached,
            new_edges=new_edges,
            best_sequence=self._best,
        )
        self.history.append(stats)
        return self._callback is None or self._callback(stats) is not False

    def run(self, callback: EpisodeCallback | None = None) -> TrainingResult:
        """Run the search (``callback`` after each candidate; False cancels).

        Raises:
            OracleUnavailableError: the oracle gave no answer; :meth:`result` has the partial
                statistics.
        """
        self._callback = callback
        self.search_result = self.search.run()
        hit = self.search_result.budget_hit
        return self.result(STOP_CANCELLED if hit == 'cancelled' else self._stop_reason())

    def _stop_reason(self) -> str:
        found = self.search_result
        return found.budget_hit or found.status if found is not None else 'not_started'

    def result(self, stop_reason: str) -> TrainingResult:
        """The result so far (also after an :class:`OracleUnavailableError`)."""
        found = self.search_result
        optimal = found is not None and found.status == STATUS_OPTIMAL
        sequence = found.sequence if found is not None else ()
        return TrainingResult(
            policy=BLOCKER_SEARCH,
            sequence=sequence,
            episodes=self.episode,
            mp_calls=self.search.queries,
            planner_runs=self.oracle.planner_runs - self.search._runs0,
            converged=found is not None and optimal and found.certified,
            stop_reason=stop_reason,
            first_optimal_episode=self.episode if optimal else -1,
            optimal_level=len(sequence),
            wall_time_s=found.wall_time_s if found is not None else 0.0,
            history=self.history,
        )


def make_trainer(
    movable_ids: tuple[str, ...],
    target_id: str,
    oracle: FeasibilityOracle,
    config: TrainingConfig,
) -> QTreeTrainer | BlockerSearchTrainer:
    """The trainer of ``config.policy``: a Q-Tree policy or BLOCKER-SEARCH."""
    if canonical_planner_name(config.policy) == BLOCKER_SEARCH:
        return BlockerSearchTrainer(movable_ids, target_id, oracle, config)
    return QTreeTrainer(movable_ids, target_id, oracle, config)
