"""Layouts of the paper's three scenes, searched for a target difficulty (#31 item 1; no ROS).

The paper measures its policies on S1, S2, S3 of known difficulty: optimal level 4 / 5 / 6 (the
target included), ξ_p = 10 / 20 / 20 feasible target sequences and ξ* = 1 optimal sequence
(Sect. 4). :mod:`.scene_structures` gives the blocking structures with those numbers; this module
holds the geometry that realises them and the search that checks it with the real planner:

- a :class:`Layout` is a target and cylinders at explicit positions; some of them (``searched``)
  may be shifted by the search;
- :func:`candidates` yields the layout itself first, then each searched object shifted on a grid,
  nearest shifts first;
- :func:`derive` runs the exact search and the sequence count on one planner seed and records every
  (set, object) answer they asked;
- :func:`accept` takes a layout only when every seed gives the target (level, ξ_p, ξ*) AND the
  same answer to every question: a layout whose answers depend on the planner's seed would give
  another difficulty to every training.

Which object occludes which is written nowhere: it comes from the geometry, through the planner.
Lengths [m], world frame = robot base frame, table top at z = 0.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from qtree_scene.scene import ObjectSpec, Role, Scenario
from qtree_task_planner.exact import count_feasible_sequences, solve_exact
from qtree_task_planner.oracle import FeasibilityAnswer, FeasibilityOracle, MemoOracle

# The paper's scenes: (optimal level with the target, ξ_p, ξ*) (Sect. 4).
PAPER_DIFFICULTY: dict[str, tuple[int, int, int]] = {
    's1': (4, 10, 1),
    's2': (5, 20, 1),
    's3': (6, 20, 1),
}
SEEDS = (0, 1, 2, 3, 4)  # planner seeds a layout must agree under
RADIUS = 0.03  # every cylinder's radius [m]
TARGET_HEIGHT = 0.16  # [m]
MIN_GAP = 0.015  # smallest free gap between two cylinders a shifted layout keeps [m]

Point = tuple[float, float]
AnswerKey = tuple[tuple[str, ...], str]  # (sorted relocated ids, object id)


@dataclass(frozen=True)
class Layout:
    """One scene's geometry: the target and the obstacles, all upright cylinders.

    Attributes:
        description: the scenario's description line.
        target: the target's (x, y) [m].
        obstacles: per obstacle (id, x [m], y [m], height [m]).
        searched: ids of the obstacles :func:`candidates` may shift.
    """

    description: str
    target: Point
    obstacles: tuple[tuple[str, float, float, float], ...]
    searched: tuple[str, ...] = ()

    def shifted(self, object_id: str, dx: float, dy: float) -> Layout:
        """The layout with ``object_id`` moved by (dx, dy) [m]."""
        moved = tuple(
            (oid, round(x + dx, 4), round(y + dy, 4), h) if oid == object_id else (oid, x, y, h)
            for oid, x, y, h in self.obstacles
        )
        return dataclasses.replace(self, obstacles=moved)

    def positions(self) -> dict[str, Point]:
        """Object id -> (x, y) [m], the target included."""
        out = {'T': self.target}
        out.update({oid: (x, y) for oid, x, y, _ in self.obstacles})
        return out

    def separated(self) -> bool:
        """True when every two cylinders keep at least :data:`MIN_GAP` between them."""
        points = list(self.positions().values())
        least = 2 * RADIUS + MIN_GAP
        return all(
            (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 >= least**2
            for i, a in enumerate(points)
            for b in points[i + 1 :]
        )


# Objects out of the arm's reach on every approach, whatever is relocated (r ≥ 0.88 m, or
# behind the target): they make the tree wide, as the paper's never-reachable objects do.
_FAR = ((0.91, 0.07), (0.91, -0.07), (0.88, 0.17), (0.88, -0.17))
_FARTHER = ((0.92, 0.32), (0.92, -0.32), (0.86, 0.45), (0.86, -0.45))
_HEIGHTS = (0.14, 0.13, 0.15, 0.12)  # O1, O2, … cycle through these [m]


def _far(first_index: int, points: Sequence[Point]) -> tuple[tuple[str, float, float, float], ...]:
    return tuple(
        (f'O{first_index + k}', x, y, _HEIGHTS[(first_index + k - 1) % len(_HEIGHTS)])
        for k, (x, y) in enumerate(points)
    )


LAYOUTS: dict[str, Layout] = {
    # Chain O2 -> O3 -> O1 -> T; O4 is freed by O2, O5 by O4 (structure of `--structures`).
    's1': Layout(
        description='Scenario 1 of the paper: 5 obstacles, optimal level 4, xi_p 10, xi* 1.',
        target=(0.80, 0.0),
        obstacles=(
            ('O1', 0.70, 0.0, 0.12),
            ('O2', 0.48, -0.06, 0.15),
            ('O3', 0.60, 0.0, 0.13),
            ('O4', 0.58, -0.14, 0.14),
            ('O5', 0.68, -0.17, 0.12),
        ),
        searched=('O4', 'O5'),
    ),
    # Chain O1 -> O2 -> O3 -> O4 -> T; O5 is freed by O3, O6 is a free decoy; O7-O10 far.
    's2': Layout(
        description='Scenario 2 of the paper: 10 obstacles, optimal level 5, xi_p 20, xi* 1.',
        target=(0.82, 0.0),
        obstacles=(
            ('O1', 0.42, -0.10, 0.14),
            ('O2', 0.50, -0.08, 0.13),
            ('O3', 0.60, -0.06, 0.15),
            ('O4', 0.72, 0.0, 0.12),
            ('O5', 0.70, -0.14, 0.14),
            ('O6', 0.55, 0.32, 0.13),
            *_far(7, _FAR),
        ),
        searched=('O5', 'O6'),
    ),
    # Chain O1 -> O2 -> O3 -> O4 -> O5 -> T; O6 is freed by O1, O7 by O4; O8-O15 far.
    's3': Layout(
        description='Scenario 3 of the paper: 15 obstacles, optimal level 6, xi_p 20, xi* 1.',
        target=(0.82, 0.0),
        obstacles=(
            ('O1', 0.38, -0.20, 0.14),
            ('O2', 0.42, -0.10, 0.13),
            ('O3', 0.50, -0.08, 0.15),
            ('O4', 0.60, -0.06, 0.12),
            ('O5', 0.72, 0.0, 0.14),
            ('O6', 0.51, -0.24, 0.13),
            ('O7', 0.70, -0.15, 0.15),
            *_far(8, _FAR + _FARTHER),
        ),
        searched=('O6', 'O7'),
    ),
}


def build(layout: Layout, base: Scenario) -> Scenario:
    """``base``'s table, statics and home with ``layout``'s objects."""
    objects = [o for o in base.objects if o.role == 'static']
    x, y = layout.target
    cylinders: list[tuple[str, Role, float, float, float]] = [('T', 'target', x, y, TARGET_HEIGHT)]
    cylinders += [(oid, 'obstacle', x, y, h) for oid, x, y, h in layout.obstacles]
    for oid, role, x, y, height in cylinders:
        position = (x, y, height / 2)
        objects.append(ObjectSpec(oid, role, 'cylinder', position, radius=RADIUS, height=height))
    return dataclasses.replace(base, objects=tuple(objects), description=layout.description)


def layout_digest(scenario: Scenario) -> str:
    """SHA-256 of every object's id, role, shape, position, radius and height (rounded to
    0.1 mm): the answer table's key to the YAML it was derived from.
    """
    rows = sorted(
        (o.id, o.role, o.shape, *(round(float(v), 4) for v in (*o.position, o.radius, o.height)))
        for o in scenario.objects
    )
    return hashlib.sha256(json.dumps(rows).encode()).hexdigest()


def candidates(layout: Layout, *, step: float = 0.01, reach: int = 3) -> Iterator[Layout]:
    """``layout`` first, then each searched object shifted by up to ``reach`` × ``step`` [m] in
    x and y, smallest shifts first; layouts whose cylinders come closer than :data:`MIN_GAP`
    are left out.
    """
    yield layout
    offsets = sorted(
        ((i * step, j * step) for i in range(-reach, reach + 1) for j in range(-reach, reach + 1)),
        key=lambda d: (d[0] ** 2 + d[1] ** 2, d),
    )[1:]
    for dx, dy in offsets:
        for object_id in layout.searched:
            moved = layout.shifted(object_id, dx, dy)
            if moved.separated():
                yield moved


@dataclass
class Derivation:
    """Difficulty of one layout under one planner seed, with the answers it rests on.

    Attributes:
        seed: the planner's seed.
        level: optimal level, target included (0: unsolvable).
        sequence: one optimal target sequence.
        xi_p: feasible target sequences.
        xi_star: optimal ones.
        by_level: level -> feasible target sequences.
        answers: (sorted relocated ids, object id) -> feasible, every question asked.
        planner_runs: real planner runs.
        seconds: wall time [s].
    """

    seed: int
    level: int
    sequence: tuple[str, ...]
    xi_p: int
    xi_star: int
    by_level: dict[int, int]
    answers: dict[AnswerKey, bool] = field(repr=False)
    planner_runs: int = 0
    seconds: float = 0.0

    @property
    def difficulty(self) -> tuple[int, int, int]:
        """(level, ξ_p, ξ*)."""
        return self.level, self.xi_p, self.xi_star


class ReplayOracle:
    """Answers from a recorded table only; a question the table lacks is an error, never a guess.

    Args:
        answers: (sorted relocated ids, object id) -> feasible.
    """

    def __init__(self, answers: Mapping[AnswerKey, bool]) -> None:
        self.answers = dict(answers)
        self.planner_runs = 0

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """The recorded answer.

        Raises:
            KeyError: (relocated, object_id) was not asked when the table was recorded.
        """
        key = (tuple(sorted(relocated)), object_id)
        if key not in self.answers:
            raise KeyError(f'no recorded answer for {object_id!r} after {sorted(relocated)}')
        return self.answers[key]

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """The recorded answer, without blockers."""
        return FeasibilityAnswer(self.feasible(relocated, object_id), None)


def derive(scenario: Scenario, oracle: FeasibilityOracle, seed: int = 0) -> Derivation:
    """Exact optimal level and sequence counts of ``scenario`` with ``oracle`` answering."""
    memo = MemoOracle(oracle)  # its results: every (set, object) asked, with the answer
    obstacles = tuple(o.id for o in scenario.obstacles)
    target = scenario.target.id
    start = time.perf_counter()
    exact = solve_exact(obstacles, target, memo)
    counts = count_feasible_sequences(obstacles, target, memo)
    return Derivation(
        seed=seed,
        level=exact.level,
        sequence=tuple(exact.sequence),
        xi_p=counts.feasible,
        xi_star=counts.optimal,
        by_level=dict(counts.by_level),
        answers={(tuple(sorted(r)), o): f for (r, o), f in memo.results.items()},
        planner_runs=memo.planner_runs,
        seconds=round(time.perf_counter() - start, 2),
    )


def accept(derivations: Sequence[Derivation], wanted: tuple[int, int, int]) -> bool:
    """True when every seed gives ``wanted`` (level, ξ_p, ξ*) and the same answers."""
    if not derivations:
        return False
    first = derivations[0]
    return all(d.difficulty == wanted and d.answers == first.answers for d in derivations)


@dataclass
class Found:
    """A layout the search accepted, with its derivation under every seed."""

    layout: Layout
    derivations: list[Derivation]
    tried: int


def search(
    layout: Layout,
    wanted: tuple[int, int, int],
    derive_seed: Callable[[Layout, int], Derivation],
    *,
    seeds: Sequence[int] = SEEDS,
    max_candidates: int = 60,
    progress: Callable[[int, Layout, Derivation], None] | None = None,
) -> Found | None:
    """First candidate of :func:`candidates` that :func:`accept` takes, or None.

    Args:
        layout: the starting layout.
        wanted: target (level, ξ_p, ξ*).
        derive_seed: (layout, seed) -> its :class:`Derivation` (the real planner in the script).
        seeds: planner seeds that must agree.
        max_candidates: candidates tried at most.
        progress: called with (index, candidate, derivation under the first seed).
    """
    for index, candidate in enumerate(candidates(layout)):
        if index >= max_candidates:
            return None
        first = derive_seed(candidate, seeds[0])
        if progress is not None:
            progress(index, candidate, first)
        if first.difficulty != wanted:
            continue
        derivations = [first]
        for seed in seeds[1:]:
            derivations.append(derive_seed(candidate, seed))
            if not accept(derivations, wanted):
                break
        else:
            return Found(candidate, derivations, index + 1)
    return None


def table_rows(answers: Mapping[AnswerKey, bool]) -> list[list[object]]:
    """JSON rows ``[relocated ids, object id, feasible]`` of an answer table, sorted."""
    return [[list(r), o, f] for (r, o), f in sorted(answers.items())]


def table_of(rows: Sequence[Sequence[Any]]) -> dict[AnswerKey, bool]:
    """Inverse of :func:`table_rows`."""
    return {(tuple(str(i) for i in r), str(o)): bool(f) for r, o, f in rows}
