#!/usr/bin/env python3
"""Reproduce Tables 1-3 and Figures 4-5 of the paper: Q-Tree policies on scenarios s1..s3.

For each scenario the parent first runs the exact BFS over sets (the reference that scores every
training) on the real in-process motion planner; its (set, object) answers are shipped to the
workers, and each worker keeps one memo per scenario that persists across its trainings, so the
planner runs only for (set, object) pairs nobody asked before. Reported per training: episodes to
the steady state, MP calls as the paper counts them (tree edges), the first optimal episode, and
the planner runs a fresh planner with a set cache would need for that training alone; per
scenario: the real planner runs this benchmark needed in total.

Usage:
    python scripts/benchmark.py                       # 50 trainings, every policy, s1..s3
    python scripts/benchmark.py --trainings 5 --scenarios s1 --policies H-EG H-EG-SET
    python scripts/benchmark.py --oracle synthetic    # synthetic tables (development only)
    python scripts/benchmark.py --ray auto            # on a Ray cluster (pip install ray)
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / 'benchmarks' / 'results'
POLICIES = ('RND', 'LRND', 'H-LRND', 'H-EG', 'H-EG-SET', 'H-EG-SET-PLAIN')
PAPER = {  # Tables 1-3: (episodes to steady state, MP calls, first optimal episode)
    ('s1', 'LRND'): (144, 42, 20),
    ('s1', 'H-LRND'): (119, 37, 18),
    ('s1', 'H-EG'): (115, 34, 16),
    ('s2', 'LRND'): (1079, 236, 96),
    ('s2', 'H-LRND'): (1007, 218, 77),
    ('s2', 'H-EG'): (717, 188, 74),
    ('s3', 'LRND'): (3496, 665, 181),
    ('s3', 'H-LRND'): (2868, 588, 160),
    ('s3', 'H-EG'): (1189, 331, 156),
}
PAPER_RND = {'s1': 'optimal in about 60 % of 50 trials', 's2': 'not solved', 's3': 'not solved'}
PAPER_XI = {'s1': 10, 's2': 20, 's3': 20}  # feasible target sequences xi_p (Sect. 4)

# -- oracles shared inside one process ---------------------------------------------------------


class SharedOracle:
    """Per-process feasibility memo of one scenario, backed by the real planner on a miss.

    Attributes:
        results: (frozenset(relocated), object) -> feasible.
        planner_runs: real planner runs made by this process.
    """

    def __init__(self, scenario: str, kind: str, results: dict | None = None) -> None:
        self.scenario = scenario
        self.kind = kind
        self.results: dict = dict(results or {})
        self.planner_runs = 0
        self._inner: Any = None

    def _backend(self) -> Any:
        if self._inner is None:
            if self.kind == 'synthetic':
                from qtree_task_planner.oracle import TableOracle
                from qtree_task_planner.synthetic import synthetic_scenario

                self._inner = TableOracle(synthetic_scenario(self.scenario)[1])
            else:
                from qtree_task_planner.oracle import MotionPlannerOracle

                self._inner = MotionPlannerOracle(self.scenario)
        return self._inner

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        key = (frozenset(relocated), object_id)
        if key not in self.results:
            self.results[key] = bool(self._backend().feasible(tuple(relocated), object_id))
            self.planner_runs += 1
        return self.results[key]


def scenario_ids(name: str, kind: str) -> tuple[tuple[str, ...], str]:
    """(obstacle ids, target id) of a scenario."""
    if kind == 'synthetic':
        from qtree_task_planner.synthetic import synthetic_scenario

        return tuple(synthetic_scenario(name)[0]), 'T'
    from qtree_scene.scenario import load_scenario

    scenario = load_scenario(name)
    return tuple(o.id for o in scenario.obstacles), scenario.target.id


_ORACLES: dict[str, SharedOracle] = {}


def _init_worker(kind: str, warm: dict[str, dict]) -> None:
    for name, results in warm.items():
        _ORACLES[name] = SharedOracle(name, kind, results)


@dataclass(frozen=True)
class Task:
    """One training: scenario, policy, seed and the settings shared by all."""

    scenario: str
    policy: str
    seed: int
    kind: str
    optimal_level: int
    max_episodes: int
    rnd_time_limit_s: float
    keep_curve: bool = False
    steady_episodes: int = 50


def run_task(task: Task) -> dict:
    """Run one training in this process; returns a JSON-ready record."""
    from qtree_task_planner.oracle import MemoOracle
    from qtree_task_planner.training import TrainingConfig, train

    shared = _ORACLES.setdefault(task.scenario, SharedOracle(task.scenario, task.kind))
    runs_before = shared.planner_runs
    obstacles, target = scenario_ids(task.scenario, task.kind)
    config = TrainingConfig(
        policy=task.policy,
        seed=task.seed,
        max_episodes=task.max_episodes,
        optimal_level=task.optimal_level or None,
        time_limit_s=task.rnd_time_limit_s if task.policy == 'RND' else None,
        steady_episodes=task.steady_episodes,
    )
    oracle = MemoOracle(shared)  # counts the distinct (set, object) pairs of this training
    result = train((*obstacles, target), target, oracle, config)
    q_bar = [s.q_bar for s in result.history]
    step = max(1, len(q_bar) // 200)
    return {
        'scenario': task.scenario,
        'policy': result.policy,
        'seed': task.seed,
        'sequence': list(result.sequence),
        'level': len(result.sequence),
        'optimal': bool(result.sequence) and len(result.sequence) == task.optimal_level,
        'episodes': result.episodes,
        'mp_calls': result.mp_calls,
        'planner_runs_fresh': result.planner_runs,
        'planner_runs_real': shared.planner_runs - runs_before,
        'first_optimal_episode': result.first_optimal_episode,
        'converged': result.converged,
        'stop_reason': result.stop_reason,
        'wall_time_s': result.wall_time_s,
        'q_bar_curve': [[i + 1, q_bar[i]] for i in range(0, len(q_bar), step)]
        if task.keep_curve
        else [],
    }


# -- statistics and reports ----------------------------------------------------------------------


def _mean_std(values: list[float]) -> tuple[float, float]:
    if not values:
        return float('nan'), float('nan')
    array = np.asarray(values, dtype=float)
    return float(array.mean()), float(array.std())


def summarize(records: list[dict]) -> list[dict]:
    """Mean and std per (scenario, policy)."""
    rows = []
    keys = sorted(
        {(r['scenario'], r['policy']) for r in records}, key=lambda k: (k[0], POLICIES.index(k[1]))
    )
    for scenario, policy in keys:
        group = [r for r in records if (r['scenario'], r['policy']) == (scenario, policy)]
        firsts = [r['first_optimal_episode'] for r in group if r['first_optimal_episode'] > 0]
        rows.append(
            {
                'scenario': scenario,
                'policy': policy,
                'trainings': len(group),
                'episodes': _mean_std([r['episodes'] for r in group]),
                'mp_calls': _mean_std([r['mp_calls'] for r in group]),
                'first_optimal': _mean_std(firsts),
                'first_optimal_reached': len(firsts),
                'optimal_share': sum(r['optimal'] for r in group) / len(group),
                'success_share': sum(bool(r['sequence']) for r in group) / len(group),
                'converged_share': sum(r['converged'] for r in group) / len(group),
                'planner_runs_fresh': _mean_std([r['planner_runs_fresh'] for r in group]),
                'wall_time_s': _mean_std([r['wall_time_s'] for r in group]),
                'paper': PAPER.get((scenario, policy)),
            }
        )
    return rows


def _fmt(pair: tuple[float, float], digits: int = 0) -> str:
    mean, std = pair
    return '–' if np.isnan(mean) else f'{mean:.{digits}f} ± {std:.{digits}f}'


def markdown(rows: list[dict], meta: dict) -> str:
    """The report: Tables 1-3 in the paper's format next to the paper's numbers."""
    lines = [
        '# Q-Tree benchmark (Tables 1-3 of the paper)',
        '',
        f'Oracle: {meta["oracle"]}; {meta["trainings"]} trainings per policy; alpha=0.5, '
        f'gamma=0.9, eps0=1, eps_min=1e-4, Ep_max={meta["max_episodes"]}, beta=1e-3 held for '
        f'{meta["steady_episodes"]} '
        f'episodes; wall time {meta["wall_time_s"]:.0f} s on {meta["workers"]} worker(s).',
        '',
    ]
    for scenario, info in meta['scenarios'].items():
        lines += [
            f'## {scenario}: {info["obstacles"]} obstacles, exact optimal level {info["level"]} '
            f'({" -> ".join(info["sequence"]) or "no solution"}), '
            f'xi_p = {info.get("feasible_sequences", "?")} (paper {PAPER_XI.get(scenario, "?")}), '
            f'xi* = {info.get("optimal_sequences", "?")}, '
            f'{info["real_planner_runs"]} real planner runs in total '
            f'(exact reference and counts: {info["reference_time_s"]:.1f} s)',
            '',
            '| policy | episodes to steady state | MP calls | 1st optimal episode | paper '
            '(Ep / MP / 1st*) | optimal share | converged | planner runs / training | time [s] |',
            '|---|---|---|---|---|---|---|---|---|',
        ]
        for row in (r for r in rows if r['scenario'] == scenario):
            paper = row['paper']
            paper_text = ' / '.join(map(str, paper)) if paper else 'ours (not in the paper)'
            if row['policy'] == 'RND':
                paper_text = PAPER_RND[scenario]
            elif row['policy'] == 'H-EG-SET-PLAIN':
                paper_text = 'ablation: H-EG-SET without optimism'
            first = (
                f'{_fmt(row["first_optimal"])} ({row["first_optimal_reached"]}/{row["trainings"]})'
            )
            lines.append(
                f'| {row["policy"]} | {_fmt(row["episodes"])} | {_fmt(row["mp_calls"])} | {first} '
                f'| {paper_text} | {row["optimal_share"]:.0%} (solved {row["success_share"]:.0%}) '
                f'| {row["converged_share"]:.0%} | {_fmt(row["planner_runs_fresh"])} '
                f'| {_fmt(row["wall_time_s"], 2)} |'
            )
        lines.append('')
    lines += [
        'RND stops at its first episode that reaches the target (its "episodes" column is that '
        'episode); "solved" is its success rate within the caps.',
        f'Steady state: eq. (11) with beta = 1e-3 and no new edge for {meta["steady_episodes"]} '
        'consecutive episodes. '
        'Level = sequence length with the target. H-EG-SET (ours): H-eG with one node per set '
        'of relocated objects (Assumption 2), optimistic values for untried actions and a '
        'Bellman sweep before extraction; H-EG-SET-PLAIN: without the optimism (ablation).',
        "MP calls = tree edges (the paper's count); planner runs / training = distinct "
        '(set, object) pairs the training asked (what a fresh planner with a set cache would '
        'run).',
        '',
    ]
    return '\n'.join(lines)


def plots(rows: list[dict], records: list[dict], out: Path, prefix: str = '') -> list[str]:
    """Figures 4 and 5 (bars with std) and the Q-bar curves; returns the file names."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    scenarios = sorted({r['scenario'] for r in rows})
    policies = [p for p in POLICIES if p != 'RND' and any(r['policy'] == p for r in rows)]
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
            ax.bar(x, means, width, yerr=stds, capsize=3, label=policy)
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
                ax.plot(curve[:, 0], curve[:, 1], label=policy)
        ax.set_title(f'{scenario.upper()}: Q-bar(k), eq. (10), first seed')
        ax.set_xlabel('episode k')
        ax.legend()
    fig.tight_layout()
    fig.savefig(out / f'{prefix}q_bar_curves.png', dpi=120)
    plt.close(fig)
    names.append(f'{prefix}q_bar_curves.png')
    return names


# -- driver --------------------------------------------------------------------------------------


def reference(name: str, kind: str) -> tuple[dict, SharedOracle]:
    """Exact optimum and sequence counts of a scenario (parent process)."""
    from qtree_task_planner.exact import count_feasible_sequences, solve_exact
    from qtree_task_planner.exceptions import SearchLimitExceededError

    shared = SharedOracle(name, kind)
    obstacles, target = scenario_ids(name, kind)
    start = time.monotonic()
    solution = solve_exact(obstacles, target, shared)
    info = {
        'obstacles': len(obstacles),
        'level': solution.level,
        'sequence': list(solution.sequence),
        'exact_queries': solution.queries,
    }
    try:
        counts = count_feasible_sequences(obstacles, target, shared, max_sets=4000)
        info.update(
            feasible_sequences=counts.feasible,
            optimal_sequences=counts.optimal,
            reachable_sets=counts.reachable_sets,
        )
    except SearchLimitExceededError:
        info.update(feasible_sequences='> budget', optimal_sequences='?')
    info['reference_time_s'] = time.monotonic() - start
    return info, shared


def run_all(
    tasks: list,
    workers: int,
    kind: str,
    warm: dict,
    ray_address: str | None,
    fn=None,
    desc: str = 'trainings',
):
    """Run the tasks (in-process, process pool or Ray) with a progress bar.

    ``fn`` (default :func:`run_task`) runs one task in a worker; it must be importable by name
    (``scripts/bench_scale.py`` passes ``qtree_task_planner.bench_scale.run_scene``).
    """
    from tqdm import tqdm

    fn = fn or run_task

    if ray_address:
        try:
            import ray
        except ImportError:
            sys.exit("--ray needs the 'ray' package: pip install 'ray[default]'")
        if ray_address == 'local':  # start a private local instance with --workers CPUs
            ray.init(num_cpus=workers, include_dashboard=False)
        else:
            ray.init(address=ray_address)
        remote = ray.remote(_ray_task)
        refs = [remote.remote(task, warm, fn) for task in tasks]
        out = []
        with tqdm(total=len(refs), desc=desc) as bar:
            while refs:
                done, refs = ray.wait(refs)
                out += ray.get(done)
                bar.update(len(done))
        return out
    if workers <= 1:
        _init_worker(kind, warm)
        return [fn(t) for t in tqdm(tasks, desc=desc)]
    with ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(kind, warm)) as pool:
        return list(tqdm(pool.map(fn, tasks, chunksize=1), total=len(tasks), desc=desc))


def run_ros(tasks: list[Task], timeout_s: float = 3600.0) -> list[dict]:
    """Run the trainings through the ROS graph: one sim + motion planner + task planner per
    scenario, goals sent one after the other (the planner's cache persists across them)."""
    import rclpy
    from orchestration import allocate_domain_id, start_node, stop_all
    from qtree_msgs.action import RetrieveTarget
    from qtree_msgs.msg import TrainingStats
    from rclpy.action import ActionClient
    from rclpy.executors import SingleThreadedExecutor
    from tqdm import tqdm

    os.environ['ROS_DOMAIN_ID'] = str(allocate_domain_id())
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    rclpy.init()
    node = rclpy.create_node('qtree_benchmark')
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    stats: list = []
    node.create_subscription(TrainingStats, '/training_stats', stats.append, 10_000)
    client = ActionClient(node, RetrieveTarget, '/retrieve_target')

    def wait(future) -> None:
        deadline = time.monotonic() + timeout_s
        while not future.done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        if not future.done():
            raise TimeoutError('no answer from /retrieve_target')

    records = []
    bar = tqdm(total=len(tasks), desc='trainings (ROS)')
    try:
        for scenario in dict.fromkeys(t.scenario for t in tasks):
            procs = [
                start_node('jaco2_sim', 'sim_node', parameters={'scenario': scenario}),
                start_node('stpik_motion_planner', 'motion_planner_node'),
                start_node('qtree_task_planner', 'task_planner_node'),
            ]
            try:
                for proc in procs:
                    proc.wait_for_log('ready', timeout_s=120.0)
                client.wait_for_server(timeout_sec=30.0)
                for task in (t for t in tasks if t.scenario == scenario):
                    stats.clear()
                    goal = RetrieveTarget.Goal(
                        policy=task.policy,
                        seed=task.seed,
                        max_episodes=task.max_episodes,
                        steady_episodes=task.steady_episodes,
                    )
                    sent = client.send_goal_async(goal)
                    wait(sent)
                    done = sent.result().get_result_async()
                    wait(done)
                    result = done.result().result
                    deadline = time.monotonic() + 5.0
                    while len(stats) < result.episodes and time.monotonic() < deadline:
                        executor.spin_once(timeout_sec=0.05)
                    first = next(
                        (
                            s.episode
                            for s in stats
                            if s.reached_target and len(s.episode_sequence) == task.optimal_level
                        ),
                        -1,
                    )
                    records.append(
                        {
                            'scenario': scenario,
                            'policy': task.policy,
                            'seed': task.seed,
                            'sequence': list(result.sequence),
                            'level': len(result.sequence),
                            'optimal': len(result.sequence) == task.optimal_level,
                            'episodes': result.episodes,
                            'mp_calls': result.mp_calls,
                            'planner_runs_fresh': result.planner_runs,
                            'planner_runs_real': result.planner_runs,
                            'first_optimal_episode': first,
                            'converged': result.converged,
                            'stop_reason': result.message,
                            'wall_time_s': result.training_time,
                            'q_bar_curve': [
                                [s.episode, s.q_bar] for s in stats[:: max(1, len(stats) // 200)]
                            ],
                        }
                    )
                    bar.update(1)
            finally:
                stop_all(procs)
    finally:
        bar.close()
        node.destroy_node()
        rclpy.try_shutdown()
    return records


def _ray_task(task: Task, warm: dict, fn=None) -> dict:
    if fn is not None and fn is not run_task:
        return fn(task)
    if task.scenario not in _ORACLES:
        _init_worker(task.kind, {task.scenario: warm.get(task.scenario, {})})
    return run_task(task)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--trainings', type=int, default=50, help='trainings per policy')
    parser.add_argument('--scenarios', nargs='+', default=['s1', 's2', 's3'])
    parser.add_argument(
        '--policies',
        nargs='+',
        default=list(POLICIES[:5]),
        choices=POLICIES,
        help="default: the paper's four and H-EG-SET",
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
    parser.add_argument(
        '--steady-episodes', type=int, default=50, help='consecutive episodes eq. (11) must hold'
    )
    parser.add_argument('--seed', type=int, default=0, help='seed of the first training')
    parser.add_argument('--out', type=Path, default=RESULTS)
    parser.add_argument('--tag', default='', help='suffix of the output file names')
    args = parser.parse_args(argv)
    if min(args.trainings, args.workers, args.max_episodes, args.steady_episodes) <= 0:
        parser.error('--trainings, --workers, --max-episodes, --steady-episodes must be > 0')
    if args.ros and (args.oracle != 'planner' or args.ray):
        parser.error('--ros uses the real motion planner node; no --oracle synthetic or --ray')
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    started = time.monotonic()
    meta: dict[str, Any] = {
        'steady_episodes': args.steady_episodes,
        'oracle': args.oracle,
        'trainings': args.trainings,
        'max_episodes': args.max_episodes,
        'workers': args.workers,
        'scenarios': {},
    }
    warm, refs = {}, {}
    for name in args.scenarios:
        info, shared = reference(name, args.oracle)
        print(
            f'{name}: exact level {info["level"]} {info["sequence"]} '
            f'({shared.planner_runs} planner runs, {info["reference_time_s"]:.1f} s)'
        )
        meta['scenarios'][name] = info
        warm[name] = shared.results
        refs[name] = shared.planner_runs
    tasks = [
        Task(
            name,
            policy,
            args.seed + i,
            args.oracle,
            meta['scenarios'][name]['level'],
            args.max_episodes,
            args.rnd_time_limit_s,
            keep_curve=i == 0,
            steady_episodes=args.steady_episodes,
        )
        for name in args.scenarios
        for policy in args.policies
        for i in range(args.trainings)
    ]
    if args.ros:
        meta['oracle'] = 'planner (through the ROS graph)'
        records = run_ros(tasks)
    else:
        records = run_all(tasks, args.workers, args.oracle, warm, args.ray)
    for name in args.scenarios:
        extra = sum(r['planner_runs_real'] for r in records if r['scenario'] == name)
        meta['scenarios'][name]['real_planner_runs'] = refs[name] + extra
    meta['wall_time_s'] = time.monotonic() - started
    rows = summarize(records)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f'benchmark{args.tag}'
    (args.out / f'{stem}.json').write_text(
        json.dumps({'meta': meta, 'summary': rows, 'records': records}, indent=1, default=str)
    )
    report = markdown(rows, meta)
    (args.out / f'{stem}.md').write_text(report)
    plots(rows, records, args.out, f'{args.tag.lstrip("_")}_' if args.tag else '')
    print(report)
    return 0


if __name__ == '__main__':
    sys.exit(main())
