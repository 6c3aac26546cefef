"""Markdown reports: Tables 1-3 (one reading) and the paper sweep (every reading), with the exact
search as its own row, the paper's numbers beside each row and the paper's claims checked.

The reports hold no wall times (those are in the JSON), so the same command on the same planner
writes the same Markdown byte for byte.
"""

from __future__ import annotations

import numpy as np

from qtree_benchmarks.task.paper import PAPER_XI, paper_text
from qtree_benchmarks.task.summary import paper_claims
from qtree_benchmarks.task.variants import Variant

COLUMNS = (
    'episodes to steady state',
    'MP calls (tree edges)',
    'real planner runs',
    '1st optimal episode (reached)',
    'optimal share',
    'converged share',
    'paper (Ep / MP / 1st*)',
)
NAMES = {'H-EG': 'H-εG', 'H-EG-SET': 'H-εG-SET', 'H-EG-SET-PLAIN': 'H-εG-SET-PLAIN'}


def fmt(pair: tuple[float, float] | list[float], digits: int = 0) -> str:
    """``mean ± std``, or ``–`` for nan."""
    mean, std = pair
    return '–' if np.isnan(mean) else f'{mean:.{digits}f} ± {std:.{digits}f}'


def name(policy: str) -> str:
    """The paper's spelling of a policy (H-εG)."""
    return NAMES.get(policy, policy)


def metric_cells(row: dict) -> list[str]:
    """The metric columns of one policy row (see :data:`COLUMNS`)."""
    first = f'{fmt(row["first_optimal"])} ({row["first_optimal_reached"]}/{row["trainings"]})'
    optimal = f'{row["optimal_share"]:.0%}'
    if row['success_share'] < 1.0 or row['policy'] == 'RND':
        optimal += f' (solved {row["success_share"]:.0%})'
    if row.get('fallback_share'):
        optimal += f' (eq. 19 fallback {row["fallback_share"]:.0%})'
    converged = '– (stops at its first target)' if row['policy'] == 'RND' else (
        f'{row["converged_share"]:.0%}')  # fmt: skip
    return [
        fmt(row['episodes']),
        fmt(row['mp_calls']),
        fmt(row['planner_runs_fresh']),
        first,
        optimal,
        converged,
        paper_text(row['scenario'], row['policy']),
    ]


def exact_cells(info: dict) -> list[str]:
    """The metric columns of the exact set search's row."""
    return [
        '– (no episodes)',
        f'– ({info["exact_queries"]} (set, object) queries)',
        str(info['exact_planner_runs']),
        '–',
        '100% (exact)',
        '–',
        '– (not in the paper)',
    ]


def scenario_heading(scenario: str, info: dict) -> str:
    """The section title of a scenario with its exact reference."""
    return (
        f'## {scenario.upper()}: {info["obstacles"]} obstacles, exact optimal level '
        f'{info["level"]} ({" -> ".join(info["sequence"]) or "no solution"}), '
        f'xi_p = {info.get("feasible_sequences", "?")} (paper {PAPER_XI.get(scenario, "?")}), '
        f'xi* = {info.get("optimal_sequences", "?")}, {info["real_planner_runs"]} real planner '
        'runs in this benchmark'
    )


def _table(head: list[str], rows: list[list[str]]) -> list[str]:
    return [
        '| ' + ' | '.join(head) + ' |',
        '|' + '---|' * len(head),
        *('| ' + ' | '.join(cells) + ' |' for cells in rows),
    ]


def _settings(meta: dict) -> str:
    return (
        f'Oracle: {meta["oracle"]}; {meta["trainings"]} seeded trainings per row (seeds '
        f'{meta.get("seed", 0)}..{meta.get("seed", 0) + meta["trainings"] - 1}); alpha = 0.5, '
        f'gamma = 0.9, eps0 = 1, eps_min = 1e-4, Ep_max = {meta["max_episodes"]}, beta = 1e-3.'
    )


def _word(ok: bool) -> str:
    return 'holds' if ok else '**fails**'


def claim_sentences(claim: dict) -> list[str]:
    """The paper's claims for one scenario and reading, with the numbers."""
    e, m, f = claim['episodes'], claim['mp_calls'], claim['first_optimal']
    o = claim['optimal_share']

    def line(values: dict, digits: int = 0) -> str:
        return ', '.join(f'{name(p)} {v:.{digits}f}' for p, v in values.items())

    return [
        f'ordering of episodes (H-εG < H-LRND < LRND) {_word(claim["order_episodes"])}: {line(e)}',
        f'ordering of MP calls (tree edges) {_word(claim["order_mp_calls"])}: {line(m)}',
        f'Fig. 4 (H-εG reaches the optimum first) {_word(claim["fig4"])}: 1st optimal {line(f)}',
        f'Fig. 5 (H-εG reaches the steady state first) {_word(claim["fig5"])}',
        'optimal share: ' + ', '.join(f'{name(p)} {v:.0%}' for p, v in o.items()),
    ]


def markdown(rows: list[dict], meta: dict) -> str:
    """Tables 1-3 for one reading: one table per scenario, exact search as a row, claims."""
    readings = meta['readings']
    lines = [
        '# Q-Tree benchmark (Tables 1-3 of the paper)',
        '',
        _settings(meta),
        f'Readings: H-LRND rule `{readings["hlrnd_rule"]}`, eps coin per '
        f'`{readings["epsilon_coin"]}`, steady window {readings["steady_episodes"]} episodes, '
        f'steady rule `{readings["steady_rule"]}`, β {readings["beta"]:g} '
        '(`scripts/benchmark.py --paper-sweep` shows every reading side by side: '
        '[benchmark_sweep.md](benchmark_sweep.md)).',
        '',
    ]
    for scenario, info in meta['scenarios'].items():
        body = [[name(r['policy']), *metric_cells(r)] for r in rows if r['scenario'] == scenario]
        body.append(['exact set search (BFS, reference)', *exact_cells(info)])
        lines += [scenario_heading(scenario, info), '', *_table(['policy', *COLUMNS], body), '']
    claims = paper_claims(rows)
    if claims:
        lines += ["## The paper's claims on these numbers", '']
        for claim in claims:
            lines.append(f'- {claim["scenario"].upper()}: ' + '; '.join(claim_sentences(claim)))
        lines.append('')
    lines += notes(meta)
    return '\n'.join(lines)


def sweep_markdown(rows: list[dict], meta: dict) -> str:
    """The paper sweep: per scenario every variant in one table, the exact row, the claims per
    reading.
    """
    lines = [
        "# Q-Tree benchmark: every reading of the paper's open points (paper sweep)",
        '',
        _settings(meta),
        'Readings: H-LRND rule `not-failed` (default: "positive reward" read as "not -1", '
        'H-LRND = LRND + target first) or `positive-q` (edges with Q > 0 or untried, all '
        'candidates when none qualifies; also the exploration step of H-εG and H-εG-SET); eps '
        'coin per `step` (default) or per `episode`; steady window: eq. (11) must hold this many '
        'episodes in a row (default 50; 1 is the literal reading); steady rule: eq. (11) also '
        'needs an episode without a new edge (`no-new-edge`, default) or not (`q-bar`); β: '
        "eq. (11)'s threshold (default 0.001). "
        '★ = the default reading (the committed Tables 1-3, [benchmark.md](benchmark.md)).',
        '',
    ]
    head = ['policy', 'H-LRND rule', 'eps coin', 'window', 'steady rule', 'β', *COLUMNS]
    for scenario, info in meta['scenarios'].items():
        body = []
        for r in (r for r in rows if r['scenario'] == scenario):
            star = ' ★' if r['default'] else ''
            window = str(r['steady_episodes'] or '-')
            v = Variant.of_record(r)
            beta = f'{v.beta:g}' if v.beta else '-'
            body.append([name(r['policy']) + star, r['hlrnd_rule'], r['epsilon_coin'], window,
                         v.steady_rule, beta, *metric_cells(r)])  # fmt: skip
        body.append(
            ['exact set search (BFS, reference)', '-', '-', '-', '-', '-', *exact_cells(info)]
        )
        lines += [scenario_heading(scenario, info), '', *_table(head, body), '']
    claims = paper_claims(rows)
    if claims:
        lines += [
            "## The paper's claims under each reading",
            '',
            'Means over the trainings of the rows above; ✓ = the claim holds, ✗ = it does not.',
            '',
        ]
        head = ['scenario', 'H-LRND rule', 'eps coin', 'window', 'steady rule', 'β',
                'episodes LRND / H-LRND / H-εG',
                'MP calls LRND / H-LRND / H-εG', '1st optimal LRND / H-LRND / H-εG',
                'optimal share LRND / H-LRND / H-εG', 'order Ep', 'order MP', 'Fig. 4',
                'Fig. 5']  # fmt: skip
        body = []
        for c in claims:
            star = ' ★' if c['default'] else ''

            def slash(values: dict, pct: bool = False) -> str:
                return ' / '.join(f'{v:.0%}' if pct else f'{v:.0f}' for v in values.values())

            body.append([
                c['scenario'].upper() + star, c['hlrnd_rule'], c['epsilon_coin'],
                str(c['steady_episodes']), c['steady_rule'], f"{c['beta']:g}",
                slash(c['episodes']), slash(c['mp_calls']),
                slash(c['first_optimal']), slash(c['optimal_share'], pct=True),
                *('✓' if c[k] else '✗' for k in ('order_episodes', 'order_mp_calls', 'fig4',
                                                  'fig5')),
            ])  # fmt: skip
        lines += [*_table(head, body), '']
    lines += notes(meta)
    return '\n'.join(lines)


def notes(meta: dict) -> list[str]:
    """Definitions shared by both reports."""
    return [
        '## Definitions',
        '',
        "- MP calls (tree edges): the paper's count, one motion-planner call per new tree edge "
        '(Sect. 3.2.2). Real planner runs: distinct (set, object) pairs one training asked, '
        'i.e. what a fresh motion planner with its set cache (Assumption 2) actually runs; the '
        'heading gives the runs of the whole benchmark (every training shares one memo per '
        'worker).',
        '- Exact set search: breadth-first over sets of relocated obstacles '
        '(`qtree_task_planner.exact`), the reference that scores every training; its planner '
        'runs are those it needs alone (the heading also counts xi_p).',
        '- 1st optimal episode: first episode reaching the target through a sequence of the '
        'exact optimal level (Fig. 4), mean over the trainings that reached it (reached/N). '
        'Without a known optimal level (the ROS action) only the first episode reaching the '
        'learned level is reported, never labelled optimal.',
        '- Optimal share: the extracted sequence (eq. 19) has the exact optimal level. When eq. '
        '(19) finds no sequence although an episode reached the target, the best explored one is '
        'returned (`extraction = best-known-fallback`; its share is shown when not 0).',
        f'- Steady state: eq. (11) with beta = 1e-3 and no new edge for the window of '
        'consecutive episodes; converged share: trainings that reached it before '
        f'Ep_max = {meta["max_episodes"]}. RND stops at its first target-reaching episode, '
        'whose sequence is its answer; "solved" is its success rate within the caps.',
        '- H-εG-SET (ours): H-εG with one node per set of relocated objects (Assumption 2), '
        'optimistic values for untried actions and a Bellman sweep before extraction.',
        '',
    ]
