"""Validation of a RetrieveTarget goal into a training configuration (no ROS import).

The node accepts every goal, then aborts an invalid one with ``error_code=INVALID_GOAL`` and the
message of :class:`InvalidParameterError`, which names the offending field, so that the client
sees why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from qtree_task_planner.exceptions import InvalidParameterError
from qtree_task_planner.replanning import DEFAULT_MAX_REPLANS, MAX_REPLANS
from qtree_task_planner.trainers import canonical_planner_name
from qtree_task_planner.training import TrainingConfig

FLOAT_FIELDS = ('alpha', 'gamma', 'epsilon0', 'epsilon_min', 'beta')  # every float64 goal field


@dataclass(frozen=True)
class GoalSettings:
    """A validated goal.

    Attributes:
        config: the training configuration.
        feedback_every: publish feedback and a /qtree snapshot every this many episodes.
        execute: run the learned sequence on the arm after training.
        max_replans: re-plans allowed during the execution (#32) [-].
    """

    config: TrainingConfig
    feedback_every: int
    execute: bool
    max_replans: int = DEFAULT_MAX_REPLANS


def settings_from_goal(goal: Any) -> GoalSettings:
    """Check every field of a ``RetrieveTarget.Goal`` (or any object with the same attributes).

    Args:
        goal: fields policy, max_episodes, seed, alpha, gamma, epsilon0, epsilon_min, beta,
            steady_episodes, execute, feedback_every, max_replans (absent: the default 3).

    Returns:
        The validated settings.

    Raises:
        InvalidParameterError: the first invalid field (the message names it).
    """
    policy = canonical_planner_name(str(goal.policy))
    for name in FLOAT_FIELDS:  # NaN and inf pass some range checks (inf > 0): reject them first
        value = float(getattr(goal, name))
        if not math.isfinite(value):
            raise InvalidParameterError(name, value, 'must be a finite number')
    for name in ('epsilon0', 'epsilon_min'):
        value = float(getattr(goal, name))
        if not 0.0 < value <= 1.0:
            raise InvalidParameterError(name, value, 'must be in (0, 1]')
    if goal.epsilon_min > goal.epsilon0:
        reason = f'must be <= epsilon0 ({goal.epsilon0})'
        raise InvalidParameterError('epsilon_min', goal.epsilon_min, reason)
    if int(goal.feedback_every) <= 0:
        raise InvalidParameterError('feedback_every', goal.feedback_every, 'must be > 0')
    max_replans = int(getattr(goal, 'max_replans', DEFAULT_MAX_REPLANS))
    if not 0 <= max_replans <= MAX_REPLANS:
        raise InvalidParameterError('max_replans', max_replans, f'must be in [0, {MAX_REPLANS}]')
    config = TrainingConfig(  # validates alpha, gamma, max_episodes, beta, steady_episodes
        policy=policy,
        max_episodes=int(goal.max_episodes),
        seed=int(goal.seed),
        alpha=float(goal.alpha),
        gamma=float(goal.gamma),
        epsilon0=float(goal.epsilon0),
        epsilon_min=float(goal.epsilon_min),
        beta=float(goal.beta),
        steady_episodes=int(goal.steady_episodes),
    )
    return GoalSettings(config, int(goal.feedback_every), bool(goal.execute), max_replans)
