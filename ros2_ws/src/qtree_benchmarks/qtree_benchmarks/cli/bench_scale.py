"""Scale benchmark (issue #14): exact set search, H-eG, H-EG-SET and BLOCKER-SEARCH on generated
clutter of 10-50 obstacles; writes benchmarks/results/scale.json, scale.md and scale.png.

The work lives in ``qtree_benchmarks.task.scale``; tasks (one per scene) run through
``qtree_benchmarks.task.runner.run_all`` like ``scripts/benchmark.py`` (in process,
``--workers`` processes, or ``--ray``).

Usage:
    python scripts/bench_scale.py                          # real planner, full grid, one core
    python scripts/bench_scale.py --oracle synthetic --workers 2
    python scripts/bench_scale.py --n 10 20 --scenes 2 --methods exact BLOCKER-SEARCH
    python scripts/bench_scale.py --merge part_a.json part_b.json   # one report from runs in parts
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from qtree_scene.generator import LAYOUTS
from stpik_motion_planner.grasps import GRASP_FAMILIES, check_families

from qtree_benchmarks.cli.benchmark import RESULTS
from qtree_benchmarks.task.runner import run_all
from qtree_benchmarks.task.scale import (
    METHODS,
    ScaleTask,
    markdown,
    plot,
    run_scene,
    scene_total,
    summarize,
)

NOTES = [
    'planner runs = distinct (set, object) pairs a method asked (a fresh planner with a set '
    'cache); wall = its own computing time plus the recorded planning time of those pairs. '
    'optimal: level equal to the exact search where it finished, else to the optimum or lower '
    'bound BLOCKER-SEARCH certified (sound blocker sets, Assumption 2, monotone feasibility); '
    'scenes where the exact search proved that no sequence exists count as optimal for a method '
    'that returned none. Every search has a budget; "budget hit" is the share of scenes where it '
    'stopped on it (learners: Ep_max or their time cap).',
]


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line options of ``argv`` (``sys.argv[1:]`` when None)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--n', type=int, nargs='+', default=[10, 20, 30, 50], help='obstacles N')
    parser.add_argument('--densities', type=float, nargs='+', default=[0.15, 0.3])
    parser.add_argument('--scenes', type=int, default=10, help='seeded scenes per (N, density)')
    parser.add_argument('--seed', type=int, default=0, help='seed of the first scene')
    parser.add_argument('--methods', nargs='+', default=list(METHODS), choices=METHODS)
    parser.add_argument('--oracle', choices=['planner', 'synthetic'], default='planner')
    parser.add_argument(
        '--layouts',
        type=_names(LAYOUTS, '--layouts'),
        default=('accessible',),
        help=f'comma-separated generator layouts ({", ".join(LAYOUTS)})',
    )
    parser.add_argument(
        '--grasp-families',
        type=_grasp_families,
        default=('side',),
        help=f'comma-separated grasp families of the planner ({", ".join(GRASP_FAMILIES)}; '
        "side: the paper's)",
    )
    parser.add_argument('--workers', type=int, default=1, help='processes (default: one core)')
    parser.add_argument('--ray', metavar='ADDRESS', help="Ray address, or 'local'")
    parser.add_argument('--exact-max-runs', type=int, default=3000)
    parser.add_argument('--exact-time-s', type=float, default=60.0)
    parser.add_argument('--learner-episodes', type=int, default=5000)
    parser.add_argument('--learner-time-s', type=float, default=10.0)
    parser.add_argument('--search-max-runs', type=int, default=3000)
    parser.add_argument('--search-time-s', type=float, default=120.0)
    parser.add_argument('--out', type=Path, default=RESULTS)
    parser.add_argument('--tag', default='', help='suffix of the output file names')
    parser.add_argument(
        '--merge', type=Path, nargs='+', metavar='JSON', help='write one report from earlier runs'
    )
    args = parser.parse_args(argv)
    positive = (
        min(args.n) >= 0
        and min(args.scenes, args.workers, args.exact_max_runs, args.search_max_runs) > 0
        and args.learner_episodes > 0
        and min(args.exact_time_s, args.learner_time_s, args.search_time_s) > 0
    )
    if not positive:
        parser.error('--n must be >= 0; counts, budgets and --workers must be > 0')
    if not all(0.0 < d <= 0.4 for d in args.densities):
        parser.error('--densities must be in (0, 0.4]')
    return args


def _names(known: tuple[str, ...], flag: str):
    """Argparse type: a comma-separated list of names out of ``known``, without repeats."""

    def parse(text: str) -> tuple[str, ...]:
        names = tuple(n.strip() for n in text.split(',') if n.strip())
        unknown = [n for n in names if n not in known]
        if not names or unknown or len(set(names)) != len(names):
            raise argparse.ArgumentTypeError(
                f'{flag}: {text!r}: expected distinct names out of {", ".join(known)}'
            )
        return names

    return parse


def _grasp_families(text: str) -> tuple[str, ...]:
    """Argparse type of ``--grasp-families``: the planner's own check (:func:`check_families`)."""
    try:
        return check_families([n.strip() for n in text.split(',') if n.strip()])
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'--grasp-families: {text!r}: {err}') from None


def merged(paths: list[Path]) -> tuple[list[dict], dict]:
    """Records and meta of earlier runs' JSON files (same oracle and budgets required).

    Raises:
        SystemExit: a file is missing, not a scale report, or its settings differ.
    """
    records: list[dict] = []
    metas = []
    for path in paths:
        try:
            payload = json.loads(path.read_text())
            records += payload['records']
            metas.append(payload['meta'])
        except (OSError, ValueError, KeyError, TypeError) as err:
            sys.exit(f'--merge: {path} is not a bench_scale JSON report ({err})')
    fixed = ('wall_time_s', 'scenes')
    if any(
        {k: v for k, v in m.items() if k not in fixed}
        != {k: v for k, v in metas[0].items() if k not in fixed}
        for m in metas
    ):
        sys.exit('--merge: the reports were run with different oracles, workers or budgets')
    meta = {**metas[0], 'wall_time_s': sum(m['wall_time_s'] for m in metas)}  # parts' sum
    counts = sorted({m['scenes'] for m in metas}, reverse=True)
    if len(counts) > 1:  # e.g. fewer scenes at N = 50: say which N got how many
        per_n = {n: m['scenes'] for m, p in zip(metas, paths, strict=True) for n in _sizes(p)}
        meta['scenes'] = ', '.join(
            f'{c} (N = {_join(n for n in per_n if per_n[n] == c)})' for c in counts
        )
    meta['merged_from'] = [p.name for p in paths]
    return records, meta


def _sizes(path: Path) -> list[int]:
    return sorted({r['n_obstacles'] for r in json.loads(path.read_text())['records']})


def _join(values) -> str:
    return ', '.join(str(v) for v in sorted(values))


def write(records: list[dict], meta: dict, out: Path, stem: str) -> None:
    """scale{tag}.json / .md / .png from the per-scene records."""
    rows = summarize(records)
    out.mkdir(parents=True, exist_ok=True)
    payload = {'meta': meta, 'rows': rows, 'records': records}
    (out / f'{stem}.json').write_text(json.dumps(payload, indent=1, default=str))
    report = markdown(rows, {**meta, 'records': records})
    (out / f'{stem}.md').write_text(report)
    plot(rows, out / f'{stem}.png')
    print(report)


BUDGETS = (  # the ScaleTask budgets the command line sets, also written to the meta
    'exact_max_runs',
    'exact_time_s',
    'learner_episodes',
    'learner_time_s',
    'search_max_runs',
    'search_time_s',
)


def budgets(args: argparse.Namespace) -> dict[str, Any]:
    """Every method's budget from the parsed command line, by :class:`ScaleTask` field."""
    return {name: getattr(args, name) for name in BUDGETS}


def main(argv: list[str] | None = None) -> int:
    """Run (or merge) the scale benchmark, write ``scale*.json/.md/.png``."""
    args = parse_args(argv)
    if args.merge:
        records, meta = merged(args.merge)
        write(records, meta, args.out, f'scale{args.tag}')
        return 0
    started = time.monotonic()
    tasks = [
        ScaleTask(
            n_obstacles=n,
            density=density,
            seed=args.seed + i,
            oracle=args.oracle,
            methods=tuple(args.methods),
            layout=layout,
            grasp_families=args.grasp_families,
            **budgets(args),
        )
        for layout in args.layouts
        for n in args.n
        for density in args.densities
        for i in range(args.scenes)
    ]
    per_scene = run_all(tasks, args.workers, args.oracle, {}, args.ray, run_scene, 'scenes')
    records = [r for scene in per_scene for r in scene]
    meta = {
        'oracle': args.oracle,
        'layouts': list(args.layouts),
        'grasp_families': list(args.grasp_families),
        'too_wide_grasps': scene_total(records, 'too_wide_grasps'),
        'top_grasps': scene_total(records, 'top_grasps'),
        'side_grasps': scene_total(records, 'side_grasps'),
        'scenes': args.scenes,
        'workers': args.workers,
        **budgets(args),
        'wall_time_s': time.monotonic() - started,
        'notes': NOTES,
    }
    write(records, meta, args.out, f'scale{args.tag}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
