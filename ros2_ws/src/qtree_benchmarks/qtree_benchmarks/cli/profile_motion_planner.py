"""Profile of the STPIK motion planner on a fixed question set, and its answers (issue #28).

Runs the task-planner-like query stream (:func:`qtree_benchmarks.motion.figures.
query_stream`) on S1–S3 in one process, blockers off, under cProfile; writes the top 25
functions by cumulative time and every answer ``(scene, relocated, object) -> (feasible,
reason)`` so two versions of the planner can be compared on the same questions.

Usage: ``python scripts/profile_motion_planner.py --tag before [--episodes 3]`` (env.sh
sourced). Writes ``benchmarks/results/profiles/motion_planner_<tag>.txt`` and ``..._<tag>
_answers.json``; ``--compare A B`` lists the answers that differ between two tags.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import sys
import time

import numpy as np
from qtree_scene.scenario import load_scenario
from stpik_motion_planner.planner import MotionPlanner

from qtree_benchmarks.motion import figures
from qtree_benchmarks.paths import results_dir

OUT = results_dir() / 'profiles'


def run(tag: str, episodes: int, scenes: list[str]) -> None:
    """Profile the query stream on ``scenes`` and write the profile and the answers."""
    profiler = cProfile.Profile()
    answers: dict[str, list] = {}
    times: list[float] = []
    feasible_times: list[float] = []
    start = time.perf_counter()
    for name in scenes:
        planner = MotionPlanner(load_scenario(name))
        planner.blockers.enabled = False  # blockers: not profiled here
        profiler.enable()
        figures.query_stream(planner, episodes, 0)
        profiler.disable()
        for (relocated, object_id), r in planner.cache._results.items():
            key = f'{name}|{",".join(sorted(relocated))}|{object_id}'
            answers[key] = [bool(r.feasible), r.reason.name]
            times.append(r.planning_time)
            if r.feasible:
                feasible_times.append(r.planning_time)
    wall = time.perf_counter() - start
    text = io.StringIO()
    stats = pstats.Stats(profiler, stream=text)
    stats.sort_stats('cumulative').print_stats(25)
    header = (
        f'# motion planner profile ({tag}): query stream, {episodes} episodes on '
        f'{", ".join(scenes)}, blockers off, one process, under cProfile\n'
        f'# load average at end: {os.getloadavg()}\n'
        f'# checks: {len(times)} (feasible {len(feasible_times)}), wall {wall:.1f} s\n'
        f'# check time under cProfile: median {np.median(times) * 1e3:.1f} ms, '
        f'p95 {np.percentile(times, 95) * 1e3:.1f} ms, feasible median '
        f'{np.median(feasible_times) * 1e3 if feasible_times else float("nan"):.1f} ms\n'
    )
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f'motion_planner_{tag}.txt').write_text(header + text.getvalue())
    (OUT / f'motion_planner_{tag}_answers.json').write_text(
        json.dumps(answers, indent=1, sort_keys=True) + '\n'
    )
    print(header)


def compare(a: str, b: str) -> None:
    """Print every question answered differently by tags ``a`` and ``b``."""
    first = json.loads((OUT / f'motion_planner_{a}_answers.json').read_text())
    second = json.loads((OUT / f'motion_planner_{b}_answers.json').read_text())
    common = sorted(set(first) & set(second))
    changed = [k for k in common if first[k][0] != second[k][0]]
    reason = [k for k in common if first[k][0] == second[k][0] and first[k][1] != second[k][1]]
    print(f'{len(common)} common questions; feasibility changed on {len(changed)}:')
    for k in changed:
        print(f'  {k}: {first[k]} -> {second[k]}')
    print(f'reason changed (same feasibility) on {len(reason)}:')
    for k in reason:
        print(f'  {k}: {first[k]} -> {second[k]}')
    print(
        f'only in {a}: {len(set(first) - set(second))}, only in {b}: '
        f'{len(set(second) - set(first))}'
    )


def main() -> int:
    """Profile typical checks, write the profiles under ``benchmarks/results/profiles``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--tag', default='after')
    parser.add_argument('--episodes', type=int, default=3)
    parser.add_argument('--scenes', default='s1,s2,s3')
    parser.add_argument('--compare', nargs=2, metavar=('A', 'B'))
    args = parser.parse_args()
    if args.compare:
        compare(*args.compare)
    else:
        run(args.tag, args.episodes, args.scenes.split(','))
    return 0


if __name__ == '__main__':
    sys.exit(main())
