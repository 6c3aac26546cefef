"""BLOCKER-SEARCH through the trainer surface the task_planner node uses."""

import pytest
from qtree_task_planner.exceptions import UnknownPolicyError
from qtree_task_planner.goal_checks import settings_from_goal
from qtree_task_planner.oracle import TableOracle
from qtree_task_planner.testing import TOY_MOVABLE, TOY_OPTIMAL_LEVEL, TOY_REQUIREMENTS
from qtree_task_planner.trainers import (
    BLOCKER_SEARCH,
    BlockerSearchTrainer,
    canonical_planner_name,
    make_trainer,
)
from qtree_task_planner.training import STOP_CANCELLED, QTreeTrainer, TrainingConfig


def test_goal_accepts_the_new_planner_and_names_it_on_errors(make_goal) -> None:
    settings = settings_from_goal(make_goal(policy=' blocker-search'))
    assert settings.config.policy == BLOCKER_SEARCH
    with pytest.raises(UnknownPolicyError, match='BLOCKER-SEARCH'):
        canonical_planner_name('A-STAR')
    assert canonical_planner_name('h-εg') == 'H-EG'


def test_trainer_surface_gives_the_certified_optimum() -> None:
    config = TrainingConfig(policy=BLOCKER_SEARCH)
    trainer = make_trainer(TOY_MOVABLE, 'T', TableOracle(TOY_REQUIREMENTS), config)
    assert isinstance(trainer, BlockerSearchTrainer)
    seen = []
    result = trainer.run(seen.append)
    assert len(result.sequence) == TOY_OPTIMAL_LEVEL and result.converged
    assert result.stop_reason == 'optimal' and result.episodes == len(seen) > 0
    assert seen[-1].reached_target and seen[-1].best_sequence == result.sequence
    assert result.planner_runs == seen[-1].planner_runs > 0
    assert trainer.tree.num_edges > 0  # the tested orders, for /qtree
    qtree = make_trainer(TOY_MOVABLE, 'T', TableOracle(TOY_REQUIREMENTS), TrainingConfig())
    assert isinstance(qtree, QTreeTrainer)


def test_budget_and_cancel() -> None:
    small = TrainingConfig(policy=BLOCKER_SEARCH, max_episodes=2)
    result = make_trainer(TOY_MOVABLE, 'T', TableOracle(TOY_REQUIREMENTS), small).run()
    assert result.stop_reason == 'planner_runs' and not result.sequence and not result.converged
    config = TrainingConfig(policy=BLOCKER_SEARCH)
    trainer = make_trainer(TOY_MOVABLE, 'T', TableOracle(TOY_REQUIREMENTS), config)
    cancelled = trainer.run(lambda stats: False)
    assert cancelled.stop_reason == STOP_CANCELLED and cancelled.episodes == 1
