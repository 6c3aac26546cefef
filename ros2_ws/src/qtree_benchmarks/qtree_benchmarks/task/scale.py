"""Scale benchmark (issue #14, item 6): exact set search, H-eG, H-EG-SET and BLOCKER-SEARCH on
cluttered scenes of 10-50 obstacles (the core of ``scripts/bench_scale.py``).

One task = one scene (N obstacles, density, seed); every method runs on it with its own budget
and a fresh view of one per-scene answer cache (:class:`SceneOracle`), so the geometry of a
(set, object) pair is planned once per scene while each method is charged what a fresh planner
with a set cache would run: ``planner_runs`` = distinct (set, object) pairs the method asked,
``wall_s`` = its own computing time plus the recorded planning time of those pairs.

Scenes: ``oracle='planner'`` uses ``qtree_scene.generator.generate_clutter`` and the real
in-process motion planner (blocker reports from its per-approach sweeps); ``'synthetic'`` uses
:func:`qtree_task_planner.testing.corridor_requirements` (abstract tabletop, sound blocker sets).

Optimal share: against the exact search where it finished; where it did not, against the lower
bound BLOCKER-SEARCH certified (a result is optimal when its level equals a certified bound or a
certified optimum); a scene with neither counts as not optimal for every method.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from qtree_scene.generator import Layout
from qtree_task_planner.blocker_search import BlockerSearchConfig, blocker_search
from qtree_task_planner.exact import solve_exact
from qtree_task_planner.exceptions import BudgetExceededError, SearchLimitExceededError
from qtree_task_planner.oracle import FeasibilityAnswer, MemoOracle, SetKey
from qtree_task_planner.training import QTreeTrainer, TrainingConfig

METHODS = ('exact', 'H-EG', 'H-EG-SET', 'BLOCKER-SEARCH')
CLEAR_ZONE = '<empty drop zone>'  # marks a verification query's key (never an object id)
_T = TypeVar('_T')


@dataclass(frozen=True)
class ScaleTask:
    """One scene and the budgets of every method.

    Attributes:
        n_obstacles: N.
        density: footprint / region area.
        seed: scene seed.
        oracle: ``'planner'`` or ``'synthetic'``.
        methods: subset of :data:`METHODS`.
        exact_max_runs: planner-run budget of the exact search.
        exact_time_s: wall budget of the exact search [s].
        learner_episodes: Ep_max of the learners.
        learner_time_s: wall budget of each learner [s].
        search_max_runs: planner-run budget of BLOCKER-SEARCH.
        search_time_s: wall budget of BLOCKER-SEARCH [s].
        layout: ``generate_clutter``'s layout (``'accessible'``, ``'uniform'``, ``'packed_*'``).
        grasp_families: the planner's grasp families (``('side',)`` the paper's, or with
            ``'top'``).
    """

    n_obstacles: int
    density: float
    seed: int
    oracle: str = 'planner'
    methods: tuple[str, ...] = METHODS
    exact_max_runs: int = 3000
    exact_time_s: float = 60.0
    learner_episodes: int = 5000
    learner_time_s: float = 10.0
    search_max_runs: int = 3000
    search_time_s: float = 120.0
    layout: Layout = 'accessible'
    grasp_families: tuple[str, ...] = ('side',)


def clear_key(relocated: tuple[str, ...], object_id: str) -> SetKey:
    """Cache key of a verification query, apart from the ordinary answer's key."""
    return frozenset(relocated) | {CLEAR_ZONE}, object_id


class SceneOracle(MemoOracle):
    """Per-scene answer cache over the real oracle (a :class:`~.oracle.MemoOracle`), with the
    planning time of each answer.

    Attributes:
        cost_s: planning time of each answer [s], by ``(frozenset(relocated), object)`` and, for
            verification queries, by :func:`clear_key`.
        spent_s: planning time actually spent in this process [s].
    """

    def __init__(self, inner: Any) -> None:
        super().__init__(inner)
        self.cost_s: dict[SetKey, float] = {}
        self.spent_s = 0.0

    @property
    def has_clear_zone(self) -> bool:
        """Whether the real oracle answers verification queries apart (the planner does)."""
        return hasattr(self.inner, 'clear_zone_feasible')

    def clear_zone(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Answer of a verification query (:func:`~.oracle.ask_clear`), memoised, timed."""
        return self._timed(
            clear_key(relocated, object_id), self.clear_zone_feasible, relocated, object_id
        )

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """Cached answer, or one real run (timed)."""
        return self._timed((frozenset(relocated), object_id), super().answer, relocated, object_id)

    def _timed(
        self, key: SetKey, ask_memo: Any, relocated: tuple[str, ...], object_id: str
    ) -> Any:
        if key in self.cost_s:
            return ask_memo(relocated, object_id)
        start = time.perf_counter()
        answer = ask_memo(relocated, object_id)
        self.cost_s[key] = time.perf_counter() - start
        self.spent_s += self.cost_s[key]
        return answer


class MethodOracle:
    """One method's view of a :class:`SceneOracle`: counts its distinct pairs, charges their
    planning time and enforces its budgets.

    Attributes:
        planner_runs: distinct (set, object) pairs asked (a fresh planner's runs).
        charged_s: planning time of those pairs [s].
    """

    def __init__(self, scene: SceneOracle, max_runs: int, time_s: float) -> None:
        self.scene = scene
        self.sound_blockers = scene.sound_blockers
        self.max_runs = max_runs
        self.deadline = time.monotonic() + time_s
        self.planner_runs = 0
        self.charged_s = 0.0
        self._seen: set[SetKey] = set()

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """The scene's answer; a new pair past a budget raises :class:`BudgetExceededError`."""
        key = (frozenset(relocated), object_id)
        return self._charged(key, lambda: self.scene.answer(relocated, object_id))

    def approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[frozenset[str], ...] | None:
        """The scene's per-approach blockers of an answer already asked (no planner run)."""
        return self.scene.approach_blockers(relocated, object_id)

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Feasibility only (for the exact search and the learners)."""
        return self.answer(relocated, object_id).feasible

    def clear_zone_feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Verification query; the ordinary answer when the real oracle has none apart."""
        if not self.scene.has_clear_zone:
            return self.feasible(relocated, object_id)
        key = clear_key(relocated, object_id)
        return self._charged(key, lambda: self.scene.clear_zone(relocated, object_id))

    def _charged(self, key: SetKey, ask: Callable[[], _T]) -> _T:
        """``ask()``; a new ``key`` counts one planner run and its cost, past a budget it raises
        :class:`BudgetExceededError` (``'planner_runs'`` or ``'time'``) instead.
        """
        if key in self._seen:
            return ask()  # memoised: no planner run
        if self.planner_runs >= self.max_runs:
            raise BudgetExceededError('planner_runs')
        if time.monotonic() > self.deadline:
            raise BudgetExceededError('time')
        answer = ask()
        self._seen.add(key)
        self.planner_runs += 1
        self.charged_s += self.scene.cost_s[key]
        return answer


def build_scene(task: ScaleTask) -> tuple[tuple[str, ...], str, Any]:
    """(obstacle ids, target id, real oracle) of a task's scene."""
    if task.oracle == 'synthetic':
        from qtree_task_planner.oracle import TableOracle
        from qtree_task_planner.testing import corridor_requirements

        obstacles, requirements = corridor_requirements(task.n_obstacles, task.density, task.seed)
        return obstacles, 'T', TableOracle(requirements)
    from qtree_scene.generator import generate_clutter
    from qtree_task_planner.oracle import MotionPlannerOracle
    from stpik_motion_planner.config import PlannerConfig
    from stpik_motion_planner.planner import MotionPlanner

    scenario = generate_clutter(task.n_obstacles, task.density, task.seed, layout=task.layout)
    planner = MotionPlanner(scenario, PlannerConfig(grasp_families=tuple(task.grasp_families)))
    obstacles = tuple(o.id for o in scenario.obstacles)
    return obstacles, scenario.target.id, MotionPlannerOracle(scenario, planner)


def grasp_counts(inner: Any) -> dict[str, int]:
    """Feasible answers the planner returned on this scene, by grasp family, and how many grip
    an object wider across the fingers, at the answer's approach yaw, than the hand opens
    (``too_wide_grasps``: 0 since #30 item 1; a synthetic oracle has no grasps: all 0).
    """
    counts = {'side_grasps': 0, 'top_grasps': 0, 'too_wide_grasps': 0}
    planner = getattr(inner, 'planner', None)
    if planner is None:
        return counts
    from jaco2_description.model import HAND_OPENING_M
    from stpik_motion_planner.hand_model import grasp_width

    for (_, object_id), result in planner.cache.items():
        if not result.feasible:
            continue
        counts['top_grasps' if result.grasp_family == 'top' else 'side_grasps'] += 1
        width = grasp_width(inner.scenario.object(object_id), result.approach_yaw)
        counts['too_wide_grasps'] += width > HAND_OPENING_M
    return counts


def _run_method(method: str, task: ScaleTask, obstacles, target, scene: SceneOracle) -> dict:
    if method == 'exact':
        oracle = MethodOracle(scene, task.exact_max_runs, task.exact_time_s)
    elif method == 'BLOCKER-SEARCH':
        oracle = MethodOracle(scene, task.search_max_runs + 1, task.search_time_s + 1.0)
    else:
        oracle = MethodOracle(scene, 10**9, task.learner_time_s + 1.0)
    spent0 = scene.spent_s
    start = time.perf_counter()
    record: dict[str, Any] = {'method': method, 'budget_hit': '', 'lower_bound': None}
    record['certified'] = False
    if method == 'exact':
        try:
            solution = solve_exact(obstacles, target, oracle, max_sets=10**6)
            sequence, episodes = solution.sequence, solution.sets_explored
            record['finished'] = True
        except (BudgetExceededError, SearchLimitExceededError) as err:
            sequence, episodes = (), 0
            record.update(finished=False, budget_hit=getattr(err, 'which', 'sets'))
    elif method == 'BLOCKER-SEARCH':
        search_config = BlockerSearchConfig(
            max_planner_runs=task.search_max_runs, time_limit_s=task.search_time_s
        )
        found = blocker_search(obstacles, target, oracle, search_config)
        sequence, episodes = found.sequence, found.candidates
        record.update(
            budget_hit=found.budget_hit,
            lower_bound=found.lower_bound,
            bound=found.bound,
            # proven: the level when finished, the bound when the budget ran out (_score)
            certified=found.bound_certified,
            optimum_certified=found.certified,
            rechecks=found.rechecks,
            contradictions=found.contradictions,
            status=found.status,
        )
    else:
        config = TrainingConfig(
            policy=method,
            seed=task.seed,
            max_episodes=task.learner_episodes,
            time_limit_s=task.learner_time_s,
        )
        trainer = QTreeTrainer((*obstacles, target), target, oracle, config)
        try:
            result = trainer.run()
        except BudgetExceededError as err:
            result = trainer.result(err.which)
        sequence, episodes = result.sequence, result.episodes
        if result.stop_reason in ('time_limit', 'max_episodes', 'time', 'planner_runs'):
            record['budget_hit'] = result.stop_reason
    own = time.perf_counter() - start - (scene.spent_s - spent0)
    record.update(
        sequence=list(sequence),
        level=len(sequence),
        planner_runs=oracle.planner_runs,
        episodes=episodes,
        wall_s=max(0.0, own) + oracle.charged_s,
    )
    return record


def run_scene(task: ScaleTask) -> list[dict]:
    """Every method of ``task`` on its scene; one record per method (JSON-ready)."""
    obstacles, target, inner = build_scene(task)
    scene = SceneOracle(inner)
    records = []
    for method in task.methods:
        record = _run_method(method, task, obstacles, target, scene)
        record.update(
            n_obstacles=task.n_obstacles,
            density=task.density,
            seed=task.seed,
            layout=task.layout,
            grasp_families=list(task.grasp_families),
        )
        records.append(record)
    _score(records)
    counts = grasp_counts(inner)  # the scene's whole cache: every method's answers
    for record in records:
        record.update(counts)
    return records


def _score(records: list[dict]) -> None:
    """Set ``optimal`` and ``reference`` of each record of one scene (see module docstring)."""
    exact = next((r for r in records if r['method'] == 'exact' and r.get('finished')), None)
    search = next((r for r in records if r['method'] == 'BLOCKER-SEARCH'), None)
    if exact is not None:
        reference, level = 'exact', exact['level']
    elif search is not None and search['certified'] and search['status'] != 'budget':
        reference, level = 'certified optimum', search['level']
    elif search is not None and search['certified']:
        reference, level = 'certified bound', search['lower_bound']
    else:
        reference, level = 'none', None
    for r in records:
        r['reference'] = reference
        r['reference_level'] = level
        if reference == 'certified bound':
            r['optimal'] = bool(r['sequence']) and r['level'] == level
        else:
            r['optimal'] = level is not None and r['level'] == level
        r['solved'] = bool(r['sequence'])


def summarize(records: list[dict]) -> list[dict]:
    """One row per (N, density, method) with the keys of issue #14."""
    rows = []
    keys = sorted({(_layout(r), r['n_obstacles'], r['density'], r['method']) for r in records})
    keys.sort(key=lambda k: (k[0], k[1], k[2], METHODS.index(k[3])))
    for layout, n, density, method in keys:
        group = [
            r
            for r in records
            if (_layout(r), r['n_obstacles'], r['density'], r['method'])
            == (layout, n, density, method)
        ]
        solvable = [r for r in group if r['reference_level'] != 0]
        rows.append(
            {
                'layout': layout,
                'grasp_families': sorted({f for r in group for f in _families(r)}),
                'n_obstacles': n,
                'density': density,
                'method': method,
                'scenes': len(group),
                'solved_share': float(np.mean([r['solved'] for r in group])),
                'optimal_share': float(np.mean([r['optimal'] for r in group])),
                'planner_runs_mean': float(np.mean([r['planner_runs'] for r in group])),
                'wall_s_mean': float(np.mean([r['wall_s'] for r in group])),
                'wall_s_max': float(np.max([r['wall_s'] for r in group])),
                'episodes_mean': float(np.mean([r['episodes'] for r in group])),
                'budget_hit_share': float(np.mean([bool(r['budget_hit']) for r in group])),
                'solvable_scenes': len(solvable),
                'exact_finished_share': float(np.mean([r['reference'] == 'exact' for r in group])),
                'too_wide_grasps': int(sum(r.get('too_wide_grasps', 0) for r in group)),
            }
        )
    return rows


def scene_total(records: list[dict], key: str) -> int:
    """Sum of a per-scene count over the scenes (every method's record of a scene holds it)."""
    scenes = {(_layout(r), r['n_obstacles'], r['density'], r['seed']): r for r in records}
    return int(sum(r.get(key, 0) for r in scenes.values()))


def _layout(record: dict) -> str:
    return record.get('layout', 'accessible')  # records and rows of runs before #30 item 5


def _families(record: dict) -> list[str]:
    return record.get('grasp_families', ['side'])


def markdown(rows: list[dict], meta: dict) -> str:
    """The scale.md report."""
    lines = [
        '# Scale benchmark (issue #14)',
        '',
        f'Oracle: {meta["oracle"]}; generator layouts '
        f'`{", ".join(meta.get("layouts", [meta.get("generator_layout", "uniform")]))}`, grasp '
        f'families `{"+".join(_families(meta))}`; '
        f'{meta["scenes"]} scenes per (layout, N, density); '
        f'grasps wider than the hand in returned answers: {meta.get("too_wide_grasps", "n/a")}; '
        f'{meta["workers"]} worker(s); total wall time {meta["wall_time_s"]:.0f} s. '
        f'Budgets: exact {meta["exact_max_runs"]} planner runs / {meta["exact_time_s"]:g} s, '
        f'learners Ep_max {meta["learner_episodes"]} / {meta["learner_time_s"]:g} s, '
        f'BLOCKER-SEARCH {meta["search_max_runs"]} runs / {meta["search_time_s"]:g} s.',
        '',
        '| layout | grasps | N | density | method | solved | optimal | planner runs '
        '| wall [s] mean (max) | episodes | budget hit | exact finished |',
        '|---|---|---|---|---|---|---|---|---|---|---|---|',
    ]
    for r in rows:
        families = '+'.join(_families(r))
        lines.append(
            f'| {_layout(r)} | {families} '
            f'| {r["n_obstacles"]} | {r["density"]:g} | {r["method"]} | {r["solved_share"]:.0%} '
            f'| {r["optimal_share"]:.0%} | {r["planner_runs_mean"]:.0f} '
            f'| {r["wall_s_mean"]:.2f} ({r["wall_s_max"]:.1f}) | {r["episodes_mean"]:.0f} '
            f'| {r["budget_hit_share"]:.0%} | {r["exact_finished_share"]:.0%} |'
        )
    lines += ['', *ratio_lines(meta.get('records', [])), '', *meta.get('notes', []), '']
    return '\n'.join(lines)


def ratio_lines(records: list[dict]) -> list[str]:
    """BLOCKER-SEARCH vs exact on the scenes where the exact search finished, per N: planner-run
    ratio and whether its level always matched.
    """
    lines = ['| N | scenes exact finished | BLOCKER-SEARCH / exact planner runs | same level |']
    lines.append('|---|---|---|---|')
    for n in sorted({r['n_obstacles'] for r in records}):
        pairs = []
        for r in records:
            if r['n_obstacles'] == n and r['method'] == 'exact' and r.get('finished'):
                other = next(
                    (
                        o
                        for o in records
                        if o['method'] == 'BLOCKER-SEARCH'
                        and (_layout(o), o['n_obstacles'], o['density'], o['seed'])
                        == (_layout(r), n, r['density'], r['seed'])
                    ),
                    None,
                )
                if other is not None:
                    pairs.append((r, other))
        if not pairs:
            continue
        ratio = sum(o['planner_runs'] for _, o in pairs) / max(
            1, sum(r['planner_runs'] for r, _ in pairs)
        )
        same = sum(o['level'] == r['level'] for r, o in pairs)
        lines.append(f'| {n} | {len(pairs)} | {ratio:.3f} | {same}/{len(pairs)} |')
    return lines


def plot(rows: list[dict], path: Any) -> None:
    """PNG: mean planner runs and mean wall time against N, one line per method and density."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    groups = sorted({(_layout(r), r['density']) for r in rows})
    styles = ('-', '--', ':', '-.')
    for method in METHODS:
        for (layout, density), style in zip(groups, styles * len(groups), strict=False):
            sel = [
                r
                for r in rows
                if r['method'] == method and r['density'] == density and _layout(r) == layout
            ]
            if not sel:
                continue
            ns = [r['n_obstacles'] for r in sel]
            where = f'{layout}, ' if len({g[0] for g in groups}) > 1 else ''
            label = f'{method} ({where}density {density:g})'
            axes[0].plot(ns, [r['planner_runs_mean'] for r in sel], style, marker='o', label=label)
            axes[1].plot(ns, [r['wall_s_mean'] for r in sel], style, marker='o', label=label)
    for ax, title in zip(axes, ('planner runs (mean)', 'wall time [s] (mean)'), strict=True):
        ax.set_yscale('log')
        ax.set_xlabel('obstacles N')
        ax.set_title(title)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
