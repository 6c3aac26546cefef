"""False-infeasible / false-feasible measurement of the planner against the reference (no ROS).

Random questions (scene, relocated set, object) on generated clutter are answered by the real
planner (:class:`~.planner.MotionPlanner`, benchmark time limit) and, where it says no, by the
slow :class:`~.reference.ReferencePlanner`. Every feasible answer of either is checked with
:func:`~.reference.verify_motion`.

* false infeasible: ours says infeasible (a planning failure, not a timeout), the reference finds
  a motion that verifies; rate over ours-infeasible answers and over all questions;
* false feasible: ours says feasible but its motion fails verification (must be 0).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np
from qtree_scene.generator import generate_clutter
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason

from qtree_benchmarks.motion.reference import ReferencePlanner, verify_motion

OURS_TIME_LIMIT_S = 30.0  # our planner's limit here: the machine is shared, 2 s would time out [s]
SCENE_SIZES = (10, 20, 30)  # obstacles per scene, cycled over the scene index [-]
DENSITIES = (0.15, 0.25, 0.35)  # footprint densities, cycled [-]
MAX_RELOCATED = 6  # largest relocated set of a question [-]


@dataclass(frozen=True)
class Question:
    """One question: can ``object_id`` be relocated once ``relocated`` are gone?"""

    scene_seed: int
    n_obstacles: int
    density: float
    relocated: tuple[str, ...]
    object_id: str


@dataclass(frozen=True)
class Answer:
    """Both planners' answers to one question.

    Attributes:
        question: the question.
        ours: our feasibility; ours_reason: its reason code name.
        ours_verified: our motion passed verification (None when infeasible).
        ours_s: our wall time [s].
        blocking_ids / blocked_by_immovable: our blockers.
        reference: reference feasibility (None when not asked: ours was feasible).
        reference_verified: its motion passed verification (None when not feasible).
        reference_s: its wall time [s].
    """

    question: Question
    ours: bool
    ours_reason: str
    ours_verified: bool | None
    ours_s: float
    blocking_ids: tuple[str, ...]
    blocked_by_immovable: bool
    reference: bool | None
    reference_verified: bool | None
    reference_s: float

    @property
    def false_infeasible(self) -> bool:
        """Ours said no (not a timeout), the reference found a verified motion."""
        return (
            not self.ours
            and self.ours_reason != Reason.TIMEOUT.name
            and bool(self.reference_verified)
        )

    @property
    def false_feasible(self) -> bool:
        """Ours said yes, its motion does not verify."""
        return self.ours and not self.ours_verified


def scene_questions(scene_index: int, per_scene: int, seed: int = 0) -> list[Question]:
    """``per_scene`` seeded random questions on generated scene ``scene_index``."""
    n = SCENE_SIZES[scene_index % len(SCENE_SIZES)]
    density = DENSITIES[(scene_index // len(SCENE_SIZES)) % len(DENSITIES)]
    scene_seed = 1000 + scene_index
    scenario = generate_clutter(n, density, scene_seed)
    rng = np.random.default_rng([seed, scene_index])
    obstacles = [o.id for o in scenario.obstacles]
    out = []
    for _ in range(per_scene):
        size = int(rng.integers(0, min(MAX_RELOCATED, len(obstacles)) + 1))
        relocated = sorted(rng.choice(obstacles, size=size, replace=False).tolist())
        left = [o for o in scenario.movable_ids if o not in relocated]
        object_id = str(left[int(rng.integers(len(left)))])
        out.append(Question(scene_seed, n, density, tuple(relocated), object_id))
    return out


def answer_scene(questions: list[Question]) -> list[Answer]:
    """Answer every question of one scene with both planners (shared per-scene caches)."""
    q0 = questions[0]
    scenario = generate_clutter(q0.n_obstacles, q0.density, q0.scene_seed)
    ours = MotionPlanner(scenario, PlannerConfig(time_limit_s=OURS_TIME_LIMIT_S))
    reference = ReferencePlanner(scenario, model=ours.robot)
    out = []
    for q in questions:
        relocated = list(q.relocated)
        start = time.perf_counter()
        mine = ours.check(q.object_id, relocated)
        ours_s = time.perf_counter() - start
        verified = (
            verify_motion(scenario, relocated, q.object_id, mine, ours.robot)[0]
            if mine.feasible
            else None
        )
        ref = ref_verified = None
        ref_s = 0.0
        if not mine.feasible and mine.reason != Reason.TIMEOUT:
            start = time.perf_counter()
            answer = reference.plan(q.object_id, relocated)  # no blocker sweeps, no cache
            ref_s = time.perf_counter() - start
            ref = answer.feasible
            if answer.feasible:
                ref_verified = verify_motion(scenario, relocated, q.object_id, answer, ours.robot)[
                    0
                ]
        out.append(
            Answer(
                q,
                mine.feasible,
                mine.reason.name,
                verified,
                ours_s,
                mine.blocking_ids,
                mine.blocked_by_immovable,
                ref,
                ref_verified,
                ref_s,
            )
        )
    return out


def summary(answers: list[Answer]) -> dict:
    """The JSON summary: counts and rates (see the module docstring)."""
    n = len(answers)
    infeasible = [a for a in answers if not a.ours and a.ours_reason != Reason.TIMEOUT.name]
    feasible = [a for a in answers if a.ours]
    fi = sum(a.false_infeasible for a in answers)
    ff = sum(a.false_feasible for a in answers)
    return {
        'questions': n,
        'scenes': len({a.question.scene_seed for a in answers}),
        'ours_feasible': len(feasible),
        'ours_infeasible': len(infeasible),
        'ours_timeouts': sum(a.ours_reason == Reason.TIMEOUT.name for a in answers),
        'reference_feasible': sum(bool(a.reference) for a in answers),
        'reference_verified': sum(bool(a.reference_verified) for a in answers),
        'reference_unverified': sum(
            bool(a.reference) and not a.reference_verified for a in answers
        ),
        'false_infeasible': fi,
        'false_infeasible_rate': fi / len(infeasible) if infeasible else 0.0,
        'false_infeasible_rate_all_questions': fi / n if n else 0.0,
        'false_feasible': ff,
        'false_feasible_rate': ff / len(feasible) if feasible else 0.0,
        'blocked_by_immovable': sum(a.blocked_by_immovable for a in answers),
        'infeasible_with_blockers': sum(bool(a.blocking_ids) for a in infeasible),
        'ours_s_mean': float(np.mean([a.ours_s for a in answers])) if n else 0.0,
        'reference_s_mean': float(np.mean([a.reference_s for a in infeasible]))
        if infeasible
        else 0.0,
    }


def rows(answers: list[Answer]) -> list[dict]:
    """One JSON row per question."""
    return [{**asdict(a), 'false_infeasible': a.false_infeasible} for a in answers]
