"""Benchmark of the STPIK motion planner: time per feasibility check by stage, cache hit rate on
a task-planner-like query stream, exact optimal relocation level per scenario, independent
verification of every feasible trajectory, where the time goes (cProfile), and three IK peers
(STPIK, pink, plain DLS) tracking the same whole EE paths from Home.

Usage: ``python scripts/bench_motion_planner.py [--quick] [--no-profile]`` (env.sh sourced).
Writes ``benchmarks/results/motion_planner.json`` and ``.md``. The logic lives in
:mod:`qtree_benchmarks.motion`.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import random
import sys
import time
from pathlib import Path

import numpy as np
from jaco2_description.model import Jaco2Model
from qtree_scene.generator import generate_clutter
from qtree_scene.scenario import load_scenario
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason
from stpik_motion_planner.verifier import STOP_CLEARANCE_M, TrajectoryVerifier
from tqdm import tqdm

from qtree_benchmarks.motion import figures, peers, report, verification
from qtree_benchmarks.paths import results_dir

OUT = results_dir()
TARGETS = {  # issue #13
    'feasible_median_ms': 10.0,
    'reached_stpik_p95_ms': 25.0,
    'stpik_whole_path': 0.9,
}


def main() -> int:
    """Run the motion-planner benchmark, write ``motion_planner.*``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--quick', action='store_true', help='short run (a few minutes)')
    parser.add_argument('--no-profile', action='store_true', help='skip the cProfile run')
    parser.add_argument(
        '--before',
        type=Path,
        help='an earlier motion_planner.json of the same questions: written as before_after',
    )
    args = parser.parse_args()
    before = json.loads(args.before.read_text()) if args.before else None
    quick = args.quick
    scenes = [load_scenario(n) for n in ('s1', 's2', 's3')]
    # layout='uniform': the generated scenes of the committed results (kept comparable).
    scenes += [
        generate_clutter(8, 0.2, seed, layout='uniform') for seed in range(1 if quick else 3)
    ]
    episodes = 10 if quick else 200
    # Feasible paths per scene given to the IK peers: ≥ 40 whole paths in all (#29). 12 per
    # scene gave 37 in the quick run (s1 has 14 feasible answers, the quick gen scene 1).
    peer_paths = 15
    max_sets = 400 if quick else 2000
    wall_start = time.perf_counter()
    # At the executor's stop distance, like the planner's own check (#29).
    verifier = TrajectoryVerifier(Jaco2Model(), clearance_m=STOP_CLEARANCE_M)
    rows, results, peer_runs, checked = [], [], [], []
    determinism = {'questions': 0, 'changed_answers': 0, 'changed': []}
    step_times: list[tuple[float, float, float]] = []  # per STPIK step (solve, kin., coll.) [s]
    for scene in tqdm(scenes, desc='scenes'):
        planner = MotionPlanner(scene)
        planner.blockers.enabled = False  # #14's blockers: not timed here
        start = time.perf_counter()
        figures.query_stream(planner, episodes, 0)
        stream = {'hits': planner.cache.hits, 'misses': planner.cache.misses}
        level, sets, queries = figures.optimal_level(planner, max_sets)
        scene_results = list(planner.cache._results.items())
        step_times += planner.stpik.step_times
        results += [r for _, r in scene_results]
        planner_s = time.perf_counter() - start
        checked.append(verification.verify_results(scene, scene_results, verifier))
        if scene.name in ('s1', 's2'):  # the same questions again, reversed, in a new planner
            _ask_again(scene, scene_results, determinism)
        feasible = [(k, r) for k, r in scene_results if r.feasible]
        chosen = random.Random(1).sample(feasible, min(peer_paths, len(feasible)))
        for key, result in chosen:
            peer_runs.append(peers.run_peers(planner, key, result))
        total = stream['hits'] + stream['misses']
        rows.append(
            {
                'scene': scene.name,
                'obstacles': len(scene.obstacles),
                'optimal_level': level,
                'sets_explored': sets,
                'exact_queries': queries,
                'planner_runs': len(planner.cache),
                'feasible_runs': len(feasible),
                'stream_queries': total,
                'stream_hit_rate': round(stream['hits'] / total, 3) if total else None,
                'overall_hit_rate': round(planner.cache.hit_rate, 3),
                'planner_wall_s': round(planner_s, 2),
                'peer_paths': len(chosen),
            }
        )
    profile = None if args.no_profile else figures.profile_breakdown(scenes[1], max_sets)
    peer_figures = figures.peer_summary(peer_runs)
    rejected = sum(
        r.reason in (Reason.VERIFICATION_FAILED, Reason.CARRIED_COLLISION) for r in results
    )
    stpik = peer_figures.get('stpik', {})
    config = PlannerConfig()
    summary = {
        'quick': quick,
        'machine': f'{platform.machine()} {platform.python_version()} (shared 2-core machine)',
        'load_average': [round(x, 1) for x in os.getloadavg()],
        'targets': TARGETS,
        'levels': {r['scene']: r['optimal_level'] for r in rows[:3]},
        'verifier': verification.merge(checked, rejected, STOP_CLEARANCE_M),
        'stpik_whole_path': {
            'paths': stpik.get('paths', 0),
            'success_rate': stpik.get('success_with_clearance'),
        },
        'checks': figures.check_summary(results),
        'determinism': determinism,
        'stpik_step_us': _step_summary(step_times),
        'peers': peer_figures,
        'peer_settings': {
            'iterations_per_waypoint': peers.PEER_ITERATIONS,
            'pink_solver': peers.QP_SOLVER,
            'pink_dt_s': round(
                config.max_joint_step_rad / float(np.max(Jaco2Model().model.velocityLimit)), 4
            ),
            'tolerance_m': config.position_tolerance_m,
            'tolerance_rad': config.orientation_tolerance_rad,
        },
        'profile': profile,
        # scripts/planner_answers.py compare --out: main vs this code on the same questions
        'speed': _speed_record(),
        'scenes': rows,
        'wall_s': round(time.perf_counter() - wall_start, 1),
    }
    if before is not None:
        summary['before_after'] = _before_after(before, summary)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / 'motion_planner.json').write_text(json.dumps(summary, indent=2) + '\n')
    markdown = report.render(summary) + report.notes(summary) + _step_note(summary)
    (OUT / 'motion_planner.md').write_text(markdown)
    print(markdown)
    return 0


def _ask_again(scene, scene_results: list, out: dict) -> None:
    """Ask the cached questions of ``scene`` again in reverse order in a fresh planner (#29:
    the answer must not depend on what was asked before); count answers whose reason or
    trajectory changed (TIMEOUT answers are not cached, so never compared).
    """
    again = MotionPlanner(scene)
    again.blockers.enabled = False
    for (relocated, object_id), first in reversed(scene_results):
        second = again.plan(object_id, sorted(relocated))
        if second.reason == Reason.TIMEOUT:  # the machine, not the question: not compared
            out['timeouts'] = out.get('timeouts', 0) + 1
            continue
        out['questions'] += 1
        same = second.reason == first.reason and np.array_equal(
            second.joint_trajectory, first.joint_trajectory
        )
        if not same:
            out['changed_answers'] += 1
            out['changed'].append(f'{scene.name} {object_id} after {sorted(relocated)}')


def _before_after(before: dict, after: dict) -> dict:
    """Timing figures and answer counts of an earlier run beside this one's."""
    out: dict = {'load_average': [before.get('load_average'), after['load_average']]}
    for group in ('all', 'reached_stpik', 'feasible'):
        for key in ('n', 'median_ms', 'p95_ms', 'mean_ms'):
            out[f'{group}.{key}'] = [
                before['checks'].get(group, {}).get(key),
                after['checks'][group][key],
            ]
    out['reasons'] = [before['checks'].get('reasons'), after['checks']['reasons']]
    out['levels'] = [before.get('levels'), after['levels']]
    out['same_answers'] = out['reasons'][0] == out['reasons'][1] and (
        out['levels'][0] == out['levels'][1]
    )
    return out


def _step_note(summary: dict) -> str:
    """Markdown lines of the all-check percentiles and the per-step figures (issue #28)."""
    every, step = summary['checks']['all'], summary['stpik_step_us']
    return (
        f'\n## Issue #28 figures\n\n'
        f'- all checks: median {every["median_ms"]} ms, p95 {every["p95_ms"]} ms '
        f'(target 50); feasible median {summary["checks"]["feasible"]["median_ms"]} ms '
        f'(target 10); load average {summary["load_average"]}.\n'
        f'- STPIK step (median over {step.get("steps", 0)} steps): {step.get("median")} µs '
        f'(target 30) = solve {step.get("solve_median")} + kinematics '
        f'{step.get("kinematics_median")} + collision {step.get("collision_median")} µs '
        f'(medians of each part).\n'
    ) + (
        f'- before/after (same questions): {summary["before_after"]}\n'
        if 'before_after' in summary
        else ''
    )


def _step_summary(step_times: list[tuple[float, float, float]]) -> dict:
    """Median wall time per STPIK step [µs] and its split (solve with the step bound,
    kinematics without collision, collision queries), over every planner step of the run.
    """
    if not step_times:
        return {'steps': 0}
    times = np.asarray(step_times) * 1e6
    return {
        'steps': len(times),
        'median': round(float(np.median(times.sum(axis=1))), 1),
        'p95': round(float(np.percentile(times.sum(axis=1), 95)), 1),
        'solve_median': round(float(np.median(times[:, 0])), 1),
        'kinematics_median': round(float(np.median(times[:, 1])), 1),
        'collision_median': round(float(np.median(times[:, 2])), 1),
    }


def _speed_record() -> dict | None:
    """The committed before/after comparison of the speed work, if any."""
    path = OUT / 'motion_planner_speed.json'
    return json.loads(path.read_text()) if path.exists() else None


if __name__ == '__main__':
    sys.exit(main())
