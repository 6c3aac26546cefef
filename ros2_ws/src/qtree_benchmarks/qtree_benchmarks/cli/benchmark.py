"""Reproduce Tables 1-3 and Figures 4-5 of the paper: Q-Tree policies on scenarios s1..s3.

Every row: episodes to the steady state, MP calls as the paper counts them (tree edges), the real
planner runs of one training (distinct (set, object) pairs), the first optimal episode, the
optimal and converged shares, the paper's numbers beside; the exact set search is its own row.
The logic lives in ``qtree_benchmarks.task``; this script parses flags and writes files.

Readings of the paper's open points (named options; the defaults are the committed tables'):
  --hlrnd-rule not-failed|positive-q  H-LRND's "positive reward": not -1 (default; keeps
                                      optimality) or Q > 0 edge weight (falls back to all
                                      candidates when none qualifies)
  --epsilon-coin step|episode         H-eG's explore/exploit coin per step (default) or episode
  --steady-episodes N                 steady-state window of eq. (11) (default 50)

Usage:
    python scripts/benchmark.py                       # Tables 1-3: benchmarks/results/benchmark.*
    python scripts/benchmark.py --paper-sweep         # every reading: benchmark_sweep.*
    python scripts/benchmark.py --trainings 5 --scenarios s1 --policies H-EG H-EG-SET --tag dev
    python scripts/benchmark.py --oracle synthetic    # synthetic tables (development only)
    python scripts/benchmark.py --ray auto            # on a Ray cluster (pip install ray)
    python scripts/benchmark.py --from-json benchmarks/results/benchmark_sweep.json
                                                      # Tables 1-3 from the sweep's default rows
    python scripts/benchmark_readme.py                # README table from the committed JSON
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from qtree_task_planner.policies import EPSILON_COINS, HLRND_RULES, POLICY_NAMES
from qtree_task_planner.training import STEADY_RULES

from qtree_benchmarks.paths import repo_root
from qtree_benchmarks.task.derive import select
from qtree_benchmarks.task.paper import PAPER_POLICIES
from qtree_benchmarks.task.plots import plots, sweep_plot
from qtree_benchmarks.task.report import markdown, sweep_markdown
from qtree_benchmarks.task.runner import Task, reference, run_all
from qtree_benchmarks.task.summary import paper_claims, summarize
from qtree_benchmarks.task.variants import (
    DEFAULT_BETA,
    DEFAULT_COIN,
    DEFAULT_RULE,
    DEFAULT_STEADY_RULE,
    DEFAULT_WINDOW,
    READINGS,
    SWEEP_BETAS,
    SWEEP_POLICIES,
    SWEEP_STEADY_RULES,
    SWEEP_WINDOWS,
    Variant,
    sweep_variants,
)

REPO = repo_root()
RESULTS = REPO / 'benchmarks' / 'results'
POLICIES = POLICY_NAMES
DEFAULT_POLICIES = ('RND', *PAPER_POLICIES, 'H-EG-SET')


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Flags; bad values end with a usage message (exit code 2)."""
    parser = argparse.ArgumentParser(
        description=__doc__.split('\n')[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument('--trainings', type=int, default=50, help='trainings per row')
    parser.add_argument('--scenarios', nargs='+', default=['s1', 's2', 's3'])
    parser.add_argument(
        '--policies',
        nargs='+',
        choices=POLICIES,
        default=None,
        help="default: RND, the paper's three and H-EG-SET",
    )
    parser.add_argument(
        '--hlrnd-rule',
        choices=HLRND_RULES,
        default=DEFAULT_RULE,
        help='H-LRND reading (also the exploration of H-EG*)',
    )
    parser.add_argument(
        '--epsilon-coin',
        choices=EPSILON_COINS,
        default=DEFAULT_COIN,
        help='H-EG coin per step or per episode',
    )
    parser.add_argument(
        '--steady-episodes',
        '--steady-window',
        type=int,
        default=DEFAULT_WINDOW,
        dest='steady_episodes',
        help='consecutive episodes eq. (11) must hold',
    )
    parser.add_argument(
        '--steady-rule',
        choices=STEADY_RULES,
        default=DEFAULT_STEADY_RULE,
        help="eq. (11) with no new edge in the episode ('no-new-edge') or alone ('q-bar')",
    )
    parser.add_argument(
        '--beta', type=float, default=DEFAULT_BETA, help="eq. (11)'s threshold (default 1e-3)"
    )
    parser.add_argument(
        '--reading',
        choices=sorted(READINGS),
        help='a named reading: sets --hlrnd-rule, --epsilon-coin, --steady-episodes, '
        "--steady-rule and --beta ('paper': the sweep's closest to the paper's tables, see "
        'paper_fidelity.md)',
    )
    parser.add_argument(
        '--paper-sweep',
        action='store_true',
        help='every combination of readings, one table per scenario '
        '(writes benchmark_sweep.*; --hlrnd-rule/--epsilon-coin ignored)',
    )
    parser.add_argument(
        '--sweep-windows',
        nargs='+',
        type=int,
        default=list(SWEEP_WINDOWS),
        help='steady windows of the sweep',
    )
    parser.add_argument(
        '--sweep-steady-rules',
        nargs='+',
        choices=STEADY_RULES,
        default=list(SWEEP_STEADY_RULES),
        help='steady rules of the sweep',
    )
    parser.add_argument(
        '--sweep-betas',
        nargs='+',
        type=float,
        default=list(SWEEP_BETAS),
        help='betas of the sweep',
    )
    parser.add_argument('--workers', type=int, default=os.cpu_count() or 1)
    parser.add_argument(
        '--ray',
        metavar='ADDRESS',
        help="Ray cluster address ('auto', 'ray://host:10001'), or 'local' to "
        'start a private instance with --workers CPUs (pip install ray)',
    )
    parser.add_argument(
        '--ros',
        action='store_true',
        help='through the ROS graph (starts sim, motion planner, task planner)',
    )
    parser.add_argument('--oracle', choices=['planner', 'synthetic'], default='planner')
    parser.add_argument('--max-episodes', type=int, default=5000, help='Ep_max')
    parser.add_argument(
        '--rnd-time-limit-s',
        type=float,
        default=60.0,
        help='cap of one RND run [s] (besides Ep_max)',
    )
    parser.add_argument('--seed', type=int, default=0, help='seed of the first training')
    parser.add_argument(
        '--from-json',
        type=Path,
        metavar='JSON',
        help='no training: write the tables of the selected rows from an earlier run '
        '(e.g. the default Tables 1-3 from benchmark_sweep.json)',
    )
    parser.add_argument('--out', type=Path, default=RESULTS)
    parser.add_argument(
        '--tag', default='', help='names the outputs benchmark_TAG.* and TAG_*.png'
    )
    args = parser.parse_args(argv)
    if args.reading:
        explicit = {
            '--hlrnd-rule',
            '--epsilon-coin',
            '--steady-episodes',
            '--steady-window',
            '--steady-rule',
            '--beta',
        }
        if explicit & {a.split('=')[0] for a in (argv if argv is not None else sys.argv[1:])}:
            parser.error('--reading sets the readings: give it or the reading flags, not both')
        reading = READINGS[args.reading]
        args.hlrnd_rule, args.epsilon_coin, args.steady_episodes = reading[:3]
        args.steady_rule, args.beta = reading[3:]
    if min(args.trainings, args.workers, args.max_episodes, args.steady_episodes) <= 0:
        parser.error('--trainings, --workers, --max-episodes, --steady-episodes must be > 0')
    if min(args.sweep_windows) <= 0:
        parser.error('--sweep-windows must be > 0')
    if not (args.beta > 0.0 and min(args.sweep_betas) > 0.0):
        parser.error('--beta and --sweep-betas must be > 0')
    if args.seed < 0:
        parser.error('--seed must be >= 0')
    if args.ros and (args.oracle != 'planner' or args.ray):
        parser.error('--ros uses the real motion planner node; no --oracle synthetic or --ray')
    if args.ros and (
        args.paper_sweep
        or args.hlrnd_rule != DEFAULT_RULE
        or args.epsilon_coin != DEFAULT_COIN
        or args.steady_rule != DEFAULT_STEADY_RULE
    ):
        parser.error('--ros runs the default readings only (the action has no reading fields)')
    args.tag = args.tag.strip('_') or ('sweep' if args.paper_sweep else '')
    return args


def variants_of(args: argparse.Namespace) -> list[Variant]:
    """The rows to train: the sweep, or one reading for every policy."""
    if args.paper_sweep:
        return sweep_variants(
            tuple(args.policies or SWEEP_POLICIES),
            tuple(args.sweep_windows),
            tuple(args.sweep_steady_rules),
            tuple(args.sweep_betas),
        )
    policies = args.policies or DEFAULT_POLICIES
    reading = (args.hlrnd_rule, args.epsilon_coin, args.steady_episodes, args.steady_rule)
    return list(dict.fromkeys(Variant.make(p, *reading, args.beta) for p in policies))


def tasks_of(args: argparse.Namespace, variants: list[Variant], meta: dict) -> list[Task]:
    """One task per scenario, variant and seed (the first seed keeps its Q-bar curve)."""
    return [
        Task(
            name,
            v.policy,
            args.seed + i,
            args.oracle,
            meta['scenarios'][name]['level'],
            args.max_episodes,
            args.rnd_time_limit_s,
            # the Q-bar curves plotted; of a sweep only the default's
            keep_curve=i == 0 and (v.is_default or not args.paper_sweep),
            **{k: val for k, val in v.training_kwargs().items() if k != 'policy'},
        )
        for name in args.scenarios
        for v in variants
        for i in range(args.trainings)
    ]


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark, write JSON + Markdown + PNG, print the report; exit code."""
    args = parse_args(argv)
    started = time.monotonic()
    meta: dict[str, Any] = {
        'oracle': args.oracle,
        'trainings': args.trainings,
        'max_episodes': args.max_episodes,
        'seed': args.seed,
        'steady_episodes': args.steady_episodes,
        'readings': {
            'hlrnd_rule': args.hlrnd_rule,
            'epsilon_coin': args.epsilon_coin,
            'steady_episodes': args.steady_episodes,
            'steady_rule': args.steady_rule,
            'beta': args.beta,
        },
        'paper_sweep': args.paper_sweep,
        'workers': args.workers,
        'scenarios': {},
    }
    if args.paper_sweep:
        meta['readings'] = {
            'sweep_windows': args.sweep_windows,
            'sweep_steady_rules': args.sweep_steady_rules,
            'sweep_betas': args.sweep_betas,
        }
    if args.from_json is not None:
        return write_from_json(args, meta)
    warm, refs = {}, {}
    for name in args.scenarios:
        info, shared = reference(name, args.oracle)
        print(
            f'{name}: exact level {info["level"]} {info["sequence"]} '
            f'({info["exact_planner_runs"]} planner runs, {info["exact_queries"]} queries; '
            f'{shared.planner_runs} with the counts, {info["reference_time_s"]:.1f} s)'
        )
        meta['scenarios'][name] = info
        warm[name] = shared.results
        refs[name] = shared.planner_runs
    tasks = tasks_of(args, variants_of(args), meta)
    if args.ros:
        from qtree_benchmarks.task.ros_runner import run_ros

        meta['oracle'] = 'planner (through the ROS graph)'
        records = run_ros(tasks)
    else:
        records = run_all(tasks, args.workers, args.oracle, warm, args.ray)
    for name in args.scenarios:
        extra = sum(r['planner_runs_real'] for r in records if r['scenario'] == name)
        meta['scenarios'][name]['real_planner_runs'] = refs[name] + extra
    meta['wall_time_s'] = time.monotonic() - started
    return write_outputs(args, meta, records)


def write_from_json(args: argparse.Namespace, meta: dict) -> int:
    """``--from-json``: the selected rows' records of an earlier run, written like a new run."""
    try:
        data = json.loads(args.from_json.read_text())
        records, meta['scenarios'] = select(data, variants_of(args), args.scenarios)
    except (OSError, ValueError, KeyError) as err:
        print(f'benchmark.py: error: --from-json {args.from_json}: {err}', file=sys.stderr)
        return 2
    if data['meta'].get('trainings') != args.trainings:
        print("benchmark.py: error: --trainings differs from the JSON's", file=sys.stderr)
        return 2
    meta['derived_from'] = str(args.from_json)
    return write_outputs(args, meta, records)


def dumps_with_one_record_per_line(data: dict) -> str:
    """JSON of a run: meta, summary and claims indented, each training record on one line (a
    sweep holds tens of thousands; indented, they made most of a 7 MB file).
    """
    head = {k: v for k, v in data.items() if k != 'records'}
    text = json.dumps(head, indent=1, default=str)
    lines = [json.dumps(r, default=str, separators=(',', ':')) for r in data['records']]
    records = '[\n' + ',\n'.join(lines) + '\n ]' if lines else '[]'
    return text[:-2] + f',\n "records": {records}\n}}\n' if head else f'{{"records": {records}}}\n'


def write_outputs(args: argparse.Namespace, meta: dict, records: list[dict]) -> int:
    """Write JSON + Markdown + PNG of a run and print the report; exit code 0."""
    rows = summarize(records)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f'benchmark_{args.tag}' if args.tag else 'benchmark'
    data = {'meta': meta, 'summary': rows, 'claims': paper_claims(rows), 'records': records}
    (args.out / f'{stem}.json').write_text(dumps_with_one_record_per_line(data))
    report = sweep_markdown(rows, meta) if args.paper_sweep else markdown(rows, meta)
    (args.out / f'{stem}.md').write_text(report)
    prefix = f'{args.tag}_' if args.tag else ''
    if args.paper_sweep:
        sweep_plot(rows, args.out, prefix)
    else:
        plots(rows, records, args.out, prefix)
    print(report)
    print(f'wrote {args.out / stem}.json/.md and the plots')
    return 0


if __name__ == '__main__':
    sys.exit(main())
