"""Q-Tree training, Algorithm 1 of the paper, with Q-bar (eq. 10) and the steady state (eq. 11).

Each episode starts at the root s_H, chooses actions with the policy, asks the feasibility oracle
ONLY when an edge is new (the motion planner is activated only for new nodes, Sect. 3.2.2, so MP
calls = edges), initialises a new edge to its reward, updates a revisited edge with eq. (5),
aborts on a -1 reward and stops when the target was tried.

Steady state (eq. 11): |Q-bar(k) - Q-bar(k-1)| <= beta must hold, with no new edge (hence no new
node), for ``steady_episodes`` consecutive episodes. A single episode is not enough: an episode
that walks into an already-known -1 edge, or through zero-valued edges, changes neither the tree
nor Q-bar, so eq. (11) on one episode would stop training at the first such episode, long before
the reward of the target has propagated to the root. Training also stops at Ep_max.

RND (no learning) does not update Q and stops at the first episode that reaches the target.
H-EG-SET (ours) additionally runs :meth:`QTree.sweep` before extracting the sequence.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from qtree_task_planner.exceptions import InvalidParameterError
from qtree_task_planner.extraction import (
    EXTRACTION_NONE,
    best_known_sequence,
    extract,
    extract_sequence,
)
from qtree_task_planner.oracle import FeasibilityOracle
from qtree_task_planner.policies import Policy, make_policy
from qtree_task_planner.rewards import reward
from qtree_task_planner.tree import QTree

STOP_STEADY = 'steady_state'
# Readings of the steady state (#31): eq. (11) with no new edge in the episode (default: the
# paper's prose, "no nodes are added and no edge weights are significantly updated"), or eq. (11)
# alone (its formula). An episode that adds an edge ends on a new edge of Q = -1 or +100, so for
# beta < 1 the two part only when an update offsets that change of Q-bar (test_training.py).
STEADY_RULES = ('no-new-edge', 'q-bar')
STOP_MAX_EPISODES = 'max_episodes'
STOP_TARGET = 'target_reached'  # RND only
STOP_CANCELLED = 'cancelled'
STOP_TIME = 'time_limit'
EXTRACTION_RND = 'first-target-episode'  # RND: the sequence of its first target-reaching episode


@dataclass(frozen=True, kw_only=True)
class TrainingConfig:
    """Hyper-parameters of one training (defaults: Sect. 4 of the paper).

    Attributes:
        policy: RND, LRND, H-LRND, H-EG or H-EG-SET.
        max_episodes: Ep_max.
        seed: seed of the ``numpy.random.Generator``.
        alpha: learning rate of eq. (5), in (0, 1].
        gamma: discount of eq. (5), in (0, 1].
        epsilon0: eps_0 of eq. (9), in (0, 1].
        epsilon_min: eps_min of eq. (9), in (0, eps_0].
        beta: threshold of eq. (11) [reward units], > 0.
        steady_episodes: consecutive episodes eq. (11) must hold, >= 1.
        time_limit_s: optional wall-time cap [s] (used for RND).
        optimal_level: known optimal level (exact reference) for the first-optimal episode; when
            None, ``first_optimal_episode`` is -1 and only ``first_learned_level_episode`` (the
            first episode reaching the level of the learned sequence) is reported.
        hlrnd_rule: H-LRND reading, ``'not-failed'`` (default) or ``'positive-q'``
            (:mod:`qtree_task_planner.policies`).
        epsilon_coin: H-eG coin per ``'step'`` (default) or per ``'episode'``.
        steady_rule: one of :data:`STEADY_RULES`: ``'no-new-edge'`` (default) or ``'q-bar'``
            (eq. (11) alone).
    """

    policy: str = 'H-EG'
    max_episodes: int = 5000
    seed: int = 0
    alpha: float = 0.5
    gamma: float = 0.9
    epsilon0: float = 1.0
    epsilon_min: float = 1e-4
    beta: float = 1e-3
    steady_episodes: int = 50
    time_limit_s: float | None = None
    optimal_level: int | None = None
    hlrnd_rule: str = 'not-failed'
    epsilon_coin: str = 'step'
    steady_rule: str = 'no-new-edge'

    def __post_init__(self) -> None:
        """Validate every field.

        Raises:
            InvalidParameterError: a field out of range (names the field).
        """
        for name in ('alpha', 'gamma'):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise InvalidParameterError(name, value, 'must be in (0, 1]')
        if self.max_episodes <= 0:
            raise InvalidParameterError('max_episodes', self.max_episodes, 'must be > 0')
        if self.seed < 0:
            raise InvalidParameterError('seed', self.seed, 'must be >= 0 (a numpy seed)')
        if not self.beta > 0.0:
            raise InvalidParameterError('beta', self.beta, 'must be > 0')
        if self.steady_episodes <= 0:
            raise InvalidParameterError('steady_episodes', self.steady_episodes, 'must be > 0')
        if self.steady_rule not in STEADY_RULES:
            raise InvalidParameterError(
                'steady_rule', self.steady_rule, f'must be one of {STEADY_RULES}'
            )
        if self.time_limit_s is not None and not self.time_limit_s > 0.0:
            raise InvalidParameterError('time_limit_s', self.time_limit_s, 'must be > 0')


@dataclass(frozen=True)
class EpisodeStats:
    """Statistics after one episode (published on /training_stats).

    Attributes:
        episode: k, 1-based.
        nodes: tree nodes (root included).
        edges: tree edges.
        mp_calls: motion-planner calls as the paper counts them (= edges).
        planner_runs: real planner runs after caching, since the training started.
        q_bar: Q-bar(k) of eq. (10) [reward units].
        epsilon: eps(k) of eq. (9) (1 for the random policies).
        sequence: objects chosen in this episode (the last may have failed).
        reached_target: the target was relocated in this episode.
        new_edges: edges created in this episode.
        best_sequence: eq. (19) extraction after this episode (``()`` if none).
    """

    episode: int
    nodes: int
    edges: int
    mp_calls: int
    planner_runs: int
    q_bar: float
    epsilon: float
    sequence: tuple[str, ...]
    reached_target: bool
    new_edges: int
    best_sequence: tuple[str, ...]


@dataclass(kw_only=True)
class TrainingResult:
    """Outcome of a training.

    Attributes:
        policy: the policy's canonical name.
        sequence: learned sequence (RND: the first sequence that reached the target); ``()``
            if none.
        episodes: episodes run.
        mp_calls: edges at the end (the paper's MP calls).
        planner_runs: real planner runs after caching.
        converged: the steady state of eq. (11) was reached.
        stop_reason: one of the ``STOP_*`` constants.
        first_optimal_episode: first episode reaching the target through a sequence of the
            known optimal level (``TrainingConfig.optimal_level``); -1 if never or if the optimal
            level is unknown.
        optimal_level: the known optimal level (0 if unknown).
        wall_time_s: training time [s].
        history: per-episode statistics.
        first_learned_level_episode: first episode reaching the target through a sequence as
            long as the learned one (-1 without a learned sequence). Equal to
            ``first_optimal_episode`` only when the learned sequence is optimal.
        extraction: how ``sequence`` was obtained: ``'eq19'`` (greedy walk of eq. 19),
            ``'best-known-fallback'`` (eq. 19 found none; the best explored target-reaching
            sequence), ``'first-target-episode'`` (RND) or ``'none'``.
    """

    policy: str
    sequence: tuple[str, ...]
    episodes: int
    mp_calls: int
    planner_runs: int
    converged: bool
    stop_reason: str
    first_optimal_episode: int
    optimal_level: int
    wall_time_s: float
    history: list[EpisodeStats] = field(repr=False)
    first_learned_level_episode: int = -1
    extraction: str = EXTRACTION_NONE

    @property
    def success(self) -> bool:
        """A sequence ending with the target was found."""
        return bool(self.sequence)


def first_optimal_episode(history: list[EpisodeStats], optimal_level: int) -> int:
    """First episode that reached the target through a sequence of ``optimal_level`` objects.

    Returns:
        The 1-based episode, or -1 if none.
    """
    for stats in history:
        if stats.reached_target and len(stats.sequence) == optimal_level:
            return stats.episode
    return -1


EpisodeCallback = Callable[[EpisodeStats], bool]


class TrainerBase(ABC):
    """What every trainer holds: its configuration, its oracle and one statistics per episode.

    The constructor keeps ``config`` and ``oracle``, starts an empty ``history`` and hands the
    action set to :meth:`_build`, where a subclass builds its own state.

    Args:
        movable_ids: the action set, obstacles then target (``Scenario.movable_ids``).
        target_id: id of the target T.
        oracle: feasibility oracle (motion planner).
        config: hyper-parameters.
    """

    def __init__(
        self,
        movable_ids: tuple[str, ...],
        target_id: str,
        oracle: FeasibilityOracle,
        config: TrainingConfig,
    ) -> None:
        self.config = config
        self.oracle = oracle
        self.history: list[EpisodeStats] = []
        self._build(movable_ids, target_id)

    @abstractmethod
    def _build(self, movable_ids: tuple[str, ...], target_id: str) -> None:
        """Build the subclass's state (called once, by the constructor)."""

    @property
    def episode(self) -> int:
        """Episodes run so far (BLOCKER-SEARCH: candidates tested)."""
        return len(self.history)


class QTreeTrainer(TrainerBase):
    """Runs Algorithm 1 episode by episode; its state stays readable after an error.

    Args:
        movable_ids: the action set, obstacles then target (``Scenario.movable_ids``).
        target_id: id of the target T.
        oracle: feasibility oracle (motion planner).
        config: hyper-parameters.

    Raises:
        InvalidParameterError: bad configuration or unknown policy.
    """

    def _build(self, movable_ids: tuple[str, ...], target_id: str) -> None:
        """The policy, the tree, the random generator and the counters (see the class)."""
        config = self.config
        self.policy: Policy = make_policy(
            config.policy,
            tuple(movable_ids),
            target_id,
            epsilon0=config.epsilon0,
            epsilon_min=config.epsilon_min,
            max_episodes=config.max_episodes,
            hlrnd_rule=config.hlrnd_rule,
            epsilon_coin=config.epsilon_coin,
        )
        self.tree = QTree(
            target_id,
            config.alpha,
            config.gamma,
            share_sets=self.policy.share_sets,
            optimistic_over=tuple(movable_ids) if self.policy.optimistic else None,
        )
        self.rng = np.random.default_rng(config.seed)
        self._runs_at_start = self.oracle.planner_runs
        self._steady_count = 0
        self._started = time.monotonic()

    @property
    def converged(self) -> bool:
        """Eq. (11) held for ``steady_episodes`` consecutive episodes without new edges."""
        return self._steady_count >= self.config.steady_episodes

    def run_episode(self) -> EpisodeStats:
        """Run one episode from the root (Algorithm 1, lines 3-10).

        Raises:
            OracleUnavailableError: the oracle gave no answer (the tree keeps what was learned).
        """
        tree, policy = self.tree, self.policy
        k = self.episode + 1
        q_bar_before = tree.q_bar
        key = tree.root.key
        sequence: list[str] = []
        new_edges, reached = 0, False
        explore = policy.episode_coin(self.rng, k)  # None unless the coin is per episode
        while True:
            action = policy.select(tree, key, self.rng, k, explore)  # line 5
            if action is None:  # dead end: every remaining action failed here
                break
            edge = tree.node(key).children.get(action)
            if edge is None:  # new edge: ask the motion planner (lines 6-9)
                feasible = self.oracle.feasible(tuple(sequence), action)
                edge, _ = tree.add_edge(key, action, reward(action, tree.target_id, feasible))
                new_edges += 1
            elif policy.learns:  # revisited edge: eq. (5) (line 10)
                tree.update(edge)
            sequence.append(action)
            if not edge.feasible:  # -1: abort the episode
                break
            if action == tree.target_id:
                reached = True
                break
            key = edge.child
        if k % 500 == 0:
            tree.recompute_q_bar()
        no_growth = new_edges == 0 or self.config.steady_rule == 'q-bar'
        steady = no_growth and abs(tree.q_bar - q_bar_before) <= self.config.beta  # eq. (11)
        self._steady_count = self._steady_count + 1 if steady else 0
        stats = EpisodeStats(
            episode=k,
            nodes=tree.num_nodes,
            edges=tree.num_edges,
            mp_calls=tree.num_edges,
            planner_runs=self.oracle.planner_runs - self._runs_at_start,
            q_bar=tree.q_bar,
            epsilon=policy.epsilon(k),
            sequence=tuple(sequence),
            reached_target=reached,
            new_edges=new_edges,
            best_sequence=self._best_sequence(),
        )
        self.history.append(stats)
        return stats

    def _best_sequence(self) -> tuple[str, ...]:
        """Eq. (19) after this episode (known values for the optimistic H-EG-SET)."""
        if not self.policy.learns:
            return ()
        if self.policy.optimistic:
            return best_known_sequence(self.tree)
        return extract_sequence(self.tree)

    def run(self, callback: EpisodeCallback | None = None) -> TrainingResult:
        """Train until the steady state, Ep_max, the time limit, or (RND) the target.

        Args:
            callback: called after each episode with its statistics; returning False cancels.

        Returns:
            The result (``stop_reason`` says why training ended).

        Raises:
            OracleUnavailableError: the oracle gave no answer; call :meth:`result` for the partial
                statistics.
        """
        config = self.config
        while True:
            stats = self.run_episode()
            if callback is not None and callback(stats) is False:
                return self.result(STOP_CANCELLED)
            if not self.policy.learns and stats.reached_target:
                return self.result(STOP_TARGET)
            if self.policy.learns and self.converged:
                return self.result(STOP_STEADY)
            if self.episode >= config.max_episodes:
                return self.result(STOP_MAX_EPISODES)
            elapsed = time.monotonic() - self._started
            if config.time_limit_s is not None and elapsed > config.time_limit_s:
                return self.result(STOP_TIME)

    def result(self, stop_reason: str) -> TrainingResult:
        """The result so far (also usable after an :class:`OracleUnavailableError`)."""
        if self.policy.learns:
            if self.policy.share_sets:  # H-EG-SET: converge the known values before eq. (19)
                self.tree.sweep()
            sequence, method = extract(self.tree)
        else:
            last = self.history[-1] if self.history else None
            sequence = last.sequence if last is not None and last.reached_target else ()
            method = EXTRACTION_RND if sequence else EXTRACTION_NONE
        level = self.config.optimal_level or 0
        first = first_optimal_episode(self.history, level) if level else -1
        learned = first_optimal_episode(self.history, len(sequence)) if sequence else -1
        return TrainingResult(
            policy=self.policy.name,
            sequence=sequence,
            episodes=self.episode,
            mp_calls=self.tree.num_edges,
            planner_runs=self.oracle.planner_runs - self._runs_at_start,
            converged=self.policy.learns and self.converged,
            stop_reason=stop_reason,
            first_optimal_episode=first,
            optimal_level=level,
            wall_time_s=time.monotonic() - self._started,
            history=self.history,
            first_learned_level_episode=learned,
            extraction=method,
        )


def train(
    movable_ids: tuple[str, ...],
    target_id: str,
    oracle: FeasibilityOracle,
    config: TrainingConfig,
    callback: EpisodeCallback | None = None,
) -> TrainingResult:
    """Build a :class:`QTreeTrainer` and run it (see there)."""
    return QTreeTrainer(movable_ids, target_id, oracle, config).run(callback)
