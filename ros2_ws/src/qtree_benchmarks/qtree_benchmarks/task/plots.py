"""Figures 4 and 5 (bars with std), MP calls, the Q-bar curves and the sweep overview (PNG)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from qtree_task_planner.policies import POLICY_NAMES

from qtree_benchmarks.task.report import name
from qtree_benchmarks.task.variants import DEFAULT_BETA, DEFAULT_STEADY_RULE, Variant


def _pyplot():
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    return plt


def plots(rows: list[dict], records: list[dict], out: Path, prefix: str = '') -> list[str]:
    """Figures 4, 5, MP calls and Q-bar curves of a one-reading run; returns the file names."""
    plt = _pyplot()
    scenarios = sorted({r['scenario'] for r in rows})
    policies = [p for p in POLICY_NAMES if p != 'RND' and any(r['policy'] == p for r in rows)]
    names = []
    for key, title, fname in [
        (
            'first_optimal',
            'Figure 4: first episode reaching the optimum',
            'fig4_first_optimal.png',
        ),
        ('episodes', 'Figure 5: episodes to steady state', 'fig5_episodes.png'),
        ('mp_calls', 'Motion-planner calls (tree edges)', 'mp_calls.png'),
    ]:
        fig, ax = plt.subplots(figsize=(7, 4))
        width = 0.8 / max(1, len(policies))
        for i, policy in enumerate(policies):
            means, stds = [], []
            for scenario in scenarios:
                row = next(
                    (r for r in rows if (r['scenario'], r['policy']) == (scenario, policy)), None
                )
                mean, std = row[key] if row else (np.nan, np.nan)
                means.append(mean)
                stds.append(std)
            x = np.arange(len(scenarios)) + (i - (len(policies) - 1) / 2) * width
            ax.bar(x, means, width, yerr=stds, capsize=3, label=name(policy))
        ax.set_xticks(np.arange(len(scenarios)), [s.upper() for s in scenarios])
        ax.set_ylabel('mean over trainings')
        ax.set_title(title)
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / f'{prefix}{fname}', dpi=120)
        plt.close(fig)
        names.append(f'{prefix}{fname}')
    fig, axes = plt.subplots(1, len(scenarios), figsize=(5 * len(scenarios), 3.5), squeeze=False)
    for ax, scenario in zip(axes[0], scenarios, strict=True):
        for policy in policies:
            rec = next(
                (
                    r
                    for r in records
                    if (r['scenario'], r['policy']) == (scenario, policy) and r['q_bar_curve']
                ),
                None,
            )
            if rec:
                curve = np.asarray(rec['q_bar_curve'])
                ax.plot(curve[:, 0], curve[:, 1], label=name(policy))
        ax.set_title(f'{scenario.upper()}: Q-bar(k), eq. (10), first seed')
        ax.set_xlabel('episode k')
        ax.legend()
    fig.tight_layout()
    fig.savefig(out / f'{prefix}q_bar_curves.png', dpi=120)
    plt.close(fig)
    names.append(f'{prefix}q_bar_curves.png')
    return names


def sweep_plot(rows: list[dict], out: Path, prefix: str = 'sweep_') -> list[str]:
    """Per scenario, episodes / MP calls / first optimal episode of every variant (bars, std),
    the paper's value of the policy as a black tick, the exact search's runs as a dashed line.
    """
    plt = _pyplot()
    scenarios = sorted({r['scenario'] for r in rows})
    # eq. (11)'s default rule and beta only: with every beta and rule a panel has hundreds of
    # bars (benchmark_sweep.md lists them all)
    default_test = (DEFAULT_STEADY_RULE, DEFAULT_BETA)
    learners = [
        r
        for r in rows
        for v in (Variant.of_record(r),)
        if r['policy'] != 'RND' and (v.steady_rule, v.beta) == default_test
    ]
    names = []
    for key, title in [
        ('episodes', 'episodes to steady state'),
        ('mp_calls', 'MP calls (tree edges)'),
        ('first_optimal', '1st optimal episode'),
    ]:
        fig, axes = plt.subplots(
            1, len(scenarios), figsize=(6 * len(scenarios), 7), squeeze=False, sharey=False
        )
        for ax, scenario in zip(axes[0], scenarios, strict=True):
            group = [r for r in learners if r['scenario'] == scenario]
            y = np.arange(len(group))
            means = [r[key][0] for r in group]
            stds = [r[key][1] for r in group]
            colors = ['tab:blue' if r['default'] else 'tab:gray' for r in group]
            ax.barh(y, means, xerr=stds, color=colors, capsize=2)
            index = {'episodes': 0, 'mp_calls': 1, 'first_optimal': 2}[key]
            for i, r in enumerate(group):
                if r['paper']:
                    ax.plot(r['paper'][index], i, marker='|', color='k', markersize=12, mew=2)
            ax.set_yticks(y, [name(r['variant']) for r in group], fontsize=7)
            ax.invert_yaxis()
            ax.set_title(f'{scenario.upper()}: {title}')
        fig.suptitle(
            'Paper sweep, eq. (11) with no new edge, beta 0.001 '
            '(blue = default reading, black tick = the paper)'
        )
        fig.tight_layout()
        fname = f'{prefix}{key}.png'
        fig.savefig(out / fname, dpi=110)
        plt.close(fig)
        names.append(fname)
    return names
