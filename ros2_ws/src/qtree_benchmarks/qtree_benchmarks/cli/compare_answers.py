r"""Dump, and compare, every motion-planner answer the exact search asks on S1-S3.

Runs the exact breadth-first search of ``tests/test_scenario_levels.py`` with the in-process
planner, then writes every ``(relocated set, object) -> (feasible, reason)`` answer it asked, and
the optimal levels, to JSON. With ``--keys`` the answers of another dump's keys are also asked, so
two dumps (e.g. before / after a planner change) compare on the same questions.

Example:
    ./qtree run python scripts/compare_answers.py --out /tmp/after.json --keys /tmp/before.json
    ./qtree run python scripts/compare_answers.py --compare /tmp/before.json /tmp/after.json \
        --json benchmarks/results/hand_model_answers.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tqdm import tqdm

SCENES = ('s1', 's2', 's3')


def _key(relocated: frozenset[str], object_id: str) -> str:
    return ','.join(sorted(relocated)) + '|' + object_id


def dump(out: Path, keys_from: Path | None) -> None:
    """Ask the exact search's questions (and ``keys_from``'s) and write the answers."""
    from qtree_scene.scenario import load_scenario
    from qtree_task_planner.exact import solve_exact
    from qtree_task_planner.oracle import MotionPlannerOracle

    extra = json.loads(keys_from.read_text()) if keys_from else {}
    data: dict[str, dict] = {}
    for name in SCENES:
        scenario = load_scenario(name)
        oracle = MotionPlannerOracle(scenario)
        obstacles = tuple(o.id for o in scenario.obstacles)
        solution = solve_exact(obstacles, scenario.target.id, oracle)
        for key in tqdm(extra.get(name, {}).get('answers', {}), desc=f'{name} extra keys'):
            relocated, object_id = key.split('|')
            oracle.feasible(tuple(r for r in relocated.split(',') if r), object_id)
        answers = {
            _key(k[0], k[1]): [bool(r.feasible), r.reason.name]
            for k, r in oracle.planner.cache._results.items()
        }
        data[name] = {'level': solution.level, 'sequence': list(solution.sequence)}
        data[name]['answers'] = answers
        print(f'{name}: level {solution.level}, {len(answers)} answers', flush=True)
    out.write_text(json.dumps(data, indent=1, sort_keys=True))


def compare(before: Path, after: Path, out: Path | None = None) -> None:
    """Print (and with ``out`` write as JSON) the answers that changed between two dumps."""
    a, b = json.loads(before.read_text()), json.loads(after.read_text())
    summary = {}
    for name in SCENES:
        old, new = a[name]['answers'], b[name]['answers']
        common = sorted(set(old) & set(new))
        feasible = [k for k in common if old[k][0] != new[k][0]]
        reason = [k for k in common if old[k][0] == new[k][0] and old[k][1] != new[k][1]]
        print(
            f'{name}: level {a[name]["level"]} -> {b[name]["level"]}; {len(common)} common '
            f'answers, {len(feasible)} feasibility changes, {len(reason)} reason-only changes'
        )
        for k in feasible + reason:
            print(f'  {k}: {old[k]} -> {new[k]}')
        summary[name] = {
            'level_before': a[name]['level'],
            'level_after': b[name]['level'],
            'answers': len(common),
            'feasibility_changes': len(feasible),
            'reason_changes': len(reason),
            'changed': {k: [old[k], new[k]] for k in feasible + reason},
        }
    if out is not None:
        out.write_text(json.dumps(summary, indent=1, sort_keys=True) + '\n')


def main(argv: list[str] | None = None) -> int:
    """Entry point: ``--out`` dumps, ``--compare BEFORE AFTER`` compares."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--out', type=Path, help='write the answers to this JSON file')
    parser.add_argument('--keys', type=Path, help='also ask the questions of this dump')
    parser.add_argument('--compare', nargs=2, type=Path, metavar=('BEFORE', 'AFTER'))
    parser.add_argument('--json', type=Path, help='with --compare: write the changes here')
    args = parser.parse_args(argv)
    if args.compare:
        before, after = args.compare
        compare(before, after, args.json)
    elif args.out:
        dump(args.out, args.keys)
    else:
        parser.error('give --out or --compare')
    return 0


if __name__ == '__main__':
    sys.exit(main())
