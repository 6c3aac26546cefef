"""Tree exploration policies of Sect. 3.2.1: RND, LRND, H-LRND, H-eG (eq. 9), and H-EG-SET.

Action set (Sect. 3.2): from a node, the candidate actions are the objects (obstacles and target)
not yet relocated in the node's sequence and not already tried unsuccessfully from this node
(:func:`available_actions`). Candidates are listed in the scenario's order (obstacles, then the
target) so that a seeded generator gives reproducible choices.

Interpretation of the points the paper leaves open (documented choices):

* RND (no learning) ignores the tree: at each step it picks uniformly among the objects not yet
  relocated in the current episode (it does not remember failures), an infeasible pick aborts the
  episode, and the search stops at the first episode that reaches the target; that episode's
  sequence is RND's answer. Sect. 4 describes it as a breadth-first-like random exploration
  "until the target is reached", optimal in about 60 % of S1 trials and intractable on S2/S3
  (a random episode almost never survives 5-6 specific picks), which this reproduces.
* LRND: uniform among the candidate actions.
* H-LRND: the target first if it was never tried from this node; otherwise uniform among
  "actions not selected in previous episodes or already selected but corresponding to a
  positive reward". Two readings (``hlrnd_rule``):

  - ``'not-failed'`` (default): "positive" as "not -1": uniform among the candidate actions, so
    H-LRND = LRND + target-first. Every feasible branch keeps being explored, the tree converges
    to the values of eq. (17) and eq. (19) returns the optimum (100 % optimal on S1-S3).
  - ``'positive-q'``: "positive" as a positive EDGE WEIGHT: uniform among the untried
    candidates and those whose edge has Q > 0; when none qualifies (all tried, none with Q > 0
    yet), uniform among all candidates. Branches whose values have not risen yet are not
    re-entered, so training stops sooner and on fewer edges, but often on a sub-optimal sequence.
    (Eq. (8) gives only 0 or 100 to feasible actions, so the reward itself cannot be the test:
    a strictly positive reward would forbid going back through any relocated obstacle.)
* H-eG: with probability eps(k) of eq. (9) explore with the H-LRND rule, otherwise exploit: the
  candidate with the largest Q, an untried candidate counting as Q = 0 (the value a new obstacle
  edge starts with), ties broken uniformly. The coin (``epsilon_coin``) is drawn per step
  (``'step'``, default: the classical epsilon-greedy) or once per episode (``'episode'``: a whole
  episode explores or exploits).
* eps(k) is reported as 1 for LRND/H-LRND/RND (always exploring) in the statistics.
* H-EG-SET (ours, not in the paper): H-eG on a tree with set sharing (see
  :mod:`qtree_task_planner.tree`): one node per SET of relocated objects, so a known
  (set, object) answer is never asked again and a failure learned after one order is known
  after every order; untried actions are valued optimistically (r_T for the target, gamma r_T
  for an obstacle, :meth:`QTree.value`), so the greedy choice tries every action that could
  still beat the best known sequence before settling (optimism in the face of uncertainty: the
  steady state cannot be declared while a shorter sequence is still possible); before
  extraction, one Bellman sweep (:meth:`QTree.sweep`) turns the values the episodes left stale
  into the steady-state values of eq. (17).
* H-EG-SET-PLAIN (ablation): set sharing and the sweep without the optimism. It needs the fewest
  planner calls but settles on sub-optimal sequences on large scenes (see the benchmark).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qtree_task_planner.exceptions import InvalidParameterError, UnknownPolicyError
from qtree_task_planner.tree import NodeKey, QTree

POLICY_NAMES = ('RND', 'LRND', 'H-LRND', 'H-EG', 'H-EG-SET', 'H-EG-SET-PLAIN')
HLRND_RULES = ('not-failed', 'positive-q')  # readings of H-LRND's "positive reward"
EPSILON_COINS = ('step', 'episode')  # when H-eG draws its explore/exploit coin


def epsilon_schedule(
    episode: int, epsilon0: float, epsilon_min: float, max_episodes: int
) -> float:
    """Exploration probability at episode k, eq. (9).

    Implements eq. (9): eps(k) = eps_0 (eps_min / eps_0)^((k - 1) / (Ep_max - 1)).

    Args:
        episode: k, 1-based.
        epsilon0: eps_0 in (0, 1].
        epsilon_min: eps_min in (0, eps_0].
        max_episodes: Ep_max >= 1 (eps stays eps_0 when Ep_max = 1).

    Returns:
        eps(k), from eps_0 at k = 1 down to eps_min at k = Ep_max.
    """
    if max_episodes <= 1:
        return epsilon0
    return epsilon0 * (epsilon_min / epsilon0) ** ((episode - 1) / (max_episodes - 1))


def available_actions(tree: QTree, key: NodeKey, movable_ids: tuple[str, ...]) -> list[str]:
    """Objects not yet relocated at this node and not already tried unsuccessfully from it.

    Args:
        tree: the Q-Tree.
        key: key of a non-terminal node.
        movable_ids: the action set, obstacles then target.

    Returns:
        Candidate actions in ``movable_ids`` order (possibly empty: a dead end).
    """
    node = tree.node(key)
    relocated = set(node.sequence)
    failed = tree.failed_actions(key)
    return [a for a in movable_ids if a not in relocated and a not in failed]


@dataclass(frozen=True)
class Policy:
    """An exploration policy.

    Attributes:
        name: one of :data:`POLICY_NAMES`.
        movable_ids: the action set, obstacles then target.
        target_id: id of the target T.
        learns: False for RND (no tree update, stop at the first target).
        share_sets: build the tree with set sharing (H-EG-SET).
        greedy: epsilon-greedy (H-EG, H-EG-SET) rather than purely random.
        epsilon0: eps_0 of eq. (9).
        epsilon_min: eps_min of eq. (9).
        max_episodes: Ep_max of eq. (9).
        hlrnd_rule: one of :data:`HLRND_RULES` (the H-LRND rule, also H-eG's exploration).
        epsilon_coin: one of :data:`EPSILON_COINS`.
    """

    name: str
    movable_ids: tuple[str, ...]
    target_id: str
    learns: bool = True
    share_sets: bool = False
    optimistic: bool = False
    greedy: bool = False
    epsilon0: float = 1.0
    epsilon_min: float = 1e-4
    max_episodes: int = 5000
    hlrnd_rule: str = 'not-failed'
    epsilon_coin: str = 'step'

    def episode_coin(self, rng: np.random.Generator, episode: int) -> bool | None:
        """Draw the per-episode coin (``epsilon_coin='episode'``): True = explore this episode.

        Returns None (no draw, the generator untouched) for per-step coins and non-greedy
        policies.
        """
        if not (self.greedy and self.epsilon_coin == 'episode'):
            return None
        return bool(rng.random() < self.epsilon(episode))

    def epsilon(self, episode: int) -> float:
        """eps(k) of eq. (9) for the greedy policies, 1 (always exploring) for the others."""
        if not self.greedy:
            return 1.0
        return epsilon_schedule(episode, self.epsilon0, self.epsilon_min, self.max_episodes)

    def select(
        self,
        tree: QTree,
        key: NodeKey,
        rng: np.random.Generator,
        episode: int,
        explore: bool | None = None,
    ) -> str | None:
        """Choose the next action from a node (Algorithm 1, line 5).

        Args:
            tree: the Q-Tree.
            key: key of the current, non-terminal node.
            rng: the training's random generator.
            episode: k, 1-based (for eq. (9)).
            explore: this episode's coin (:meth:`episode_coin`); None draws one per step.

        Returns:
            The object to relocate, or None when no candidate is left (dead end).
        """
        if not self.learns:  # RND: uniform among objects not relocated in this episode
            relocated = set(tree.node(key).sequence)
            options = [a for a in self.movable_ids if a not in relocated]
            return _uniform(options, rng)
        options = available_actions(tree, key, self.movable_ids)
        if not options:
            return None
        if self.name == 'LRND':
            return _uniform(options, rng)
        if self.greedy:
            exploit = rng.random() >= self.epsilon(episode) if explore is None else not explore
            if exploit:
                return _argmax_q(tree, key, options, rng)
        return self._heuristic(tree, key, options, rng)

    def _heuristic(
        self, tree: QTree, key: NodeKey, options: list[str], rng: np.random.Generator
    ) -> str | None:
        """H-LRND rule: the target if untried here, else uniform among the candidates (or, with
        ``hlrnd_rule='positive-q'``, among the untried ones and those with Q > 0 when any).
        """
        children = tree.node(key).children
        if self.target_id in options and self.target_id not in children:
            return self.target_id
        if self.hlrnd_rule == 'positive-q':
            positive = [a for a in options if a not in children or children[a].q > 0.0]
            options = positive or options
        return _uniform(options, rng)


def _uniform(options: list[str], rng: np.random.Generator) -> str | None:
    """Uniform choice, None from an empty list."""
    if not options:
        return None
    return options[int(rng.integers(len(options)))]


def _argmax_q(tree: QTree, key: NodeKey, options: list[str], rng: np.random.Generator) -> str:
    """Candidate with the largest Q (untried = 0), ties broken uniformly at random."""
    children = tree.node(key).children
    values = [children[a].q if a in children else tree.untried_value(key, a) for a in options]
    best = max(values)
    ties = [a for a, v in zip(options, values, strict=True) if v == best]
    return ties[int(rng.integers(len(ties)))] if len(ties) > 1 else ties[0]


def canonical_policy_name(name: str) -> str:
    """The canonical spelling of a policy name (``h-εg`` -> ``H-EG``).

    Raises:
        UnknownPolicyError: not one of :data:`POLICY_NAMES`.
    """
    canonical = name.strip().upper().replace('Ε', 'E')
    if canonical not in POLICY_NAMES:
        raise UnknownPolicyError(name, POLICY_NAMES)
    return canonical


def make_policy(
    name: str,
    movable_ids: tuple[str, ...],
    target_id: str,
    *,
    epsilon0: float = 1.0,
    epsilon_min: float = 1e-4,
    max_episodes: int = 5000,
    hlrnd_rule: str = 'not-failed',
    epsilon_coin: str = 'step',
) -> Policy:
    """Build a policy by name.

    Args:
        name: RND, LRND, H-LRND, H-EG or H-EG-SET (``H-eG`` and ``H-εG`` are accepted too).
        movable_ids: the action set, obstacles then target.
        target_id: id of the target, which must be in ``movable_ids``.
        epsilon0: eps_0 of eq. (9), in (0, 1].
        epsilon_min: eps_min of eq. (9), in (0, eps_0].
        max_episodes: Ep_max >= 1.
        hlrnd_rule: one of :data:`HLRND_RULES`.
        epsilon_coin: one of :data:`EPSILON_COINS`.

    Returns:
        The policy.

    Raises:
        UnknownPolicyError: unknown name.
        InvalidParameterError: an epsilon out of range.
    """
    canonical = canonical_policy_name(name)
    if not 0.0 < epsilon0 <= 1.0:
        raise InvalidParameterError('epsilon0', epsilon0, 'must be in (0, 1]')
    if not 0.0 < epsilon_min <= 1.0:
        raise InvalidParameterError('epsilon_min', epsilon_min, 'must be in (0, 1]')
    if epsilon_min > epsilon0:
        reason = f'must be <= epsilon0 ({epsilon0})'
        raise InvalidParameterError('epsilon_min', epsilon_min, reason)
    if max_episodes < 1:
        raise InvalidParameterError('max_episodes', max_episodes, 'must be > 0')
    if hlrnd_rule not in HLRND_RULES:
        raise InvalidParameterError('hlrnd_rule', hlrnd_rule, f'must be one of {HLRND_RULES}')
    if epsilon_coin not in EPSILON_COINS:
        raise InvalidParameterError(
            'epsilon_coin', epsilon_coin, f'must be one of {EPSILON_COINS}'
        )
    if target_id not in movable_ids:
        raise InvalidParameterError('target_id', target_id, 'must be one of the movable objects')
    return Policy(
        name=canonical,
        movable_ids=tuple(movable_ids),
        target_id=target_id,
        learns=canonical != 'RND',
        share_sets=canonical.startswith('H-EG-SET'),
        optimistic=canonical == 'H-EG-SET',
        greedy=canonical.startswith('H-EG'),
        epsilon0=epsilon0,
        epsilon_min=epsilon_min,
        max_episodes=max_episodes,
        hlrnd_rule=hlrnd_rule,
        epsilon_coin=epsilon_coin,
    )
