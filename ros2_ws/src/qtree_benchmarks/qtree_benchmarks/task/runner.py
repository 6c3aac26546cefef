"""Scenario oracles, the exact reference and the trainings of the benchmark (no ROS import).

For each scenario the parent first runs the exact BFS over sets (the reference that scores every
training) on the real in-process motion planner; its (set, object) answers are shipped to the
workers, and each worker keeps one memo per scenario that persists across its trainings, so the
planner runs only for (set, object) pairs nobody asked before. Executors: in-process, a process
pool, or Ray; every training is seeded, so the executor changes no figure.
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

from qtree_benchmarks.task.variants import Variant

# The planner's own limit (2 s) makes answers depend on the machine's load: a check that times
# out on a busy machine is infeasible there and feasible on an idle one. The benchmark asks for the
# geometric answer, so it gives every check this long and fails loudly on a timeout.
PLANNING_TIME_LIMIT_S = 300.0
TIMEOUT_REASON = 301  # RelocateObject.TIMEOUT


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
                from qtree_task_planner.testing import synthetic_scenario

                self._inner = TableOracle(synthetic_scenario(self.scenario)[1])
            else:
                from qtree_scene.scenario import load_scenario
                from stpik_motion_planner.config import PlannerConfig
                from stpik_motion_planner.planner import MotionPlanner

                config = PlannerConfig(time_limit_s=PLANNING_TIME_LIMIT_S)
                self._inner = MotionPlanner(load_scenario(self.scenario), config)
        return self._inner

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Answer from the memo or run the planner once for this (set, object).

        Raises:
            RuntimeError: the planner timed out (the answer would depend on the machine's load).
        """
        key = (frozenset(relocated), object_id)
        if key not in self.results:
            backend = self._backend()
            if self.kind == 'synthetic':
                answer = backend.feasible(tuple(relocated), object_id)
            else:
                result = backend.check(object_id, list(relocated))
                if int(result.reason) == TIMEOUT_REASON:
                    raise RuntimeError(
                        f'{self.scenario}: planning {object_id!r} after {sorted(relocated)} timed '
                        f'out after {PLANNING_TIME_LIMIT_S} s; the benchmark needs geometric '
                        'answers'
                    )
                answer = result.feasible
            self.results[key] = bool(answer)
            self.planner_runs += 1
        return self.results[key]


def scenario_ids(name: str, kind: str) -> tuple[tuple[str, ...], str]:
    """(obstacle ids, target id) of a scenario (``kind``: ``'planner'`` or ``'synthetic'``)."""
    if kind == 'synthetic':
        from qtree_task_planner.testing import synthetic_scenario

        return tuple(synthetic_scenario(name)[0]), 'T'
    from qtree_scene.scenario import load_scenario

    scenario = load_scenario(name)
    return tuple(o.id for o in scenario.obstacles), scenario.target.id


_ORACLES: dict[str, SharedOracle] = {}


def init_worker(kind: str, warm: dict[str, dict]) -> None:
    """Process-pool initializer: one warm memo per scenario."""
    for name, results in warm.items():
        _ORACLES[name] = SharedOracle(name, kind, results)


@dataclass(frozen=True)
class Task:
    """One training: scenario, variant (policy and readings), seed and the shared settings."""

    scenario: str
    policy: str
    seed: int
    kind: str
    optimal_level: int
    max_episodes: int
    rnd_time_limit_s: float
    keep_curve: bool = False
    steady_episodes: int = 50
    hlrnd_rule: str = 'not-failed'
    epsilon_coin: str = 'step'
    steady_rule: str = 'no-new-edge'
    beta: float = 1e-3

    @property
    def variant(self) -> Variant:
        """The task's variant (readings that do not apply blanked)."""
        return Variant.make(
            self.policy,
            self.hlrnd_rule,
            self.epsilon_coin,
            self.steady_episodes,
            self.steady_rule,
            self.beta,
        )


def run_task(task: Task) -> dict:
    """Run one training in this process; returns a JSON-ready record."""
    from qtree_task_planner.oracle import MemoOracle
    from qtree_task_planner.training import TrainingConfig, train

    shared = _ORACLES.setdefault(task.scenario, SharedOracle(task.scenario, task.kind))
    runs_before = shared.planner_runs
    obstacles, target = scenario_ids(task.scenario, task.kind)
    variant = task.variant
    config = TrainingConfig(
        seed=task.seed,
        max_episodes=task.max_episodes,
        optimal_level=task.optimal_level or None,
        time_limit_s=task.rnd_time_limit_s if task.policy == 'RND' else None,
        **variant.training_kwargs(),
    )
    oracle = MemoOracle(shared)  # counts the distinct (set, object) pairs of this training
    result = train((*obstacles, target), target, oracle, config)
    q_bar = [s.q_bar for s in result.history]
    step = max(1, len(q_bar) // 200)
    return training_record(
        task,
        policy=result.policy,
        sequence=result.sequence,
        extraction=result.extraction,
        episodes=result.episodes,
        mp_calls=result.mp_calls,
        planner_runs_fresh=result.planner_runs,
        planner_runs_real=shared.planner_runs - runs_before,
        first_optimal_episode=result.first_optimal_episode,
        first_learned_level_episode=result.first_learned_level_episode,
        converged=result.converged,
        stop_reason=result.stop_reason,
        wall_time_s=result.wall_time_s,
        q_bar_curve=[[i + 1, q_bar[i]] for i in range(0, len(q_bar), step)]
        if task.keep_curve
        else [],
    )


def training_record(task: Task, *, policy: str, sequence: Any, **fields: Any) -> dict:
    """The JSON record of one training, the same keys in process and through ROS.

    Args:
        task: the training's task (scenario, variant, seed, optimal level).
        policy: the policy that trained.
        sequence: the extracted sequence (the target last; empty: none).
        fields: the training's figures (``episodes``, ``mp_calls``, ``planner_runs_fresh``,
            ``planner_runs_real``, ``first_optimal_episode``, ``first_learned_level_episode``,
            ``converged``, ``stop_reason``, ``wall_time_s``, ``q_bar_curve``, ``extraction``).
    """
    variant = task.variant
    return {
        'scenario': task.scenario,
        'policy': policy,
        'hlrnd_rule': variant.hlrnd_rule,
        'epsilon_coin': variant.epsilon_coin,
        'steady_episodes': variant.steady_episodes,
        'steady_rule': variant.steady_rule,
        'beta': variant.beta,
        'seed': task.seed,
        'sequence': list(sequence),
        'level': len(sequence),
        'optimal': bool(sequence) and len(sequence) == task.optimal_level,  # none is never optimal
        **fields,
    }


def reference(name: str, kind: str) -> tuple[dict, SharedOracle]:
    """Exact optimum, its planner runs and queries, and the sequence counts (parent process).

    Returns:
        (info, oracle): info has ``level``, ``sequence``, ``exact_queries``,
        ``exact_planner_runs`` (runs the exact search alone needs), ``feasible_sequences``
        (xi_p), ``optimal_sequences`` (xi*), ``reachable_sets``, ``reference_time_s``.
    """
    from qtree_task_planner.exact import count_feasible_sequences, solve_exact
    from qtree_task_planner.exceptions import SearchLimitExceededError

    shared = SharedOracle(name, kind)
    obstacles, target = scenario_ids(name, kind)
    start = time.monotonic()
    solution = solve_exact(obstacles, target, shared)
    info: dict[str, Any] = {
        'obstacles': len(obstacles),
        'level': solution.level,
        'sequence': list(solution.sequence),
        'exact_queries': solution.queries,
        'exact_planner_runs': shared.planner_runs,
        'exact_time_s': time.monotonic() - start,
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


def _ray_task(task: Task, warm: dict, fn: Any = None) -> dict:
    if fn is not None and fn is not run_task:
        return fn(task)
    if task.scenario not in _ORACLES:
        init_worker(task.kind, {task.scenario: warm.get(task.scenario, {})})
    return run_task(task)


def run_all(
    tasks: list,
    workers: int,
    kind: str,
    warm: dict,
    ray_address: str | None,
    fn: Any = None,
    desc: str = 'trainings',
) -> list:
    """Run the tasks (in-process, process pool or Ray) with a progress bar; records in task
    order. ``fn`` (default :func:`run_task`) runs one task in a worker and must be importable
    by name (``scripts/bench_scale.py`` passes ``qtree_benchmarks.task.scale.run_scene``).
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
        order = {ref: i for i, ref in enumerate(refs)}
        out: list[Any] = [None] * len(refs)
        with tqdm(total=len(refs), desc=desc) as bar:
            while refs:
                done, refs = ray.wait(refs)
                for ref, record in zip(done, ray.get(done), strict=True):
                    out[order[ref]] = record
                bar.update(len(done))
        return out
    if workers <= 1:
        init_worker(kind, warm)
        return [fn(t) for t in tqdm(tasks, desc=desc)]
    with ProcessPoolExecutor(workers, initializer=init_worker, initargs=(kind, warm)) as pool:
        return list(tqdm(pool.map(fn, tasks, chunksize=1), total=len(tasks), desc=desc))
