"""Seeded random cluttered scenes for scaling studies and property tests (no ROS).

Cylinders are placed by random sequential addition in a rectangle in front of the robot
(x ≥ ``x_min``, centred on y = 0, width = 1.75 × depth like the paper-style region
x ∈ [0.35, 0.75], |y| ≤ 0.35). The rectangle's area is set by ``density`` = total footprint area /
region area. The object farthest from the robot base is the target ``'T'``; the obstacles are
``'O1'``… in order of increasing distance from the base.
"""

from __future__ import annotations

import math

import numpy as np
from jaco2_description.model import HOME

from qtree_scene.exceptions import ScenarioError
from qtree_scene.scenario import TABLE_ID, validate_scenario
from qtree_scene.scene import ObjectSpec, Scenario

MAX_DENSITY = 0.4  # random sequential addition jams near 0.55; stay well below [-]
ASPECT = 1.75  # region width (y) / depth (x) [-]
DROP_ZONE_CENTER = (0.0, 0.5, 0.15)  # [m]
DROP_ZONE_SIZE = (0.3, 0.3, 0.3)  # [m]
TABLE_X_MIN = -0.25  # table edge behind the robot base [m]
TABLE_MARGIN = 0.1  # table border around the clutter region [m]


def generate_clutter(
    n_objects: int,
    density: float,
    seed: int,
    *,
    radius_range: tuple[float, float] = (0.025, 0.035),
    height_range: tuple[float, float] = (0.10, 0.18),
    gap: float = 0.01,
    x_min: float = 0.35,
    attempts: int = 2000,
) -> Scenario:
    """Random non-overlapping cylinders in front of the robot; the same seed gives the same scene.

    Args:
        n_objects: number of obstacles N_o (≥ 0); one target is added.
        density: total cylinder footprint / region area, in (0, 0.4].
        seed: seed of the numpy generator.
        radius_range: cylinder radii are uniform in this range [m].
        height_range: cylinder heights are uniform in this range [m].
        gap: minimum free distance between two cylinders [m], > 0.
        x_min: near edge of the region [m] (clear of the robot keep-out disc).
        attempts: placement tries per object before the scene is declared too dense.

    Returns:
        A validated scenario named ``gen_<n>_<density>_<seed>``.

    Raises:
        ScenarioError: bad arguments, or no placement found (density too high).
    """
    source = 'generate_clutter'
    if isinstance(n_objects, bool) or not isinstance(n_objects, int) or n_objects < 0:
        raise ScenarioError(source, 'n_objects', f'must be an int ≥ 0, got {n_objects!r}')
    if not (math.isfinite(density) and 0 < density <= MAX_DENSITY):
        raise ScenarioError(source, 'density', f'must be in (0, {MAX_DENSITY}], got {density}')
    lo_r, hi_r = radius_range
    if not (0 < lo_r <= hi_r and 0 < height_range[0] <= height_range[1] and gap > 0):
        raise ScenarioError(source, 'radius_range', 'sizes and gap must be positive and ordered')
    rng = np.random.default_rng(seed)
    n = n_objects + 1
    radii = rng.uniform(lo_r, hi_r, n)
    heights = rng.uniform(*height_range, n)
    area = float(np.sum(np.pi * (radii + gap / 2) ** 2)) / density  # [m²]
    depth = math.sqrt(area / ASPECT)
    width = ASPECT * depth
    centers: list[np.ndarray] = []
    for k in range(n):
        r = radii[k]
        for _ in range(attempts):
            c = np.array(
                [
                    rng.uniform(x_min + r, x_min + depth - r),
                    rng.uniform(-width / 2 + r, width / 2 - r),
                ]
            )
            if all(np.hypot(*(c - o)) > r + radii[i] + gap for i, o in enumerate(centers)):
                centers.append(c)
                break
        else:
            problem = f'cannot place {n} cylinders at density {density}; lower it'
            raise ScenarioError(source, 'density', problem)
    order = np.argsort([-np.hypot(*c) for c in centers])  # farthest first: the target
    objects = []
    for rank, k in enumerate(order):
        x, y = (float(v) for v in centers[k])
        objects.append(
            ObjectSpec(
                id='T' if rank == 0 else f'O{n - rank}',
                role='target' if rank == 0 else 'obstacle',
                shape='cylinder',
                position=(x, y, float(heights[k]) / 2),
                radius=float(radii[k]),
                height=float(heights[k]),
            )
        )
    objects = [*objects[1:][::-1], objects[0]]  # O1 (nearest) … O_n, then T
    x_max = x_min + depth + TABLE_MARGIN
    half_y = max(DROP_ZONE_CENTER[1] + DROP_ZONE_SIZE[1] / 2, width / 2) + TABLE_MARGIN
    table = ObjectSpec(
        id=TABLE_ID,
        role='static',
        shape='box',
        position=((TABLE_X_MIN + x_max) / 2, 0.0, -0.025),
        size=(x_max - TABLE_X_MIN, 2 * half_y, 0.05),
    )
    scenario = Scenario(
        name=f'gen_{n_objects}_{density:g}_{seed}',
        objects=(*objects, table),
        drop_zone_center=DROP_ZONE_CENTER,
        drop_zone_size=DROP_ZONE_SIZE,
        home=tuple(float(v) for v in HOME),
        description=f'generate_clutter(n_objects={n_objects}, density={density}, seed={seed})',
    )
    validate_scenario(scenario)
    return scenario
