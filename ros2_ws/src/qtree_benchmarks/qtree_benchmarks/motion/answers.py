"""Planner answers on the exact search's questions, to prove a speed-up changes none. No ROS.

:func:`exact_answers` runs the exact set search (:func:`qtree_task_planner.exact.solve_exact`,
the questions the benchmark asks) on S1–S3 and the benchmark's generated scenes, on a fresh
planner, and records per question ``(relocated set, object)`` the answer ``[feasible, reason]``,
and beside it the CPU time of the check (``time.process_time``, robust to a shared machine) and
a fingerprint of the returned motion.
:func:`compare` lists the questions whose answer differs between two such records.

The time limit is raised (:data:`TIME_LIMIT_S`) so that a loaded machine's ``TIMEOUT`` cannot
make two runs of the same code differ; every other setting is the planner's default. The #14
blocker search on infeasible answers is switched off (it does not change feasible/reason).
"""

from __future__ import annotations

import cProfile
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
from qtree_scene.generator import generate_clutter
from qtree_scene.scenario import load_scenario
from qtree_scene.scene import Scenario
from qtree_task_planner.exact import solve_exact
from qtree_task_planner.exceptions import SearchLimitExceededError
from qtree_task_planner.oracle import MotionPlannerOracle
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult

from qtree_benchmarks.motion.figures import PHASES
from qtree_benchmarks.profile_stats import raw_stats

SCENARIOS = ('s1', 's2', 's3', 'gen_8_0.2_0', 'gen_8_0.2_1', 'gen_8_0.2_2')  # the benchmark's
TIME_LIMIT_S = 600.0  # no TIMEOUT answers on a loaded machine [s]
MAX_SETS = 400  # exact-search budget on the generated scenes [-]


def load(name: str) -> Scenario:
    """An installed scenario (``'s1'``) or a generated one, ``'gen_<objects>_<density>_<seed>'``
    (:func:`qtree_scene.generator.generate_clutter`, ``layout='uniform'``: the scenes the
    committed answer keys were taken on, fixed so that planner changes stay comparable).
    """
    if name.startswith('gen_'):
        _, objects, density, seed = name.split('_')
        return generate_clutter(int(objects), float(density), int(seed), layout='uniform')
    return load_scenario(name)


def question_key(relocated: Iterable[str], object_id: str) -> str:
    """``'a,b|o'``: the sorted relocated set and the object (the cache's key as text)."""
    return f'{",".join(sorted(relocated))}|{object_id}'


def _fingerprint(result) -> list:
    """Approach yaw [rad], number of samples and sum of the joint trajectory [rad] (rounded)."""
    if not result.feasible:
        return []
    q = np.asarray(result.joint_trajectory)
    return [round(float(result.approach_yaw), 6), len(q), round(float(q.sum()), 6)]


class RecordingPlanner(MotionPlanner):
    """The motion planner, handing every answer of :meth:`check` and its CPU time [s] to
    ``record(object_id, relocated, result, cpu_s)``.
    """

    def __init__(
        self,
        scenario: Scenario,
        config: PlannerConfig,
        record: Callable[[str, list[str], PlanResult, float], None],
    ) -> None:
        super().__init__(scenario, config)
        self._record = record

    def check(self, object_id: str, relocated_ids: Iterable[str]) -> PlanResult:
        """:meth:`MotionPlanner.check`, recorded."""
        relocated = list(relocated_ids)
        start = time.process_time()
        result = super().check(object_id, relocated)
        self._record(object_id, relocated, result, time.process_time() - start)
        return result


def exact_answers(name: str, progress: Callable[[str], None] | None = None) -> dict:
    """Answers, CPU times [s] and motion fingerprints of one scenario's exact search.

    Returns:
        ``{'answers': {key: [feasible, reason]}, 'cpu_s': {key: s}, 'reached_stpik': {key:
        bool}, 'motion': {key: [yaw, n, sum]}, 'stages_s': {key: {stage: wall s}}, 'level':
        optimal level}``.
    """
    scenario = load(name)
    out: dict = {'answers': {}, 'cpu_s': {}, 'reached_stpik': {}, 'motion': {}, 'stages_s': {}}

    def record(object_id: str, relocated: list[str], result: PlanResult, cpu_s: float) -> None:
        if result.from_cache:
            return
        key = question_key(relocated, object_id)
        out['cpu_s'][key] = cpu_s
        out['answers'][key] = [bool(result.feasible), result.reason.name]
        out['reached_stpik'][key] = result.timings.get('stpik', 0.0) > 0.0
        out['motion'][key] = _fingerprint(result)
        out['stages_s'][key] = {k: round(v, 6) for k, v in result.timings.items()}
        if progress is not None:
            progress(f'{name} {key}: {result.reason.name}')

    planner = RecordingPlanner(scenario, PlannerConfig(time_limit_s=TIME_LIMIT_S), record)
    planner.blockers.enabled = False
    oracle = MotionPlannerOracle(scenario, planner=planner)
    ids = tuple(o.id for o in scenario.obstacles)
    try:
        out['level'] = solve_exact(ids, scenario.target.id, oracle, max_sets=MAX_SETS).level
    except SearchLimitExceededError:
        out['level'] = None  # past the budget: the questions asked so far are recorded
    return out


def compare(before: dict, after: dict) -> dict:
    """Questions answered differently (or asked by only one run), and motions that changed."""
    changed, motions, missing = [], 0, []
    before, after = scenarios(before), scenarios(after)
    for name in sorted(set(before) | set(after)):
        a = before.get(name, {}).get('answers', {})
        b = after.get(name, {}).get('answers', {})
        for key in sorted(set(a) | set(b)):
            if key not in a or key not in b:
                missing.append(f'{name} {key}')
            elif a[key] != b[key]:
                changed.append(f'{name} {key}: {a[key]} -> {b[key]}')
            elif before[name]['motion'].get(key) != after[name]['motion'].get(key):
                motions += 1
    total = sum(len(before.get(n, {}).get('answers', {})) for n in before)
    return {'questions': total, 'changed': changed, 'missing': missing, 'motions_changed': motions}


def fastest(records: list[dict]) -> dict:
    """The first record with, per question, the smallest CPU time over ``records`` (runs of the
    same code; the minimum filters out interference of other processes).
    """
    out = {
        name: {**part, 'cpu_s': dict(part['cpu_s'])}
        for name, part in scenarios(records[0]).items()
    }
    for record in records[1:]:
        for name, part in out.items():
            for key, seconds in record.get(name, {}).get('cpu_s', {}).items():
                if key in part['cpu_s']:
                    part['cpu_s'][key] = min(part['cpu_s'][key], seconds)
    return out


def timing_summary(record: dict) -> dict:
    """Median / p95 CPU ms of the feasible and reached-STPIK checks of a record (and the
    feasible checks' median wall ms per stage).
    """
    feasible: list[float] = []
    reached: list[float] = []
    stages: dict[str, list[float]] = {}
    for part in scenarios(record).values():
        for key, seconds in part['cpu_s'].items():
            if part['answers'][key][0]:
                feasible.append(seconds)
                for stage, value in part.get('stages_s', {}).get(key, {}).items():
                    stages.setdefault(stage, []).append(value)
            if part['reached_stpik'][key]:
                reached.append(seconds)

    def stats(values: list[float]) -> dict:
        if not values:
            return {'n': 0}
        return {
            'n': len(values),
            'median_ms': round(float(np.median(values)) * 1e3, 1),
            'p95_ms': round(float(np.percentile(values, 95)) * 1e3, 1),
            'total_s': round(float(np.sum(values)), 2),
        }

    out = {'feasible': stats(feasible), 'reached_stpik': stats(reached)}
    out['feasible']['stage_median_wall_ms'] = {
        k: round(float(np.median(v)) * 1e3, 1) for k, v in stages.items()
    }
    return out


def profiled_answers(names: Iterable[str], progress: Callable[[str], None] | None = None) -> dict:
    """:func:`exact_answers` of every scenario under cProfile with a CPU clock.

    Returns:
        ``{scenario: record, ..., '_profile': {phase: cumulative CPU s}}`` (phases of
        :data:`~qtree_benchmarks.motion.figures.PHASES`, summed over the scenarios).
    """
    profiler = cProfile.Profile(time.process_time)
    out = {}
    profiler.enable()
    for name in names:
        out[name] = exact_answers(name, progress)
    profiler.disable()
    phases: dict[str, float] = {}
    for (file, _, function), (_, _, _, cumulative, _) in raw_stats(profiler).items():
        phase = PHASES.get((Path(file).name, function))
        if phase is not None:
            phases[phase] = round(phases.get(phase, 0.0) + cumulative, 3)
    out['_profile'] = phases
    return out


def scenarios(record: dict) -> dict:
    """The per-scenario parts of a record (without ``'_profile'``)."""
    return {name: part for name, part in record.items() if not name.startswith('_')}
