"""A benchmark variant: a policy and the reading of each point the paper leaves open.

Readings (see :mod:`qtree_task_planner.policies` and :mod:`qtree_task_planner.training`):

* ``hlrnd_rule``: H-LRND's "not selected before, or selected with a positive reward":
  ``'not-failed'`` (default; keeps optimality: 100 % optimal on S1-S3) or ``'positive-q'``
  (Q > 0 edge weight, falling back to all candidates when none qualifies). Used by H-LRND and
  by the exploration step of H-EG / H-EG-SET.
* ``epsilon_coin``: H-eG's explore/exploit coin per ``'step'`` (default) or per ``'episode'``.
* ``steady_episodes``: the steady-state window, episodes in a row eq. (11) must hold (default 50;
  the paper's literal reading is 1).

A reading that does not apply to a policy is stored as ``'-'`` (e.g. the coin of LRND), so one
variant = one distinct training setting.
"""

from __future__ import annotations

from dataclasses import dataclass

from qtree_task_planner.policies import EPSILON_COINS, HLRND_RULES, POLICY_NAMES

DEFAULT_RULE = 'not-failed'
DEFAULT_COIN = 'step'
DEFAULT_WINDOW = 50
NOT_APPLICABLE = '-'
SWEEP_POLICIES = ('RND', 'LRND', 'H-LRND', 'H-EG', 'H-EG-SET')
SWEEP_WINDOWS = (1, 50)
# Named readings (hlrnd_rule, epsilon_coin, steady_episodes). 'paper': the combination of the
# committed sweep (benchmark_sweep.json, 50 trainings per row, windows 1/5/10/20/50, the S1-S3
# re-laid to the paper's difficulty by #31) whose Tables 1-3 cells come closest to the paper's
# (scripts/paper_fidelity.py: 8 of 18 cells within ±30 %, the default 7): H-LRND's "positive
# reward" as "not -1", H-εG's coin once per episode, eq. (11) on 50 episodes.
READINGS: dict[str, tuple[str, str, int]] = {
    'default': (DEFAULT_RULE, DEFAULT_COIN, DEFAULT_WINDOW),
    'paper': ('not-failed', 'episode', 50),
}


def uses_rule(policy: str) -> bool:
    """The policy explores with the H-LRND rule."""
    return policy.startswith('H-')


def uses_coin(policy: str) -> bool:
    """The policy is epsilon-greedy."""
    return policy.startswith('H-EG')


def uses_window(policy: str) -> bool:
    """The policy stops at the steady state (RND stops at its first target)."""
    return policy != 'RND'


@dataclass(frozen=True)
class Variant:
    """One training setting of the benchmark.

    Attributes:
        policy: one of :data:`qtree_task_planner.policies.POLICY_NAMES`.
        hlrnd_rule: one of ``HLRND_RULES`` or ``'-'`` when it does not apply.
        epsilon_coin: one of ``EPSILON_COINS`` or ``'-'``.
        steady_episodes: steady-state window (0 when it does not apply: RND).
    """

    policy: str
    hlrnd_rule: str = DEFAULT_RULE
    epsilon_coin: str = DEFAULT_COIN
    steady_episodes: int = DEFAULT_WINDOW

    @classmethod
    def make(cls, policy: str, rule: str, coin: str, window: int) -> Variant:
        """A variant with the readings that do not apply to ``policy`` blanked.

        Raises:
            ValueError: unknown policy or reading, or window < 1.
        """
        if policy not in POLICY_NAMES:
            raise ValueError(f'unknown policy {policy!r}; expected one of {POLICY_NAMES}')
        if rule not in HLRND_RULES:
            raise ValueError(f'unknown H-LRND rule {rule!r}; expected one of {HLRND_RULES}')
        if coin not in EPSILON_COINS:
            raise ValueError(f'unknown epsilon coin {coin!r}; expected one of {EPSILON_COINS}')
        if window < 1:
            raise ValueError(f'steady window must be >= 1, got {window}')
        return cls(
            policy,
            rule if uses_rule(policy) else NOT_APPLICABLE,
            coin if uses_coin(policy) else NOT_APPLICABLE,
            window if uses_window(policy) else 0,
        )

    @classmethod
    def of_record(cls, record: dict) -> Variant:
        """The variant a benchmark record or summary row was trained with."""
        return cls(record['policy'], record['hlrnd_rule'], record['epsilon_coin'],
                   int(record['steady_episodes']))  # fmt: skip

    @property
    def is_default(self) -> bool:
        """Every reading that applies is the default one (the committed Tables 1-3)."""
        return (
            self.hlrnd_rule in (DEFAULT_RULE, NOT_APPLICABLE)
            and self.epsilon_coin in (DEFAULT_COIN, NOT_APPLICABLE)
            and self.steady_episodes in (DEFAULT_WINDOW, 0)
        )

    @property
    def label(self) -> str:
        """A short unique name: ``H-EG [positive-q, coin/episode, window 1]``."""
        parts = []
        if self.hlrnd_rule != NOT_APPLICABLE:
            parts.append(self.hlrnd_rule)
        if self.epsilon_coin != NOT_APPLICABLE:
            parts.append(f'coin/{self.epsilon_coin}')
        if self.steady_episodes:
            parts.append(f'window {self.steady_episodes}')
        return f'{self.policy} [{", ".join(parts)}]' if parts else self.policy

    def training_kwargs(self) -> dict:
        """Keyword arguments of :class:`qtree_task_planner.training.TrainingConfig`."""
        return {
            'policy': self.policy,
            'hlrnd_rule': DEFAULT_RULE if self.hlrnd_rule == NOT_APPLICABLE else self.hlrnd_rule,
            'epsilon_coin': (
                DEFAULT_COIN if self.epsilon_coin == NOT_APPLICABLE else self.epsilon_coin
            ),
            'steady_episodes': self.steady_episodes or DEFAULT_WINDOW,
        }


def sweep_variants(
    policies: tuple[str, ...] = SWEEP_POLICIES, windows: tuple[int, ...] = SWEEP_WINDOWS
) -> list[Variant]:
    """Every combination of readings that changes a policy's numbers, each once, in table
    order (policy, then rule, coin, window).
    """
    seen: dict[Variant, None] = {}
    for policy in policies:
        for rule in HLRND_RULES:
            for coin in EPSILON_COINS:
                for window in windows:
                    seen.setdefault(Variant.make(policy, rule, coin, window), None)
    return list(seen)
