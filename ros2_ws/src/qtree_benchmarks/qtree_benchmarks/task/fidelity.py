"""How close our re-run of Tables 1-3 comes to the paper, cell by cell (#31 items 2-4; no ROS).

A *reading* is one combination of the paper's open points (:mod:`.variants`): the H-LRND rule
(``hlrnd_rule``), the H-εG coin (``epsilon_coin``), the steady window of eq. (11)
(``steady_episodes``), whether eq. (11) also needs an episode without a new edge
(``steady_rule``) and its threshold (``beta``). For a reading, each of the 18 cells (S1-S3 ×
LRND / H-LRND / H-εG × episodes / MP calls) is our mean over the trainings beside the paper's
number (:data:`~.paper.PAPER`), with their ratio; a cell is *close* when the ratio is within
±30 %.
The paper's orderings (LRND > H-LRND > H-εG in episodes, in MP calls and in the first optimal
episode, Fig. 4) are checked per scenario.
"""

from __future__ import annotations

import itertools
from typing import Any

from qtree_benchmarks.task.paper import PAPER, PAPER_POLICIES, PAPER_XI
from qtree_benchmarks.task.variants import (
    EPSILON_COINS,
    HLRND_RULES,
    STEADY_RULES,
    Reading,
    Variant,
)

METRICS = ('episodes', 'mp_calls')  # Tables 1-3 columns compared (index in PAPER's tuples)
CLOSE = 0.30  # a cell is close to the paper when |ours / paper - 1| <= CLOSE [-]
PAPER_XI_STAR = 1  # optimal sequences of each of the paper's scenes (Sect. 4)
PAPER_LEVELS = {'s1': 4, 's2': 5, 's3': 6}


def summary_row(rows: list[dict], scenario: str, policy: str, reading: Reading) -> dict | None:
    """The summary row of ``policy`` on ``scenario`` under ``reading`` (None: not run)."""
    want = Variant.make(policy, *reading)
    for row in rows:
        if row['scenario'] == scenario and Variant.of_record(row) == want:
            return row
    return None


def cells(rows: list[dict], reading: Reading, scenarios: list[str]) -> list[dict]:
    """The cells ``{scenario, policy, metric, ours, paper, ratio}`` of one reading."""
    out = []
    for scenario, policy in itertools.product(scenarios, PAPER_POLICIES):
        row = summary_row(rows, scenario, policy, reading)
        for index, metric in enumerate(METRICS):
            paper = PAPER[(scenario, policy)][index]
            ours = None if row is None else float(row[metric][0])
            ratio = None if ours is None else ours / paper
            out.append(
                {
                    'scenario': scenario.upper(),
                    'policy': policy,
                    'metric': metric,
                    'ours': ours,
                    'paper': paper,
                    'ratio': ratio,
                    'trainings': None if row is None else row['trainings'],
                }
            )
    return out


def close_count(reading_cells: list[dict]) -> int:
    """Cells within ±:data:`CLOSE` of the paper."""
    return sum(
        c['ratio'] is not None and abs(c['ratio'] - 1.0) <= CLOSE + 1e-9 for c in reading_cells
    )


def claims(rows: list[dict], reading: Reading, scenarios: list[str]) -> list[dict]:
    """Each ordering the paper claims, per scenario, and whether it holds under ``reading``.

    Also the optimal share of each policy split into eq. (19)'s own extraction and the
    best-known fallback, and the first-optimal mean with the trainings it averages.
    """
    out = []
    for scenario in scenarios:
        looked_up = {p: summary_row(rows, scenario, p, reading) for p in PAPER_POLICIES}
        found = {p: r for p, r in looked_up.items() if r is not None}
        if len(found) < len(looked_up):
            continue
        for metric in (*METRICS, 'first_optimal'):
            means = [found[p][metric][0] for p in PAPER_POLICIES]
            holds = all(a > b for a, b in itertools.pairwise(means))
            out.append(
                {
                    'scenario': scenario.upper(),
                    'claim': f'{metric}: ' + ' > '.join(PAPER_POLICIES),
                    'holds': bool(holds),
                    'ours': dict(zip(PAPER_POLICIES, means, strict=True)),
                    'first_optimal_trainings': {
                        p: found[p]['first_optimal_reached'] for p in PAPER_POLICIES
                    }
                    if metric == 'first_optimal'
                    else None,
                }
            )
    return out


def optimal_shares(records: list[dict], reading: Reading, scenarios: list[str]) -> list[dict]:
    """Per scenario and policy: trainings, optimal through eq. (19) itself, optimal only through
    the best-known fallback.
    """
    out = []
    for scenario, policy in itertools.product(scenarios, PAPER_POLICIES):
        want = Variant.make(policy, *reading)
        group = [r for r in records if r['scenario'] == scenario and Variant.of_record(r) == want]
        if not group:
            continue
        eq19 = sum(r['optimal'] and r['extraction'] == 'eq19' for r in group)
        fallback = sum(r['optimal'] and r['extraction'] != 'eq19' for r in group)
        out.append(
            {
                'scenario': scenario.upper(),
                'policy': policy,
                'trainings': len(group),
                'eq19_optimal_share': eq19 / len(group),
                'fallback_optimal_share': fallback / len(group),
            }
        )
    return out


def readings_of(rows: list[dict]) -> list[Reading]:
    """Every reading the summary rows cover for all three of the paper's policies."""
    paper_rows = [Variant.of_record(r) for r in rows if r['policy'] in PAPER_POLICIES]
    windows = sorted({v.steady_episodes for v in paper_rows})
    steady_rules = [s for s in STEADY_RULES if s in {v.steady_rule for v in paper_rows}]
    betas = sorted({v.beta for v in paper_rows})
    return [
        reading
        for reading in itertools.product(HLRND_RULES, EPSILON_COINS, windows, steady_rules, betas)
        if all(
            summary_row(rows, s, p, reading) is not None
            for s in {r['scenario'] for r in rows}
            for p in PAPER_POLICIES
        )
    ]


def fidelity_report(data: dict, preset: Reading, default: Reading) -> dict:
    """``paper_fidelity.json`` from a benchmark JSON (``benchmark_sweep.json``).

    Args:
        data: the benchmark JSON (``meta``, ``summary``, ``records``).
        preset: the reading named ``paper`` (:data:`~.variants.READINGS`).
        default: today's default reading, reported beside it.

    Returns:
        ``scenarios`` (``S1``.. -> ``level``, ``xi_p``, ``xi_star`` and the paper's), ``reading``,
        ``cells``, ``cells_within_30pct``, ``claims``, ``optimal_shares``, ``readings`` (every
        reading swept with its close-cell count, best first) and ``default``.
    """
    rows, records = data['summary'], data.get('records', [])
    scenarios = [s for s in ('s1', 's2', 's3') if any(r['scenario'] == s for r in rows)]
    meta_scenes = data['meta']['scenarios']
    counted = sorted(
        ((close_count(cells(rows, r, scenarios)), r) for r in readings_of(rows)),
        key=lambda pair: -pair[0],
    )
    ranked = [{'reading': _named(r), 'cells_within_30pct': n} for n, r in counted]

    def block(reading: Reading) -> dict:
        chosen = cells(rows, reading, scenarios)
        return {
            'reading': _named(reading),
            'cells': chosen,
            'cells_within_30pct': close_count(chosen),
            'claims': claims(rows, reading, scenarios),
            'optimal_shares': optimal_shares(records, reading, scenarios),
        }

    return {
        'scenarios': {
            s.upper(): {
                'level': meta_scenes[s]['level'],
                'xi_p': meta_scenes[s]['feasible_sequences'],
                'xi_star': meta_scenes[s]['optimal_sequences'],
                'paper': {'level': PAPER_LEVELS[s], 'xi_p': PAPER_XI[s], 'xi_star': PAPER_XI_STAR},
            }
            for s in scenarios
        },
        **block(preset),
        'cells_total': len(scenarios) * len(PAPER_POLICIES) * len(METRICS),
        'readings': ranked,
        'default': block(default),
        'trainings': data['meta'].get('trainings'),
    }


def _named(reading: Reading) -> dict[str, Any]:
    rule, coin, window, steady_rule, beta = reading
    return {
        'hlrnd_rule': rule,
        'epsilon_coin': coin,
        'steady_episodes': window,
        'steady_rule': steady_rule,
        'beta': beta,
    }


def markdown(report: dict) -> str:
    """``paper_fidelity.md``: the scenes, the preset's cells and claims, every reading ranked."""
    r = report['reading']
    lines = [
        '# Tables 1-3 against the paper, cell by cell (#31)',
        '',
        f'Generated by `scripts/paper_fidelity.py` from the committed sweep '
        f'({report["trainings"]} trainings per row). Preset `paper`: H-LRND rule '
        f'`{r["hlrnd_rule"]}`, H-εG coin `{r["epsilon_coin"]}`, steady window '
        f'{r["steady_episodes"]}, steady rule `{r["steady_rule"]}`, β {r["beta"]:g}: '
        f'**{report["cells_within_30pct"]} of {report["cells_total"]} '
        f'cells within ±30 %** (target 12). Default reading: '
        f'{report["default"]["cells_within_30pct"]} of {report["cells_total"]}.',
        '',
        '| scene | level (paper) | ξ_p (paper) | ξ* (paper) |',
        '|---|---|---|---|',
    ]
    for name, s in report['scenarios'].items():
        p = s['paper']
        lines.append(
            f'| {name} | {s["level"]} ({p["level"]}) | {s["xi_p"]} ({p["xi_p"]}) '
            f'| {s["xi_star"]} ({p["xi_star"]}) |'
        )
    lines += [
        '',
        '| scene | policy | metric | ours | paper | ours / paper |',
        '|---|---|---|---|---|---|',
    ]
    for c in report['cells']:
        ours = '–' if c['ours'] is None else f'{c["ours"]:.0f}'
        ratio = '–' if c['ratio'] is None else f'{c["ratio"]:.2f}'
        where = f'| {c["scenario"]} | {c["policy"]} | {c["metric"]} '
        lines.append(f'{where}| {ours} | {c["paper"]} | {ratio} |')
    lines += ['', '| scene | claim | holds |', '|---|---|---|']
    lines += [f'| {c["scenario"]} | {c["claim"]} | {c["holds"]} |' for c in report['claims']]
    lines += [
        '',
        '| scene | policy | trainings | optimal by eq. (19) | optimal only by the fallback |',
        '|---|---|---|---|---|',
    ]
    lines += [
        f'| {o["scenario"]} | {o["policy"]} | {o["trainings"]} | {o["eq19_optimal_share"]:.0%} '
        f'| {o["fallback_optimal_share"]:.0%} |'
        for o in report['optimal_shares']
    ]
    lines += [
        '',
        '| H-LRND rule | H-εG coin | steady window | steady rule | β | cells within ±30 % |',
        '|---|---|---|---|---|---|',
    ]
    lines += [
        f'| {x["reading"]["hlrnd_rule"]} | {x["reading"]["epsilon_coin"]} '
        f'| {x["reading"]["steady_episodes"]} | {x["reading"]["steady_rule"]} '
        f'| {x["reading"]["beta"]:g} | {x["cells_within_30pct"]} |'
        for x in report['readings']
    ]
    return '\n'.join(lines) + '\n'
