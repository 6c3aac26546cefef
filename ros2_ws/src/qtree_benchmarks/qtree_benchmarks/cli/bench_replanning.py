"""Replanning benchmark (#32 item 6): a world change in the middle of a retrieval, in process.

For each scenario (S1-S3 and generated clutter of 10-20 objects) the retrieval is learned once
with BLOCKER-SEARCH on the in-process motion planner (its cache is the planner's cache before
the change); then, per event and run (seed), the world changes before a random relocation and
the retrieval is recovered as the ROS graph does it (new planner, answers carried over, rest
re-planned): :mod:`qtree_benchmarks.task.replanning`.

Usage: ``python scripts/bench_replanning.py [--scenarios s1 s2 s3 gen10 gen15 gen20] [--runs 4]``
(env.sh sourced). Writes ``benchmarks/results/replanning.json`` (rows ``{scenario, event, runs,
retrieved, replans_mean, extra_planner_runs_mean, reused_answers_share, recovery_s_median}``,
then every run), ``.md`` and ``.png``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import re
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from statistics import median

from qtree_scene.exceptions import ScenarioError
from qtree_scene.generator import generate_clutter
from qtree_scene.scenario import load_scenario
from tqdm import tqdm

from qtree_benchmarks.paths import repo_root
from qtree_benchmarks.task.clutter import make_planner
from qtree_benchmarks.task.replanning import EVENTS, learn, run_event, summary_rows

ROOT = repo_root()
OUT = ROOT / 'benchmarks' / 'results'
GENERATED = re.compile(r'^gen(\d+)$')
DENSITY = 0.2  # footprint density of the generated scenes [-]
TARGETS = {
    'retrieved_share_min': 0.95,
    'collisions_max': 0,
    'recovery_s_median_max': 2.0,
    'reused_share_one_object_min': 0.5,
}
# The events that touch one object (the reuse target's); the target moved counts since a moved
# target no longer drops every answer (its own go, the others' are kept by the same rules).
ONE_OBJECT_EVENTS = ('moved_into_path', 'moved_out_of_way', 'object_added', 'target_moved')


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line options of ``argv`` (``sys.argv[1:]`` when None)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        '--scenarios', nargs='+', default=['s1', 's2', 's3', 'gen10', 'gen15', 'gen20']
    )
    parser.add_argument('--events', nargs='+', default=list(EVENTS), choices=EVENTS)
    parser.add_argument('--runs', type=int, default=4, help='runs (seeds) per scenario and event')
    parser.add_argument('--output', type=Path, default=OUT / 'replanning.json')
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error('--runs must be >= 1')
    for name in args.scenarios:
        if not GENERATED.match(name):
            try:
                load_scenario(name)
            except (ScenarioError, OSError) as err:
                parser.error(f'--scenarios: {name!r}: {err}')
    return args


def learned_scene(name: str, max_seeds: int = 8):
    """(planner, sequence, first training) of a named or generated (``gen<N>``) scene whose
    retrieval BLOCKER-SEARCH finds; generated scenes try seeds 0, 1, … until one is found.
    """
    match = GENERATED.match(name)
    candidates = (
        (generate_clutter(int(match.group(1)), DENSITY, seed) for seed in range(max_seeds))
        if match
        else iter([load_scenario(name)])
    )
    for scenario in candidates:
        planner = make_planner(scenario)
        obstacles = [o.id for o in scenario.obstacles]
        result = learn(planner, (), obstacles, scenario.target.id)
        if result.status == 'optimal':
            return planner, result.sequence, result
    raise RuntimeError(f'{name}: no retrievable scene found')


def markdown(data: dict) -> str:
    """The Markdown report of the benchmark ``data``."""
    lines = [
        '# Replanning after a world change (#32 item 6)',
        '',
        f'{data["date_utc"]}, commit {data["commit"][:10]}, load {data["load_1min"]}. '
        'In process (no ROS): recovery = new planner + answers carried over + re-plan, from the '
        "event to the next relocation's motion ready; the ROS graph adds the arm's stop, its "
        'undo motion and DDS. Collisions: the verifier run again in the new scene on every kept '
        'answer and every relocation executed after the event.',
        '',
        '| scenario | event | runs | retrieved | replans | extra planner runs | reused share '
        '| recovery median [s] |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for r in data['rows']:
        retrieved = '–' if r['retrieved'] is None else f'{r["retrieved"]:.0%}'
        lines.append(
            f'| {r["scenario"]} | {r["event"]} | {r["runs"]} | {retrieved} | {r["replans_mean"]} '
            f'| {r["extra_planner_runs_mean"]} | {r["reused_answers_share"]:.0%} '
            f'| {r["recovery_s_median"]:.2f} |'
        )
    t = data['targets']
    lines += ['', '## Targets', '']
    for key, value in t.items():
        lines.append(f'- {key}: {value}')
    return '\n'.join(lines) + '\n'


def plot(data: dict, path: Path) -> None:
    """Plot the replanning figures of ``data`` to the PNG ``path``."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    import numpy as np

    rows = data['rows']
    scenarios = list(dict.fromkeys(r['scenario'] for r in rows))
    events = list(dict.fromkeys(r['event'] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    width = 0.8 / len(events)
    for i, event in enumerate(events):
        by = {r['scenario']: r for r in rows if r['event'] == event}
        x = np.arange(len(scenarios)) + i * width
        axes[0].bar(x, [by[s]['recovery_s_median'] if s in by else 0 for s in scenarios], width,
                    label=event)  # fmt: skip
        axes[1].bar(x, [by[s]['reused_answers_share'] if s in by else 0 for s in scenarios],
                    width, label=event)  # fmt: skip
    for ax, title in zip(
        axes,
        ('median recovery [s] (event to next motion ready)', 'answers kept / cached'),
        strict=True,
    ):
        ax.set_xticks(np.arange(len(scenarios)) + 0.4 - width / 2, scenarios)
        ax.set_title(title)
    axes[0].axhline(TARGETS['recovery_s_median_max'], color='k', ls='--', lw=1, label='target')
    axes[1].axhline(TARGETS['reused_share_one_object_min'], color='k', ls='--', lw=1)
    axes[0].legend(fontsize=8)
    fig.suptitle('Recovery after a world change in the middle of a retrieval (in process)')
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def targets_met(outcomes: list, rows: list[dict]) -> dict:
    """Whether each target of #32 item 6 is met by the ``outcomes`` and ``rows``."""
    possible = [o for o in outcomes if o.solvable]
    one_object = [o for o in outcomes if o.event in ONE_OBJECT_EVENTS]
    retrieved = sum(o.retrieved for o in possible) / len(possible) if possible else None
    reused = sum(o.reused_share for o in one_object) / len(one_object) if one_object else None
    collisions = sum(o.violations for o in outcomes)
    recovery = median(o.recovery_s for o in outcomes)
    return {
        'retrieved_share': retrieved,
        'retrieved_share_met': retrieved is not None
        and retrieved >= TARGETS['retrieved_share_min'],
        'collisions': collisions,
        'collisions_met': collisions == 0,
        'recovery_s_median': recovery,
        'recovery_met': recovery <= TARGETS['recovery_s_median_max'],
        'reused_share_one_object': reused,
        'reused_met': reused is not None and reused >= TARGETS['reused_share_one_object_min'],
        # pooled: all kept answers / all cached answers of those runs (the share above is the
        # mean of the per-run shares)
        'reused_of_cached_one_object': [
            sum(o.reused for o in one_object),
            sum(o.cached for o in one_object),
        ],
        'kept_infeasible_answers': sum(o.kept_infeasible for o in outcomes),
        'kept_infeasible_answered_otherwise_afresh': sum(
            o.kept_infeasible_differ for o in outcomes
        ),
        'kept_harder': sum(o.kept_harder for o in outcomes),
        'kept_harder_feasible_afresh': sum(o.kept_harder_feasible_afresh for o in outcomes),
        'kept_harder_reason_differs': sum(o.kept_harder_reason_differs for o in outcomes),
        # the answers dropped on those runs, by why (answer_reuse.judge)
        'dropped_one_object_by': dict(
            sum((Counter(o.dropped_by) for o in one_object), Counter()).most_common()
        ),
        'unsolvable_after_event': sum(o.solvable is False for o in outcomes),
        'undecided_after_event': sum(o.solvable is None for o in outcomes),
        'solvable_decided_by': dict(Counter(o.decided_by for o in outcomes)),
    }


def main(argv: list[str] | None = None) -> int:
    """Run the replanning benchmark; exit code 0 when it finished."""
    args = parse_args(argv)
    outcomes, skipped, scenes = [], [], {}
    total = len(args.scenarios) * len(args.events) * args.runs
    with tqdm(total=total, desc='replanning runs') as bar:
        for name in args.scenarios:
            started = time.perf_counter()
            planner, sequence, first = learned_scene(name)
            scenes[name] = {
                'scene': planner.scenario.name,
                'objects': len(planner.scenario.obstacles) + 1,
                'sequence': list(sequence),
                'first_training_planner_runs': first.planner_runs,
                'first_training_s': round(time.perf_counter() - started, 1),
                'cached_answers': len(planner.cache),
            }
            for event in args.events:
                for seed in range(args.runs):
                    outcome = run_event(planner, sequence, event, seed, make_planner)
                    if outcome is None:
                        skipped.append({'scenario': name, 'event': event, 'seed': seed})
                    else:
                        outcomes.append(dataclasses.replace(outcome, scenario=name))
                    bar.update()
    rows = summary_rows(outcomes)
    commit = subprocess.run(
        ['git', 'rev-parse', 'HEAD'], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    data = {
        'date_utc': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
        'commit': commit,
        'machine': f'{platform.machine()}, {os.cpu_count()} cores',
        'load_1min': round(os.getloadavg()[0], 2),
        'mode': 'in process (no ROS), BLOCKER-SEARCH, recovery = planning part only',
        'rows': rows,
        'targets': {**TARGETS, **targets_met(outcomes, rows)},
        'scenes': scenes,
        'skipped': skipped,
        'runs': [dataclasses.asdict(o) | {'reused_share': o.reused_share} for o in outcomes],
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(data, indent=2) + '\n')
    args.output.with_suffix('.md').write_text(markdown(data))
    plot(data, args.output.with_suffix('.png'))
    print(markdown(data))
    print(f'written {args.output} (.md, .png)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
