"""Execution benchmark: every relocation of the S1–S3 optimal sequences executed open loop and
closed loop (the STPIK local controller, paper Sect. 3.1), without and with each disturbance.

In-process at simulated time (the simulator's integrator and disturbances, the motion planner's
closed-loop controller; see ``scripts/execution_benchmark.py``), so the figures are deterministic
except the controller step times, measured as wall time and as thread CPU time.

Usage: ``python scripts/bench_execution.py [--scenarios s1 s2 s3] [--quick]`` (env.sh sourced).
Writes ``benchmarks/results/execution.json`` (``rows[]`` per mode × disturbance, ``runs[]`` per
relocation) and ``execution.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from itertools import zip_longest

from qtree_scene.scenario import load_scenario
from stpik_motion_planner.execution_config import ExecutionConfig
from stpik_motion_planner.planner import MotionPlanner
from tqdm import tqdm

from qtree_benchmarks.motion.execution import (
    DISTURBANCES,
    Executor,
    aggregate,
    optimal_relocations,
    summary,
)
from qtree_benchmarks.paths import results_dir

OUT = results_dir()
MODES = ('open_loop', 'closed_loop')
TARGETS = {
    'closed_rms_mm': 5.0,
    'closed_placement_mm': 5.0,
    'disturbed_closed_placement_mm': 10.0,
    'step_p99_us': 2000.0,
}
TARGET_DISTURBANCES = ('offset_0.05rad_j2', 'latency_50ms', 'velocity_0.7x')


def main() -> int:
    """Run the execution benchmark; exit code 0 when every target is met."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--scenarios', nargs='+', default=['s1', 's2', 's3'])
    parser.add_argument('--quick', action='store_true', help='first relocation per scene only')
    parser.add_argument(
        '--markdown-only', action='store_true', help='rewrite execution.md from execution.json'
    )
    args = parser.parse_args()
    if args.markdown_only:
        report = json.loads((OUT / 'execution.json').read_text())
        (OUT / 'execution.md').write_text(markdown(report))
        return 0
    start = time.time()
    per_scene = []
    for name in args.scenarios:
        scenario = load_scenario(name)
        planner = MotionPlanner(scenario)
        relocations = optimal_relocations(scenario, planner)
        per_scene.append(
            [(name, scenario, planner, *r) for r in relocations[: 1 if args.quick else None]]
        )
    # Interleaved (1st relocation of every scene, then the 2nd, ...): the results file is
    # rewritten after each relocation, so a cut-short run still covers every scene.
    order = [job for group in zip_longest(*per_scene) for job in group if job is not None]
    runs: list[dict] = []
    total = len(order) * len(MODES) * len(DISTURBANCES)
    done = 0
    with tqdm(total=total, desc='executions', unit='run') as bar:
        for name, scenario, planner, relocated, object_id in order:
            result = planner.check(object_id, relocated)
            if not result.feasible:
                print(f'{name}: {object_id} after {relocated} not feasible: {result.message}')
                continue
            for disturbance, values in DISTURBANCES.items():
                for mode in MODES:
                    run = Executor(
                        scenario, relocated, object_id, result, values,
                        planner_config=planner.config,
                    ).run(mode)  # fmt: skip
                    runs.append(summary(mode, disturbance, f'{name}:{object_id}', run))
                    bar.update()
            done += 1
            write(args, runs, done, len(order), start)
    report = write(args, runs, done, len(order), start)
    print(markdown(report))
    return 0


def write(args: argparse.Namespace, runs: list[dict], done: int, planned: int, start: float):
    """Write execution.json and execution.md for the runs so far; the report."""
    rows = aggregate(runs)
    checks = check_targets(rows)
    report = {
        'machine': f'{platform.machine()} {platform.python_version()} (shared 2-core machine)',
        'scenarios': args.scenarios,
        'quick': args.quick,
        'relocations': done,
        'relocations_planned': planned,
        'control_rate_hz': ExecutionConfig().control_rate_hz,
        'obstacle_margin_mm': MotionPlanner(load_scenario('s1')).config.obstacle_min_distance_m
        * 1e3,
        'targets': TARGETS,
        'target_checks': checks,
        'rows': rows,
        'runs': runs,
        'wall_s': round(time.time() - start, 1),
        'load_average_5min': round(os.getloadavg()[1], 2),  # other processes on the cores
    }
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / 'execution.json').write_text(json.dumps(report, indent=1) + '\n')
    (OUT / 'execution.md').write_text(markdown(report))
    return report


def check_targets(rows: list[dict]) -> dict[str, dict]:
    """Each target of issue #17 with the figure reached and whether it is met."""
    by = {(r['mode'], r['disturbance']): r for r in rows}
    closed = by.get(('closed_loop', 'none'), {})
    margin = MotionPlanner(load_scenario('s1')).config.obstacle_min_distance_m * 1e3
    out = {
        'closed_rms_mm': _check(closed.get('rms_error_mm'), TARGETS['closed_rms_mm']),
        'closed_placement_mm': _check(
            closed.get('placement_error_mm'), TARGETS['closed_placement_mm']
        ),
        'closed_clearance_mm': {
            'value': closed.get('min_clearance_mm'),
            'limit': margin,
            'met': (closed.get('min_clearance_mm') or -1) >= margin,
        },
        'closed_completed': {
            'value': closed.get('completed'),
            'limit': closed.get('relocations'),
            'met': closed.get('completed') == closed.get('relocations'),
        },
    }
    for d in TARGET_DISTURBANCES:
        row = by.get(('closed_loop', d), {})
        complete = row.get('completed') == row.get('relocations')
        check = _check(row.get('placement_error_mm'), TARGETS['disturbed_closed_placement_mm'])
        check['met'] = check['met'] and complete
        out[f'closed_placement_mm_{d}'] = check
    p99 = [r['step_p99_us'] for r in rows if r['mode'] == 'closed_loop' and r['step_p99_us']]
    cpu = [
        r['step_cpu_p99_us'] for r in rows if r['mode'] == 'closed_loop' and r['step_cpu_p99_us']
    ]
    out['step_p99_us'] = _check(max(p99, default=None), TARGETS['step_p99_us'])
    out['step_cpu_p99_us'] = _check(max(cpu, default=None), TARGETS['step_p99_us'])
    return out


def _check(value: float | None, limit: float) -> dict:
    return {'value': value, 'limit': limit, 'met': value is not None and value <= limit}


def markdown(report: dict) -> str:
    """The Markdown page of the results."""
    lines = [
        '# Execution benchmark (issue #17): open loop vs the closed-loop STPIK controller',
        '',
        f'{report["relocations"]} of the {report.get("relocations_planned", "?")} relocations of '
        f'the exact optimal sequences of {", ".join(report["scenarios"]).upper()} (taken '
        'interleaved: the first of each scene, then the second, ...), each executed open loop '
        '(the planned trajectory streamed whole) and closed loop (one STPIK step of eq. 6 per '
        f'tick at {report["control_rate_hz"]:g} Hz), in-process at simulated time on the sim '
        f'integrator. {report["machine"]}; wall {report["wall_s"]} s.',
        '',
        'Errors are of the TRUE EE position vs the reference of the same instant; placement is '
        'the object centre at the release vs where the plan releases it (worst relocation; the '
        'sim then stands an object released within 50 mm of its drop slot on the slot: a '
        'modelling step, not counted); clearance is the '
        'smallest robot / carried-object distance to the scene (planner margin '
        f'{report["obstacle_margin_mm"]:g} mm); step times are per controller step (wall, and '
        'thread CPU time, which excludes preemption by the other processes of the shared '
        'machine).',
        '',
        '| disturbance | mode | done | RMS [mm] | max [mm] | placement max / mean [mm] | '
        'min clearance [mm] | time [s] | step median / p99 [µs] | step CPU p99 [µs] |',
        '|---|---|---|---|---|---|---|---|---|---|',
    ]
    for r in report['rows']:
        lines.append(
            f'| {r["disturbance"]} | {r["mode"]} | {r["completed"]}/{r["relocations"]} | '
            f'{r["rms_error_mm"]} | {r["max_error_mm"]} | {r["placement_error_mm"]} / '
            f'{r["mean_placement_error_mm"]} | {r["min_clearance_mm"]} | '
            f'{r["time_to_complete_s"]} | {r["step_median_us"]} / {r["step_p99_us"]} | '
            f'{r["step_cpu_p99_us"]} |'
        )
    lines += ['', '## Targets', '', '| target | value | limit | met |', '|---|---|---|---|']
    for name, c in report['target_checks'].items():
        lines.append(f'| {name} | {c["value"]} | {c["limit"]} | {"yes" if c["met"] else "NO"} |')
    lines += [
        '',
        '## Notes',
        '',
        *([f'- **{report["note"]}**'] if report.get('note') else []),
        '- The plans move at `velocity_scale` = 0.5 of the joint velocity limits, so a 0.7× '
        'velocity limit does not bind and changes little in either mode.',
        '- Latency only delays the open-loop motion (same end point, larger error vs the '
        'timed reference); the joint offset is what open loop cannot see: the arm settles '
        'off by the offset, and the ROS open-loop executor then never sees its goal within '
        '`goal_tolerance_rad` (0.02 rad) and answers EXECUTION_FAILED after '
        '`execution_timeout_s`; here it is let through to show the drift.',
        '- Since #26 the closed loop corrects the predicted arm (reference + the offset '
        'measured across the round trip, a Smith predictor) instead of the delayed '
        'measurement. Under latency it therefore follows the plan a round trip late, like open '
        'loop (RMS 9.0 mm vs the reference of the same instant), where it used to push the arm '
        'ahead to cancel an error that was the delay itself: RMS 1.22 mm, but a minimum '
        'clearance of 0.81 mm against the 5 mm margin, 1.14 mm off at the placement, and an '
        'oscillating loop from 5 + 5 ticks of round trip (test_closed_loop.py). The offset row '
        'pays for the same choice at the start of each relocation (the arm jumps by the offset '
        'before it is measured): RMS 1.97 mm / max 18.1 mm, was 0.43 / 11.6 mm.',
        '- Wall-time step percentiles include preemption by other processes (5-minute load '
        f'average {report.get("load_average_5min", "?")} at the end of the run, '
        f'{os.cpu_count()} cores); the thread CPU time is the cost of the step itself.',
    ]
    failures = [r for r in report['rows'] if r['failures']]
    if failures:
        lines += ['', '## Stops', '']
        for r in failures:
            lines.append(f'- {r["mode"]}, {r["disturbance"]}: ' + '; '.join(r['failures']))
    return '\n'.join(lines) + '\n'


if __name__ == '__main__':
    sys.exit(main())
