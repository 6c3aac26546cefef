"""Seeded random cluttered scenes of household-sized objects for scaling studies (no ROS).

Objects (cylinders, and boxes with probability ``box_share``) are placed by random sequential
addition in a rectangle in front of the robot: x ≥ ``x_min``, centred on y = 0, width =
``ASPECT`` × depth. The rectangle's area is set by ``density`` = total footprint area / region
area (:func:`region_size`; a scene of at most ``SMALL_SCENE`` objects gets at least room for them,
hence may have a lower density). The obstacles are ``'O1'``… in order of increasing distance from
the base. The same arguments always give the same scene.

Two random layouts, and four packed household ones (:mod:`qtree_scene.packed_layouts`:
``packed_rows``, ``packed_ring``, ``packed_shelf``, ``packed_mixed``; real object sizes, 1-2.5 cm
gaps; ``density`` and the shape ranges do not apply to them):

* ``'accessible'`` (default): the target ``'T'`` (a shape the open hand closes on, at most
  ``HAND_OPENING_M`` across) is placed first, inside the side-grasp workspace; then the others,
  largest first, each only where the scene stays clearable for the 2-D swept hand of
  :mod:`qtree_scene.hand_access` (:func:`qtree_scene.layouts.accessible_layout`): removing the
  objects placed with a free approach, in the reverse order of placement, leaves every one of
  them, and last the target, an approach free of what still stands. Layouts are redrawn (at most
  ``LAYOUT_RESTARTS``, then the last one is kept) until the target stands among the clutter: some
  object nearer the base in its approach corridor, some farther from the base, and every one of
  the planner's approaches blocked in the 2-D model. The model is the cautious side (margins,
  heights ignored), so the planner may still grasp such a target untouched, e.g. over a short
  neighbour; the benchmark counts how often.
* ``'uniform'``: plain random sequential addition, largest first, the target then drawn among the
  graspable objects in the workspace, preferably among the clutter. Most dense scenes of this
  layout are not retrievable (``benchmarks/results/clutter_solvable.md``).

Whether the target can actually be retrieved by the motion planner is checked outside this
package (``qtree_benchmarks.task.clutter.generate_retrievable``); the 2-D model is a necessary
condition for the planner's corridor test, not a sufficient one (IK, joint limits, arm links).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import numpy as np
from jaco2_description.model import HAND_OPENING_M, HOME

from qtree_scene.exceptions import ScenarioError
from qtree_scene.footprint import Footprint
from qtree_scene.hand_access import free_yaws
from qtree_scene.layouts import (
    Region,
    Shape,
    accessible_layout,
    in_clutter,
    pick_target,
    uniform_layout,
)
from qtree_scene.packed_layouts import PACKED_LAYOUTS, packed_layout
from qtree_scene.placement import DROP_TABLE_REACH_M
from qtree_scene.scenario import TABLE_ID, validate_scenario
from qtree_scene.scene import ObjectSpec, Role, Scenario

MAX_DENSITY = 0.4  # random sequential addition of mixed shapes jams near 0.45; stay below [-]
ASPECT = 1.75  # region width (y) / depth (x) [-]
DROP_ZONE_CENTER = (0.0, 0.5, 0.15)  # [m]
DROP_ZONE_SIZE = (0.3, 0.3, 0.3)  # [m]
# Table edge behind the robot base [m]: the table reaches all around the base, so that the drop
# slots of qtree_scene.placement (beside and behind the robot) have room for 30 relocations+.
TABLE_X_MIN = -DROP_TABLE_REACH_M
TABLE_MARGIN = 0.1  # table border around the clutter region [m]
RADIUS_LIMITS = (0.01, 0.08)  # accepted radius_range bounds [m]
HEIGHT_LIMITS = (0.03, 0.4)  # accepted height_range bounds [m]
SMALL_SCENE = 3  # scenes of at most this many objects get room for them at any density [-]
LAYOUT_RESTARTS = 8  # fresh layouts tried before the density is declared impossible [-]
# Near edge of the clutter region per layout [m]: the accessible layout starts where objects
# can be carried away (CARRY_MIN_REACH_M, minus a small object's radius).
X_MIN_M = {'accessible': 0.42, 'uniform': 0.35}
Layout = Literal[
    'accessible', 'uniform', 'packed_rows', 'packed_ring', 'packed_shelf', 'packed_mixed'
]
LAYOUTS: tuple[str, ...] = ('accessible', 'uniform', *PACKED_LAYOUTS)
KEEPOUT_M = 0.2  # the scenarios' default robot keep-out radius [m]


def region_size(footprint_area: float, density: float) -> tuple[float, float]:
    """Depth (x) and width (y) [m] of the clutter rectangle holding ``footprint_area`` [m²]."""
    area = footprint_area / density  # [m²]
    depth = math.sqrt(area / ASPECT)
    return depth, ASPECT * depth


def footprint_area(obj: ObjectSpec) -> float:
    """Area of an object's footprint on the table [m²]."""
    return math.pi * obj.radius**2 if obj.shape == 'cylinder' else obj.size[0] * obj.size[1]


def _check_arguments(
    n_objects: object,
    density: object,
    radius_range: tuple[float, float],
    height_range: tuple[float, float],
    box_share: float,
    gap: float,
) -> None:
    source = 'generate_clutter'
    if isinstance(n_objects, bool) or not isinstance(n_objects, int) or n_objects < 0:
        raise ScenarioError(source, 'n_objects', f'must be an int ≥ 0, got {n_objects!r}')
    if (
        isinstance(density, bool)
        or not isinstance(density, (int, float))
        or not (math.isfinite(density) and 0 < density <= MAX_DENSITY)
    ):
        raise ScenarioError(source, 'density', f'must be in (0, {MAX_DENSITY}], got {density}')
    for name, (lo, hi), (low, high) in (
        ('radius_range', radius_range, RADIUS_LIMITS),
        ('height_range', height_range, HEIGHT_LIMITS),
    ):
        if not (math.isfinite(lo) and math.isfinite(hi) and low <= lo <= hi <= high):
            raise ScenarioError(
                source, name, f'must satisfy {low} ≤ low ≤ high ≤ {high} m, got {(lo, hi)}'
            )
    if 2 * radius_range[0] > HAND_OPENING_M:
        problem = f'low end {radius_range[0]} m: no object the {HAND_OPENING_M} m hand holds'
        raise ScenarioError(source, 'radius_range', problem)
    if not (math.isfinite(box_share) and 0.0 <= box_share <= 1.0):
        raise ScenarioError(source, 'box_share', f'must be in [0, 1], got {box_share}')
    if not (math.isfinite(gap) and 0 < gap <= 0.1):
        raise ScenarioError(source, 'gap', f'must be in (0, 0.1] m, got {gap}')


def _draw_shapes(
    rng: np.random.Generator,
    n: int,
    radius_range: tuple[float, float],
    height_range: tuple[float, float],
    box_share: float,
) -> list[Shape]:
    """Cylinders of radius in ``radius_range``; boxes with edges in 2 × ``radius_range``.

    The first shape's half widths are clipped to ``HAND_OPENING_M`` / 2, and a box's footprint
    diagonal to ``HAND_OPENING_M``, so that every scene has an object the hand can close on from
    any approach yaw (the target's candidates, :func:`_pick_target`; #30: the planner now
    compares the width across the fingers at the approach, and an 82 x 75 mm target at a random
    yaw was 83-111 mm across at every approach but the two side ones).
    """
    shapes = []
    for index in range(n):
        box = bool(rng.random() < box_share)
        radius = float(rng.uniform(*radius_range))
        sx, sy = (float(v) for v in 2 * rng.uniform(*radius_range, 2))
        if index == 0:
            radius, sx, sy = (min(v, HAND_OPENING_M / 2) for v in (radius, sx / 2, sy / 2))
            sx, sy = 2 * sx, 2 * sy
            if math.hypot(sx, sy) > HAND_OPENING_M:  # the longer edge gives way, the shorter
                short = min(sx, sy, HAND_OPENING_M / math.sqrt(2.0))  # stays in its range
                long = math.sqrt(HAND_OPENING_M**2 - short**2) * (1.0 - 1e-9)
                sx, sy = (short, long) if sx <= sy else (long, short)
        height = float(rng.uniform(*height_range))
        if box:
            shapes.append(Shape(True, 0.0, sx, sy, height))
        else:
            shapes.append(Shape(False, radius, 2 * radius, 2 * radius, height))
    return shapes


def generate_clutter(
    n_objects: int,
    density: float,
    seed: int,
    *,
    radius_range: tuple[float, float] = (0.02, 0.05),
    height_range: tuple[float, float] = (0.08, 0.25),
    box_share: float = 0.3,
    gap: float = 0.01,
    x_min: float | None = None,
    attempts: int = 3000,
    layout: Layout = 'accessible',
) -> Scenario:
    """Random non-overlapping household-sized objects in front of the robot, seeded.

    Args:
        n_objects: number of obstacles N_o (≥ 0); one target is added.
        density: total footprint area / clutter region area, in (0, 0.4] (0.1–0.35 realistic).
        seed: seed of the numpy generator; the same arguments give the same scene.
        radius_range: cylinder radii, and half the box edges, are uniform in this range [m].
        height_range: object heights are uniform in this range [m].
        box_share: probability that an object is a box (random yaw) instead of a cylinder [-].
        gap: minimum free distance between two footprints [m], > 0.
        x_min: near edge of the region [m] (clear of the robot keep-out disc); default
            ``X_MIN_M[layout]``.
        attempts: placement tries per object and layout; at most ``LAYOUT_RESTARTS`` layouts
            are tried, so the generator always terminates.
        layout: ``'accessible'``: every object the arm can carry away is placed only where a
            side-grasp approach stays free of the objects placed before it, and every other
            object only where it leaves each of those a free approach, so that removing them in
            the reverse order clears the target for the 2-D hand model of
            :mod:`qtree_scene.hand_access` (the target is placed first, in the workspace).
            ``'uniform'``: plain random sequential addition, the target drawn afterwards (the
            generator before issue #14's solvability work; many scenes are not retrievable).
            ``'packed_*'``: household objects packed 1-2.5 cm apart around or in front of the
            target (:mod:`qtree_scene.packed_layouts`); ``density``, the shape ranges,
            ``box_share``, ``gap`` and ``x_min`` are checked but not used.

    Returns:
        A validated scenario named ``gen_<n>_<density>_<seed>``.

    Raises:
        ScenarioError: an argument out of range (field = its name), or no layout found within the
            budget (field ``'density'``: too dense to pack) or no graspable object landed in the
            side-grasp workspace (field ``'density'``).
    """
    _check_arguments(n_objects, density, radius_range, height_range, box_share, gap)
    if layout not in LAYOUTS:
        raise ScenarioError(
            'generate_clutter', 'layout', f'must be one of {LAYOUTS}, got {layout!r}'
        )
    x_min = X_MIN_M.get(layout, 0.35) if x_min is None else x_min
    if not (isinstance(x_min, (int, float)) and math.isfinite(x_min) and 0.0 < x_min <= 1.0):
        raise ScenarioError('generate_clutter', 'x_min', f'must be in (0, 1] m, got {x_min!r}')
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ScenarioError('generate_clutter', 'seed', f'must be an int ≥ 0, got {seed!r}')
    rng = np.random.default_rng(int(seed))
    if layout in PACKED_LAYOUTS:
        return _packed(layout, rng, n_objects, density, seed)
    n = n_objects + 1
    shapes = _draw_shapes(rng, n, radius_range, height_range, box_share)
    depth, width = region_size(sum(s.area for s in shapes), float(density))
    smallest = (2 * max(s.bound for s in shapes) + gap) * math.sqrt(n) * 1.5
    if n <= SMALL_SCENE and depth < smallest:  # room for a tiny scene's objects
        depth, width = smallest, ASPECT * smallest
    region = Region(depth, width, x_min, gap, attempts)
    footprints, target = None, None
    if layout == 'accessible':
        for _ in range(LAYOUT_RESTARTS):
            found = accessible_layout(rng, shapes, region)
            if found is not None:
                footprints, target = found, 0
                if in_clutter(0, found, shapes) and not free_yaws(found[0].center, found[1:]):
                    break  # every planner approach blocked in the 2-D model
    else:
        for _ in range(LAYOUT_RESTARTS):
            footprints = uniform_layout(rng, shapes, region)
            if footprints is not None:
                target = pick_target(rng, footprints, shapes)
                if target is not None:
                    break
    if footprints is None:
        problem = f'cannot pack {n} objects at density {density} in {LAYOUT_RESTARTS} tries'
        raise ScenarioError('generate_clutter', 'density', problem + '; lower it')
    if target is None:
        problem = f'no graspable object landed in the side-grasp workspace at density {density}'
        raise ScenarioError('generate_clutter', 'density', problem + '; raise it')
    scenario = _assemble(n_objects, density, seed, shapes, footprints, target, depth, width, x_min)
    validate_scenario(scenario)
    return scenario


def _packed(
    layout: str, rng: np.random.Generator, n_objects: int, density: float, seed: int
) -> Scenario:
    for _ in range(LAYOUT_RESTARTS):
        found = packed_layout(layout, rng, n_objects, KEEPOUT_M)
        if found is not None:
            break
    else:
        problem = f'{layout} holds no {n_objects} obstacles in {LAYOUT_RESTARTS} tries'
        raise ScenarioError('generate_clutter', 'n_objects', problem + '; ask fewer')
    shapes, footprints = found
    x_min = min(f.center[0] for f in footprints) - 0.12
    depth = max(f.center[0] for f in footprints) + 0.12 - x_min
    width = 2 * max(abs(f.center[1]) for f in footprints) + 0.24
    scenario = _assemble(n_objects, density, seed, shapes, footprints, 0, depth, width, x_min)
    scenario = dataclasses.replace(
        scenario,
        name=f'{layout}_{n_objects}_{seed}',
        description=f'generate_clutter(n_objects={n_objects}, seed={seed}, layout={layout!r})',
    )
    validate_scenario(scenario)
    return scenario


def _assemble(
    n_objects: int,
    density: float,
    seed: int,
    shapes: list[Shape],
    footprints: list[Footprint],
    target: int,
    depth: float,
    width: float,
    x_min: float,
) -> Scenario:
    others = sorted(
        (k for k in range(len(shapes)) if k != target),
        key=lambda k: math.hypot(*footprints[k].center),
    )
    objects = []
    for rank, k in enumerate([*others, target], start=1):
        s, fp = shapes[k], footprints[k]
        is_target = k == target
        position = (fp.center[0], fp.center[1], s.height / 2)
        object_id = 'T' if is_target else f'O{rank}'
        object_role: Role = 'target' if is_target else 'obstacle'
        if s.box:
            size = (s.sx, s.sy, s.height)
            spec = ObjectSpec(object_id, object_role, 'box', position, fp.yaw, size=size)
        else:
            spec = ObjectSpec(
                object_id, object_role, 'cylinder', position, radius=s.radius, height=s.height
            )
        objects.append(spec)
    x_max = x_min + depth + TABLE_MARGIN
    half_y = max(DROP_ZONE_CENTER[1] + DROP_ZONE_SIZE[1] / 2, width / 2) + TABLE_MARGIN
    half_y = max(half_y, DROP_TABLE_REACH_M)  # room for the drop slots beside the robot
    table = ObjectSpec(
        id=TABLE_ID,
        role='static',
        shape='box',
        position=((TABLE_X_MIN + x_max) / 2, 0.0, -0.025),
        size=(x_max - TABLE_X_MIN, 2 * half_y, 0.05),
    )
    return Scenario(
        name=f'gen_{n_objects}_{density:g}_{seed}',
        objects=(*objects, table),
        drop_zone_center=DROP_ZONE_CENTER,
        drop_zone_size=DROP_ZONE_SIZE,
        home=tuple(float(v) for v in HOME),
        description=(
            f'generate_clutter(n_objects={n_objects}, density={density}, seed={seed}): '
            f'region x [{x_min:.3f}, {x_min + depth:.3f}] m, |y| ≤ {width / 2:.3f} m'
        ),
    )
