"""Generated clutter whose target is retrievable, checked with the real in-process planner.

``qtree_scene.generator`` may not import the motion planner, so the solvability filter lives here
(no ROS import). A scene is retrievable when some sequence of feasible relocations ends with the
target. Two checks:

* ``'exact'``: :func:`qtree_task_planner.exact.solve_exact` (BFS over sets, minimal sequence)
  with the :class:`~qtree_task_planner.oracle.MotionPlannerOracle`;
* ``'closure'``: relocate every feasible obstacle, repeat until the target is feasible or no
  obstacle is: far fewer planner runs, and exact when removing objects never makes a relocation
  infeasible (what Assumption 2 and a planner that only ever loses obstacles give); its
  sequence is feasible but not minimal.

Every check has budgets (planner runs, expanded sets, wall time); a scene that hits one is
neither accepted nor called unsolvable, it is counted apart.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Literal

from qtree_scene.generator import generate_clutter
from qtree_scene.scene import Scenario
from qtree_task_planner.exact import solve_exact
from qtree_task_planner.exceptions import BudgetExceededError, SearchLimitExceededError
from qtree_task_planner.oracle import MemoOracle, MotionPlannerOracle

Method = Literal['exact', 'closure']
BENCH_TIME_LIMIT_S = 30.0  # planner time limit per check in benchmarks (shared machine) [s]


@dataclass(frozen=True)
class Retrievability:
    """Outcome of one retrievability check.

    Attributes:
        scenario: the scene checked.
        retrievable: True / False, or None when a budget was hit.
        sequence: a feasible sequence ending with the target (minimal with ``'exact'``).
        planner_runs: real planner runs used.
        wall_s: wall time of the check [s].
        method: ``'exact'`` or ``'closure'``.
        detail: why (budget hit, no feasible obstacle left, ...).
    """

    scenario: Scenario
    retrievable: bool | None
    sequence: tuple[str, ...]
    planner_runs: int
    wall_s: float
    method: Method
    detail: str = ''


@dataclass
class RetrievableBatch:
    """Scenes kept by :func:`generate_retrievable` and the count of those rejected.

    Attributes:
        kept: the retrievable scenes' checks, in seed order.
        rejected_unsolvable: generated scenes whose target is not retrievable.
        rejected_budget: generated scenes whose check hit a budget.
        rejected_invalid: seeds for which the generator raised (density cannot be packed).
        seeds_tried: seeds used, in order.
    """

    kept: list[Retrievability] = field(default_factory=list)
    rejected_unsolvable: int = 0
    rejected_budget: int = 0
    rejected_invalid: int = 0
    seeds_tried: list[int] = field(default_factory=list)

    @property
    def scenarios(self) -> list[Scenario]:
        """The kept scenes."""
        return [k.scenario for k in self.kept]


class _BudgetOracle:
    """Forwards to a memoised planner oracle; raises BudgetExceededError past the budgets."""

    def __init__(self, inner: MemoOracle, max_runs: int, deadline: float) -> None:
        self.inner = inner
        self.max_runs = max_runs
        self.deadline = deadline

    @property
    def planner_runs(self) -> int:
        return self.inner.planner_runs

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        if self.inner.planner_runs >= self.max_runs:
            raise BudgetExceededError('planner_runs', f'more than {self.max_runs} planner runs')
        if time.monotonic() > self.deadline:
            raise BudgetExceededError('time', 'wall-time budget exceeded')
        return self.inner.feasible(relocated, object_id)


def make_planner(scenario: Scenario, time_limit_s: float = BENCH_TIME_LIMIT_S) -> Any:
    """An in-process ``MotionPlanner`` for ``scenario`` with a benchmark time limit [s]."""
    from stpik_motion_planner.config import PlannerConfig
    from stpik_motion_planner.planner import MotionPlanner

    return MotionPlanner(scenario, PlannerConfig(time_limit_s=time_limit_s))


def check_retrievable(
    scenario: Scenario,
    *,
    method: Method = 'exact',
    max_planner_runs: int = 2000,
    max_sets: int = 5000,
    budget_s: float = 900.0,
    planner: Any | None = None,
) -> Retrievability:
    """Is the target of ``scenario`` retrievable with the in-process motion planner?

    Args:
        scenario: the scene.
        method: ``'exact'`` (set BFS) or ``'closure'`` (see the module docstring).
        max_planner_runs: budget of real planner runs.
        max_sets: budget of sets expanded by the exact search.
        budget_s: wall-time budget [s].
        planner: a ``MotionPlanner`` to reuse (default: :func:`make_planner`).

    Raises:
        ValueError: unknown method or non-positive budget.
    """
    if method not in ('exact', 'closure'):
        raise ValueError(f"method must be 'exact' or 'closure', got {method!r}")
    if min(max_planner_runs, max_sets) < 1 or not budget_s > 0:
        raise ValueError('budgets must be positive')
    start = time.monotonic()
    memo = MemoOracle(MotionPlannerOracle(scenario, planner or make_planner(scenario)))
    oracle = _BudgetOracle(memo, max_planner_runs, start + budget_s)
    obstacles = tuple(o.id for o in scenario.obstacles)
    target = scenario.target.id

    def done(ok: bool | None, sequence: tuple[str, ...], detail: str) -> Retrievability:
        wall = time.monotonic() - start
        return Retrievability(scenario, ok, sequence, memo.planner_runs, wall, method, detail)

    try:
        if method == 'exact':
            solution = solve_exact(obstacles, target, oracle, max_sets=max_sets)
            detail = f'optimal level {solution.level}' if solution.solvable else 'no sequence'
            return done(solution.solvable, solution.sequence, detail)
        return _closure(obstacles, target, oracle, done)
    except (BudgetExceededError, SearchLimitExceededError) as err:
        return done(None, (), f'budget hit: {err}')


def _closure(
    obstacles: tuple[str, ...],
    target: str,
    oracle: _BudgetOracle,
    done: Callable[[bool | None, tuple[str, ...], str], Retrievability],
) -> Retrievability:
    order: list[str] = []
    while True:
        if oracle.feasible(tuple(order), target):
            return done(True, (*order, target), f'{len(order)} obstacles relocated')
        new = [o for o in obstacles if o not in order and oracle.feasible(tuple(order), o)]
        if not new:
            left = len(obstacles) - len(order)
            return done(False, (), f'{left} obstacles left, none feasible')
        order += new


def generate_retrievable(
    count: int,
    n_objects: int,
    density: float,
    *,
    first_seed: int = 0,
    max_seeds: int | None = None,
    method: Method = 'exact',
    progress: Callable[[Retrievability | None], None] | None = None,
    planner_factory: Callable[[Scenario], Any] = make_planner,
    **budgets: Any,
) -> RetrievableBatch:
    """The first ``count`` seeds from ``first_seed`` on whose scene's target is retrievable.

    Args:
        count: scenes wanted (≥ 1).
        n_objects: obstacles per scene.
        density: footprint density, see ``generate_clutter``.
        first_seed: first generator seed tried.
        max_seeds: seeds tried at most (default 10 × ``count``): the loop always ends.
        method: the check, see :func:`check_retrievable`.
        progress: called after each seed with its check (None when the generator raised).
        planner_factory: builds the planner of a scene (default :func:`make_planner`).
        **budgets: ``max_planner_runs``, ``max_sets``, ``budget_s`` of each check.

    Returns:
        The kept scenes (possibly fewer than ``count``) and the rejected counts.

    Raises:
        ValueError: ``count`` < 1 or ``max_seeds`` < 1; generator argument errors
            (``ScenarioError``) other than an unpackable density.
    """
    if count < 1 or (max_seeds is not None and max_seeds < 1):
        raise ValueError('count and max_seeds must be ≥ 1')
    from qtree_scene.exceptions import ScenarioError

    batch = RetrievableBatch()
    for seed in _seeds(first_seed, max_seeds or 10 * count):
        if len(batch.kept) >= count:
            break
        batch.seeds_tried.append(seed)
        try:
            scenario = generate_clutter(n_objects, density, seed)
        except ScenarioError as err:
            if err.field != 'density':
                raise
            batch.rejected_invalid += 1
            if progress:
                progress(None)
            continue
        planner = planner_factory(scenario)
        check = check_retrievable(scenario, method=method, planner=planner, **budgets)
        if check.retrievable:
            batch.kept.append(check)
        elif check.retrievable is None:
            batch.rejected_budget += 1
        else:
            batch.rejected_unsolvable += 1
        if progress:
            progress(check)
    return batch


def _seeds(first: int, n: int) -> Iterator[int]:
    yield from range(first, first + n)
