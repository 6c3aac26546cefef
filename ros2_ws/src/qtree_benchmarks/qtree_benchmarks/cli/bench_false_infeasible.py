"""False-infeasible / false-feasible rates of the motion planner against the slow reference.

Random (scene, relocated set, object) questions on generated clutter (N = 10, 20, 30 obstacles,
densities 0.15 / 0.25 / 0.35) are answered by the planner and, where it says no, by
``qtree_benchmarks.motion.reference.ReferencePlanner``; every feasible motion is verified densely
(see ``qtree_benchmarks.motion.false_infeasible``). Results are written after every scene, so an
interrupted run still leaves its figures.

Usage: ``python scripts/bench_false_infeasible.py [--scenes 10] [--per-scene 30] [--workers 1]``
(env.sh sourced). Writes ``benchmarks/results/false_infeasible.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

from tqdm import tqdm

from qtree_benchmarks.motion.false_infeasible import (
    OURS_TIME_LIMIT_S,
    answer_scene,
    rows,
    scene_questions,
    summary,
)
from qtree_benchmarks.motion.reference import REFERENCE_CONFIG
from qtree_benchmarks.paths import results_dir

OUT = results_dir()
TARGET_FALSE_INFEASIBLE = 0.05  # [-]


def parse() -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--scenes', type=int, default=10, help='generated scenes (≥ 1)')
    parser.add_argument('--per-scene', type=int, default=30, help='questions per scene (≥ 1)')
    parser.add_argument('--workers', type=int, default=1, help='processes, one scene each')
    parser.add_argument('--seed', type=int, default=0, help='question seed (≥ 0)')
    args = parser.parse_args()
    for name in ('scenes', 'per_scene', 'workers'):
        if getattr(args, name) < 1:
            parser.error(f'--{name.replace("_", "-")} must be ≥ 1')
    if args.seed < 0:
        parser.error('--seed must be ≥ 0')
    return args


def write(answers: list, meta: dict) -> dict:
    """Write ``false_infeasible.json`` and ``.md``; return the summary written."""
    result = {**summary(answers), 'meta': meta, 'rows': rows(answers)}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / 'false_infeasible.json').write_text(json.dumps(result, indent=1, default=str) + '\n')
    (OUT / 'false_infeasible.md').write_text(markdown(result))
    return result


def markdown(r: dict) -> str:
    """The Markdown report of a summary ``r``."""
    m = r['meta']
    ok_fi = 'met' if r['false_infeasible_rate'] <= TARGET_FALSE_INFEASIBLE else 'MISSED'
    ok_ff = 'met' if r['false_feasible'] == 0 else 'MISSED'
    lines = [
        '# False-infeasible rate of the motion planner',
        '',
        f'{r["questions"]} random (scene, relocated set, object) questions on {r["scenes"]} '
        f'generated scenes ({m["status"]}; {m["wall_s"]:.0f} s wall, {m["workers"]} worker(s), '
        f'shared machine). Ours: `MotionPlanner`, time limit {OURS_TIME_LIMIT_S:g} s. '
        f'Reference: `ReferencePlanner` {m["reference_config"]}, asked where ours said no; every '
        "feasible motion verified densely (0.01 rad) with the model's own FCL bodies.",
        '',
        '| figure | value | target |',
        '|---|---|---|',
        f'| ours feasible / infeasible / timeouts | {r["ours_feasible"]} / '
        f'{r["ours_infeasible"]} / {r["ours_timeouts"]} | |',
        f'| reference feasible (verified) where ours said no | {r["reference_feasible"]} '
        f'({r["reference_verified"]}) | |',
        f'| **false-infeasible rate** (of ours-infeasible) | '
        f'{r["false_infeasible_rate"]:.1%} ({r["false_infeasible"]}) | ≤ 5 % ({ok_fi}) |',
        f'| false-infeasible over all questions | {r["false_infeasible_rate_all_questions"]:.1%}'
        ' | |',
        f'| **false-feasible** (ours feasible, motion fails verification) | '
        f'{r["false_feasible"]} ({r["false_feasible_rate"]:.1%}) | 0 ({ok_ff}) |',
        f'| infeasible answers naming blockers / blocked by immovable | '
        f'{r["infeasible_with_blockers"]} / {r["blocked_by_immovable"]} | |',
        f'| mean wall per question: ours / reference | {r["ours_s_mean"]:.1f} s / '
        f'{r["reference_s_mean"]:.1f} s | |',
        '',
    ]
    return '\n'.join(lines)


def main() -> int:
    """Ask every question of the planner and of the reference, write the results."""
    args = parse()
    jobs = [scene_questions(i, args.per_scene, args.seed) for i in range(args.scenes)]
    meta = {
        'scenes_requested': args.scenes,
        'per_scene': args.per_scene,
        'workers': args.workers,
        'seed': args.seed,
        'reference_config': REFERENCE_CONFIG,
        'machine': platform.node(),
        'status': 'running',
        'wall_s': 0.0,
    }
    start = time.monotonic()
    answers: list = []
    with tqdm(total=len(jobs) * args.per_scene, desc='questions') as bar:
        if args.workers == 1:
            done = (answer_scene(job) for job in jobs)
        else:
            pool = ProcessPoolExecutor(args.workers)
            done = (f.result() for f in as_completed([pool.submit(answer_scene, j) for j in jobs]))
        for scene_answers in done:
            answers += scene_answers
            bar.update(len(scene_answers))
            meta['wall_s'] = time.monotonic() - start
            write(answers, meta)
    meta['status'] = 'complete'
    result = write(answers, meta)
    print(markdown(result))
    return 0


if __name__ == '__main__':
    sys.exit(main())
