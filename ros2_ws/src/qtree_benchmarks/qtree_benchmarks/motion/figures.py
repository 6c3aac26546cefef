"""Planner figures: query streams, exact optimal levels, timing summaries, profiles. No ROS."""

from __future__ import annotations

import cProfile
import random
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from qtree_scene.scene import Scenario
from qtree_task_planner.exact import solve_exact
from qtree_task_planner.exceptions import SearchLimitExceededError
from qtree_task_planner.oracle import MotionPlannerOracle
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult

from qtree_benchmarks.motion.peers import PEERS
from qtree_benchmarks.profile_stats import raw_stats

STAGES = ('sampling', 'stpik', 'collision', 'verify')
PHASES = {  # (file, function) -> phase reported with its cumulative profiled time
    ('planner.py', 'plan'): 'whole check (plan)',
    ('planner.py', '_sample'): 'Cartesian sampling (_sample)',
    ('stpik.py', 'converge'): 'STPIK converge (pre-grasp, above drop zone; up to 40 iterations)',
    ('stpik.py', 'track'): 'STPIK track (approach, lift, place, retreat legs)',
    ('stpik.py', 'transit'): 'joint transits (collision checks only)',
    ('verifier.py', 'verify'): 'independent verification of the returned trajectory',
}


def query_stream(planner: MotionPlanner, episodes: int, seed: int) -> None:
    """Task-planner-like queries: random relocation sequences, the target tried at every step."""
    rng = random.Random(seed)
    ids = [o.id for o in planner.scenario.obstacles]
    target = planner.scenario.target.id
    for _ in range(episodes):
        done: list[str] = []
        while not planner.check(target, done).feasible:
            remaining = [o for o in ids if o not in done]
            if not remaining:
                break
            choice = rng.choice(remaining)
            if not planner.check(choice, done).feasible:
                break
            done.append(choice)


def optimal_level(planner: MotionPlanner, max_sets: int) -> tuple[int | None, int, int]:
    """(optimal level, sets explored, oracle queries) by exact BFS; level None past the budget."""
    scenario = planner.scenario
    oracle = MotionPlannerOracle(scenario, planner=planner)
    try:
        solution = solve_exact(
            tuple(o.id for o in scenario.obstacles), scenario.target.id, oracle, max_sets=max_sets
        )
    except SearchLimitExceededError:
        return None, max_sets, -1
    return (solution.level or None), solution.sets_explored, solution.queries


def profile_breakdown(scenario: Scenario, max_sets: int) -> dict:
    """CProfile of a fresh planner's exact search; own time grouped by where it is spent."""
    planner = MotionPlanner(scenario)
    profiler = cProfile.Profile()
    profiler.enable()
    optimal_level(planner, max_sets)
    profiler.disable()
    stats = raw_stats(profiler)
    groups: dict[str, float] = {}
    functions: dict[str, float] = {}
    for (file, line, name), (_, _, own, _, _) in stats.items():
        group = _category(file, name)
        groups[group] = groups.get(group, 0.0) + own
        where = f'{Path(file).name}:{line}({name})' if file != '~' else name
        functions[where] = functions.get(where, 0.0) + own
    total = sum(groups.values())
    phases = {}
    for (file, _, name), (_, _, _, cumulative, _) in stats.items():
        if (Path(file).name, name) in PHASES:
            phases[PHASES[Path(file).name, name]] = round(cumulative, 3)
    return {
        'phase_cumulative_s': phases,
        'scenario': scenario.name,
        'checks': len(planner.cache),
        'total_s': round(total, 3),
        'share': {k: round(v / total, 3) for k, v in _largest(groups)},
        'top_functions_s': {k: round(v, 3) for k, v in _largest(functions)[:12]},
    }


def _largest(seconds: dict[str, float]) -> list[tuple[str, float]]:
    """``seconds`` as (name, s) pairs, largest first (``Counter.most_common`` for floats)."""
    return sorted(seconds.items(), key=lambda item: -item[1])


def _category(file: str, name: str) -> str:
    text = f'{file} {name}'
    if 'collision.py' in file or 'fcl' in text:
        return 'FCL queries (broad phase, callbacks, narrow phase, placement)'
    if 'damped_pinv' in name or 'solve_hierarchy' in name or 'linalg' in text:
        return 'STPIK pseudo-inverses (SVD, eq. 6 projections)'
    if '/tasks/' in file or ('stpik.py' in file and name == 'solve'):
        return 'STPIK task assembly (rows, activation)'
    if 'pinocchio' in text:
        return 'Pinocchio (FK, Jacobians, SE3)'
    if 'cartesian_path.py' in file or 'ompl' in text:
        return 'Cartesian sampling (corridor, RRTConnect)'
    if 'stpik.py' in file:
        return 'STPIK loop (track/converge/transit)'
    if 'numpy' in text or file == '~':
        return 'other numpy / builtins'
    return 'other Python'


def percentile_ms(values: Sequence[float], q: float) -> float | None:
    """Percentile ``q`` of ``values`` [s] in milliseconds (None if empty)."""
    return round(float(np.percentile(values, q)) * 1e3, 2) if len(values) else None


def check_summary(results: list[PlanResult]) -> dict:
    """Median / p95 of uncached checks, all and feasible, and the per-stage split."""
    feasible = [r for r in results if r.feasible]
    reached = [r for r in results if r.timings.get('stpik', 0.0) > 0.0]
    out: dict[str, Any] = {'reasons': dict(Counter(r.reason.name for r in results).most_common())}
    total = sum(r.planning_time for r in results) or 1.0
    pregrasp = [r for r in results if not r.feasible and r.message.startswith('pre-grasp')]
    out['time_share'] = {
        'rejected before STPIK': _share(
            [r for r in results if r.timings.get('stpik', 0.0) <= 0.0], total
        ),
        'infeasible in STPIK': _share([r for r in reached if not r.feasible], total),
        '  of which the pre-grasp converge failed': _share(pregrasp, total),
        'feasible': _share(feasible, total),
    }
    for label, group in (('all', results), ('reached_stpik', reached), ('feasible', feasible)):
        times = [r.planning_time for r in group]
        cpu = [r.cpu_time for r in group]
        out[label] = {
            'n': len(group),
            'median_ms': percentile_ms(times, 50),
            'p95_ms': percentile_ms(times, 95),
            'cpu_median_ms': percentile_ms(cpu, 50),  # thread CPU time (load-independent)
            'cpu_p95_ms': percentile_ms(cpu, 95),
            'mean_ms': round(float(np.mean(times)) * 1e3, 2) if times else None,
            'stage_median_ms': {
                k: percentile_ms([r.timings.get(k, 0.0) for r in group], 50) for k in STAGES
            },
            'stage_mean_ms': {
                k: round(float(np.mean([r.timings.get(k, 0.0) for r in group])) * 1e3, 2)
                if group
                else None
                for k in STAGES
            },
        }
    return out


def _share(group: list[PlanResult], total: float) -> float:
    return round(sum(r.planning_time for r in group) / total, 3)


def peer_summary(runs: list[dict[str, dict]]) -> dict:
    """Per peer: success rates, median/p95 time per path and per waypoint, error figures."""
    out = {}
    for name in PEERS:
        rows = [r[name] for r in runs]
        if not rows:
            continue
        seconds = [r['seconds'] for r in rows]
        per_waypoint = [r['seconds'] / max(r['waypoints'], 1) for r in rows]
        clearances = [r['scene_clearance_m'] for r in rows if r['scene_clearance_m'] is not None]
        out[name] = {
            'paths': len(rows),
            'tracked': round(float(np.mean([r['tracked'] for r in rows])), 3),
            'judged': sum(r['limits_ok'] is not None for r in rows),
            'limits_ok': _rate([r['limits_ok'] for r in rows]),
            'collision_free': _rate([r['collision_free'] for r in rows]),
            'success': round(float(np.mean([r['success'] for r in rows])), 3),
            'success_with_clearance': round(
                float(np.mean([r['success_with_clearance'] for r in rows])), 3
            ),
            'median_ms': percentile_ms(seconds, 50),
            'p95_ms': percentile_ms(seconds, 95),
            'median_us_per_waypoint': round(float(np.median(per_waypoint)) * 1e6, 1),
            'median_scene_clearance_mm': round(float(np.median(clearances)) * 1e3, 1)
            if clearances
            else None,
            'failures': dict(
                Counter(
                    r['message'].split(':')[0] if r['message'] else _failure(r)
                    for r in rows
                    if not r['success_with_clearance']
                )
            ),
        }
    return out


def _rate(flags: list[bool | None]) -> float | None:
    judged = [f for f in flags if f is not None]
    return round(float(np.mean(judged)), 3) if judged else None


def _failure(row: dict) -> str:
    if not row['tracked']:
        return 'tolerance missed'
    if not row['limits_ok']:
        return 'joint limit'
    return 'clearance'
