"""Synthetic feasibility tables for tests and development (never for reported results).

Feasibility in reported results always comes from the real geometry through the motion planner;
these tables only exercise the learner: a hand-made toy scene and seeded random tables.
"""

from __future__ import annotations

import numpy as np

from qtree_task_planner.oracle import TableOracle

TOY_OBSTACLES = ('O1', 'O2', 'O3', 'O4', 'O5')
TOY_MOVABLE = (*TOY_OBSTACLES, 'T')
# T needs {O1, O2, O3} gone (optimal level 4) or {O1, O2, O4, O5} gone (level 5);
# O1 needs O2 or O4 gone; O3 needs O2 gone; O2, O4, O5 are free.
TOY_REQUIREMENTS: dict[str, list[set[str]]] = {
    'T': [{'O1', 'O2', 'O3'}, {'O1', 'O2', 'O4', 'O5'}],
    'O1': [{'O2'}, {'O4'}],
    'O3': [{'O2'}],
}
TOY_OPTIMAL_LEVEL = 4


def toy_oracle() -> TableOracle:
    """A fresh oracle of the toy 5-obstacle scene."""
    return TableOracle(TOY_REQUIREMENTS)


def random_requirements(
    n_obstacles: int, rng: np.random.Generator, *, max_sets: int = 2, p_blocked: float = 0.4
) -> tuple[tuple[str, ...], dict[str, list[set[str]]]]:
    """A random table: each object is blocked with probability ``p_blocked``; a blocked object
    gets 1..``max_sets`` clearing sets, each a random non-empty subset of the other obstacles.
    The target is always blocked.

    Args:
        n_obstacles: N_o >= 1.
        rng: random generator.
        max_sets: maximum clearing sets per blocked object.
        p_blocked: probability that an obstacle is blocked.

    Returns:
        (obstacle ids ``O1..ON``, requirements for :class:`TableOracle`).
    """
    obstacles = tuple(f'O{i + 1}' for i in range(n_obstacles))
    requirements: dict[str, list[set[str]]] = {}
    for obj in (*obstacles, 'T'):
        if obj != 'T' and rng.random() >= p_blocked:
            continue
        others = [o for o in obstacles if o != obj]
        sets = []
        for _ in range(int(rng.integers(1, max_sets + 1))):
            if not others:
                break
            size = int(rng.integers(1, min(3, len(others)) + 1))
            sets.append({others[i] for i in rng.choice(len(others), size, replace=False)})
        requirements[obj] = sets
    return obstacles, requirements


# Seeds of :func:`random_requirements` (p_blocked=0.6) giving scenes shaped like the paper's:
# N_o = 5 / 10 / 15 with optimal levels 4 / 5 / 6 and a unique or rare optimum.
SYNTHETIC_SCENARIOS = {'s1': (5, 4), 's2': (10, 3), 's3': (15, 155)}


def synthetic_scenario(name: str) -> tuple[tuple[str, ...], dict[str, list[set[str]]]]:
    """A synthetic stand-in of scenario ``name`` (``'s1'``, ``'s2'``, ``'s3'``).

    Returns:
        (obstacle ids, requirements for :class:`TableOracle`); the target is ``'T'``.

    Raises:
        KeyError: unknown name.
    """
    n_obstacles, seed = SYNTHETIC_SCENARIOS[name]
    return random_requirements(n_obstacles, np.random.default_rng(seed), p_blocked=0.6)


def decoy_requirements(
    n_chain: int, n_decoys: int
) -> tuple[tuple[str, ...], dict[str, list[set[str]]]]:
    """An abstract decoy scene: a blocking chain plus free, useless decoys.

    T needs ``C1`` gone, ``C1`` needs ``C2`` gone, …, ``C{n_chain}`` is free; the decoys
    ``D1``… are always feasible and never help. The unique optimum relocates the chain from its
    far end, level ``n_chain + 1``; the decoys only widen the search (the issue #14 profile).

    Args:
        n_chain: chain length >= 0.
        n_decoys: number of decoys >= 0.

    Returns:
        (obstacle ids, chain first then decoys; requirements for :class:`TableOracle`).
    """
    if n_chain < 0 or n_decoys < 0:
        raise ValueError(f'n_chain and n_decoys must be >= 0, got {n_chain}, {n_decoys}')
    chain = [f'C{i + 1}' for i in range(n_chain)]
    decoys = [f'D{i + 1}' for i in range(n_decoys)]
    requirements: dict[str, list[set[str]]] = {}
    for blocked, blocker in zip(['T', *chain], chain, strict=False):
        requirements[blocked] = [{blocker}]
    return (*chain, *decoys), requirements


APPROACH_OFFSETS_RAD = (-0.6, -0.3, 0.0, 0.3, 0.6)  # side-grasp approach yaws about the bearing
REACH_M = 0.85  # farther objects cannot be grasped at all (blocked by nothing movable) [m]


def corridor_requirements(
    n_obstacles: int, density: float, seed: int, *, radius: float = 0.03, hand: float = 0.09
) -> tuple[tuple[str, ...], dict[str, list[set[str]]]]:
    """An abstract clutter scene with blocker sets, shaped like a tabletop (development only).

    ``n_obstacles + 1`` discs of radius ``radius`` [m] are placed without overlap in a rectangle
    in front of the base (x >= 0.35 m, width 1.75 x depth, area set by ``density`` = footprint /
    area). An object is grasped along one of five approach directions around its bearing from
    the base; an approach's clearing set is every disc whose centre lies in the corridor swept by
    the hand (width ``hand`` + 2 radius [m]) from the object back towards the base side, up to
    the region's near edge. Objects beyond :data:`REACH_M` have no approach. The target ``T``
    is the disc nearest the region's centre; the obstacles are ``O1``… by distance to the base.

    Returns:
        (obstacle ids, requirements for :class:`TableOracle`; the target is ``'T'``).

    Raises:
        ValueError: ``n_obstacles < 0``, density outside (0, 0.5], or the discs do not fit.
    """
    if n_obstacles < 0 or not 0.0 < density <= 0.5:
        raise ValueError(
            f'need n_obstacles >= 0 and density in (0, 0.5], got {n_obstacles}, {density}'
        )
    rng = np.random.default_rng(seed)
    n = n_obstacles + 1
    depth = float(np.sqrt(n * np.pi * radius**2 / density / 1.75))
    width = 1.75 * depth
    centres: list[np.ndarray] = []
    for _ in range(n):
        for _ in range(5000):
            c = np.array(
                [
                    rng.uniform(0.35 + radius, 0.35 + depth - radius),
                    rng.uniform(-width / 2 + radius, width / 2 - radius),
                ]
            )
            if all(np.hypot(*(c - o)) > 2 * radius + 0.005 for o in centres):
                centres.append(c)
                break
        else:
            raise ValueError(f'cannot place {n} discs at density {density}')
    middle = np.array([0.35 + depth / 2, 0.0])
    target = int(np.argmin([np.hypot(*(c - middle)) for c in centres]))
    others = sorted((i for i in range(n) if i != target), key=lambda i: np.hypot(*centres[i]))
    names = {target: 'T', **{i: f'O{k + 1}' for k, i in enumerate(others)}}
    half = hand / 2 + radius
    requirements: dict[str, list[set[str]]] = {}
    for i, c in enumerate(centres):
        if np.hypot(*c) > REACH_M:
            requirements[names[i]] = []
            continue
        bearing = float(np.arctan2(c[1], c[0]))
        sets = []
        for offset in APPROACH_OFFSETS_RAD:
            u = -np.array([np.cos(bearing + offset), np.sin(bearing + offset)])  # towards the arm
            blocking = set()
            for j, d in enumerate(centres):
                along = float(np.dot(d - c, u))
                across = abs(float(np.cross(u, d - c)))
                if j != i and along > 0.0 and across < half + radius:
                    blocking.add(names[j])
            sets.append(blocking)
        if not any(not s for s in sets):
            requirements[names[i]] = sets
    return tuple(f'O{k + 1}' for k in range(n_obstacles)), requirements
