"""Statistics per (scenario, variant) and the paper's claims checked against them."""

from __future__ import annotations

from typing import Any

import numpy as np
from qtree_task_planner.policies import EPSILON_COINS, HLRND_RULES, POLICY_NAMES
from qtree_task_planner.training import STEADY_RULES

from qtree_benchmarks.task.paper import PAPER, PAPER_POLICIES
from qtree_benchmarks.task.variants import NOT_APPLICABLE, Variant


def mean_std(values: list[float]) -> tuple[float, float]:
    """(mean, std) of the values, (nan, nan) when empty."""
    if not values:
        return float('nan'), float('nan')
    array = np.asarray(values, dtype=float)
    return float(array.mean()), float(array.std())


def summarize(records: list[dict]) -> list[dict]:
    """Mean and std per (scenario, variant), in scenario then table order.

    Row keys: scenario, policy, variant (label), hlrnd_rule, epsilon_coin, steady_episodes,
    steady_rule, beta, default, trainings, episodes, mp_calls (tree edges), planner_runs_fresh
    (real planner runs of one training with a fresh set-cached planner), first_optimal,
    first_optimal_reached, optimal_share, success_share, converged_share, fallback_share (eq. 19
    found none), wall_time_s, paper (Ep, MP, 1st*) or None. Pairs are (mean, std).
    """
    groups: dict[tuple[str, Variant], list[dict]] = {}
    for record in records:
        groups.setdefault((record['scenario'], Variant.of_record(record)), []).append(record)

    def order(key: tuple[str, Variant]) -> tuple:
        scenario, v = key
        rules, coins = (NOT_APPLICABLE, *HLRND_RULES), (NOT_APPLICABLE, *EPSILON_COINS)
        steady = (NOT_APPLICABLE, *STEADY_RULES)
        return (scenario, POLICY_NAMES.index(v.policy), rules.index(v.hlrnd_rule),
                coins.index(v.epsilon_coin), -v.steady_episodes, steady.index(v.steady_rule),
                v.beta)  # fmt: skip

    rows = []
    for scenario, variant in sorted(groups, key=order):
        group = groups[(scenario, variant)]
        firsts = [r['first_optimal_episode'] for r in group if r['first_optimal_episode'] > 0]
        rows.append(
            {
                'scenario': scenario,
                'policy': variant.policy,
                'variant': variant.label,
                'hlrnd_rule': variant.hlrnd_rule,
                'epsilon_coin': variant.epsilon_coin,
                'steady_episodes': variant.steady_episodes,
                'steady_rule': variant.steady_rule,
                'beta': variant.beta,
                'default': variant.is_default,
                'trainings': len(group),
                'episodes': mean_std([r['episodes'] for r in group]),
                'mp_calls': mean_std([r['mp_calls'] for r in group]),
                'planner_runs_fresh': mean_std([r['planner_runs_fresh'] for r in group]),
                'first_optimal': mean_std(firsts),
                'first_optimal_reached': len(firsts),
                'optimal_share': sum(r['optimal'] for r in group) / len(group),
                'success_share': sum(bool(r['sequence']) for r in group) / len(group),
                'converged_share': sum(r['converged'] for r in group) / len(group),
                'fallback_share': sum(r.get('extraction') == 'best-known-fallback' for r in group)
                / len(group),
                'wall_time_s': mean_std([r['wall_time_s'] for r in group]),
                'paper': PAPER.get((scenario, variant.policy)),
            }
        )
    return rows


def _find(rows: list[dict], scenario: str, policy: str, **readings: Any) -> dict | None:
    for row in rows:
        if row['scenario'] != scenario or row['policy'] != policy:
            continue
        variant = Variant.of_record(row)  # rows written before a reading existed: its default
        known = {k: getattr(variant, k) for k in readings}
        if all(known[k] == v for k, v in readings.items() if known[k] not in (NOT_APPLICABLE, 0)):
            return row
    return None


def paper_claims(rows: list[dict]) -> list[dict]:
    """The paper's claims, checked for each scenario and each combination of readings.

    Claims: episodes and MP calls decrease LRND > H-LRND > H-eG (Tables 1-3), H-eG reaches the
    optimum first (Fig. 4) and reaches the steady state in the fewest episodes (Fig. 5).

    Returns:
        One dict per (scenario, rule, coin, window) with the three rows' means: keys scenario,
        hlrnd_rule, epsilon_coin, steady_episodes, episodes / mp_calls / first_optimal (policy ->
        mean), optimal_share (policy -> share), and the booleans order_episodes, order_mp_calls,
        fig4, fig5.
    """
    out = []
    combos = {
        (r['scenario'], v.hlrnd_rule, v.epsilon_coin, v.steady_episodes, v.steady_rule, v.beta)
        for r in rows
        if r['policy'] == 'H-EG'
        for v in (Variant.of_record(r),)
    }

    def order(c: tuple) -> tuple:
        return (c[0], HLRND_RULES.index(c[1]), EPSILON_COINS.index(c[2]), -c[3],
                STEADY_RULES.index(c[4]), c[5])  # fmt: skip

    for scenario, rule, coin, window, steady_rule, beta in sorted(combos, key=order):
        readings = {
            'hlrnd_rule': rule,
            'epsilon_coin': coin,
            'steady_episodes': window,
            'steady_rule': steady_rule,
            'beta': beta,
        }
        found = {p: _find(rows, scenario, p, **readings) for p in PAPER_POLICIES}
        picked = {p: row for p, row in found.items() if row is not None}
        if len(picked) < len(found):
            continue
        claim: dict[str, Any] = {
            'scenario': scenario,
            **readings,
            'default': all(row['default'] for row in picked.values()),
        }
        for key in ('episodes', 'mp_calls', 'first_optimal'):
            claim[key] = {p: row[key][0] for p, row in picked.items()}
        claim['optimal_share'] = {p: row['optimal_share'] for p, row in picked.items()}
        lrnd, hlrnd, heg = PAPER_POLICIES
        for key in ('episodes', 'mp_calls'):
            v = claim[key]
            claim[f'order_{key}'] = bool(v[heg] < v[hlrnd] < v[lrnd])
        first = claim['first_optimal']
        claim['fig4'] = bool(first[heg] < min(first[lrnd], first[hlrnd]))
        claim['fig5'] = bool(
            claim['episodes'][heg] < min(claim['episodes'][p] for p in (lrnd, hlrnd))
        )
        out.append(claim)
    return out
