"""Where generated objects may stand: the two layouts of ``generate_clutter`` (no ROS).

* :func:`uniform_layout`: random sequential addition, largest footprint first;
* :func:`accessible_layout`: the same, keeping the scene clearable by side grasps for the 2-D
  swept hand of :mod:`qtree_scene.hand_access` (the target first, then the others).

:func:`pick_target` draws the target of a uniform layout; :func:`in_clutter` says whether an
object stands among the clutter. Shapes are drawn by :mod:`qtree_scene.generator`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from functools import partial

import numpy as np
from jaco2_description.model import HAND_OPENING_M

from qtree_scene.footprint import Footprint, overlap
from qtree_scene.hand_access import blocked_yaws, bound, free_yaws

# Side-grasp workspace of the Jaco² j2s7s300 for the target: horizontal distance of the object
# axis from the base axis and its azimuth (isolated objects are graspable on x ∈ [0.3, 0.85] m,
# |y| ≤ 0.45 m; these bounds keep a margin so that a cleared target is always in reach).
WORKSPACE_REACH_M = (0.34, 0.72)  # [m]
WORKSPACE_AZIMUTH_RAD = 0.75  # |atan2(y, x)| ≤ this [rad]
CORRIDOR_HALF_WIDTH_M = 0.06  # half width of the hand's approach corridor toward the base [m]
# Approaches the accessible layout counts on: the radial one and every 0.2 rad up to ±0.8 rad.
# The planner tries up to ±1.6 rad, but on generated scenes the wide side approaches fail IK or a
# joint limit too often (and the transit from home passes over the neighbours) to be relied on.
CLEARING_APPROACHES = 9
# Objects nearer the base than this are not counted on by the accessible layout: the planner
# often fails them (link 3 meets the table, the transit from home sweeps the neighbours) [m].
CARRY_MIN_REACH_M = 0.45


@dataclass(frozen=True)
class Shape:
    """One drawn object before placement: a cylinder (radius) or a box (edges sx, sy), height."""

    box: bool
    radius: float
    sx: float
    sy: float
    height: float

    @property
    def area(self) -> float:
        """Footprint area [m²]."""
        return self.sx * self.sy if self.box else math.pi * self.radius**2

    @property
    def grasp_width(self) -> float:
        """Width the side-grasping hand closes on [m]: the diameter, or a box's narrower edge."""
        return min(self.sx, self.sy)

    @property
    def bound(self) -> float:
        """Radius of the footprint's bounding circle [m]."""
        return math.hypot(self.sx, self.sy) / 2 if self.box else self.radius


def in_side_grasp_workspace(position: tuple[float, ...]) -> bool:
    """Whether an object centred at ``position`` (x, y[, z]) [m] is inside the target workspace."""
    reach = math.hypot(position[0], position[1])
    azimuth = abs(math.atan2(position[1], position[0]))
    low, high = WORKSPACE_REACH_M
    return low <= reach <= high and azimuth <= WORKSPACE_AZIMUTH_RAD


@dataclass(frozen=True)
class Region:
    """The clutter rectangle and how a layout places objects in it.

    Attributes:
        depth: extent along x [m].
        width: extent along y, centred on y = 0 [m].
        x_min: x of the rectangle's edge nearer the base [m].
        gap: least clearance between two objects [m].
        attempts: random poses tried per object before the layout gives up.
    """

    depth: float
    width: float
    x_min: float
    gap: float
    attempts: int


def candidate(rng: np.random.Generator, s: Shape, region: Region) -> Footprint:
    """One random pose of shape ``s`` inside the clutter rectangle."""
    b = s.bound
    centre = (
        float(rng.uniform(region.x_min + b, region.x_min + region.depth - b)),
        float(rng.uniform(-region.width / 2 + b, region.width / 2 - b)),
    )
    if s.box:
        yaw = float(rng.uniform(-math.pi / 2, math.pi / 2))
        return Footprint(centre, yaw=yaw, half_size=(s.sx / 2, s.sy / 2))
    return Footprint(centre, radius=s.radius)


def overlaps_any(fp: Footprint, placed: Iterable[Footprint], gap: float) -> bool:
    """Whether footprint ``fp`` comes closer than ``gap`` [m] to any ``placed`` one."""
    # Cheap bounding test first; 2·gap because overlap() grows rectangles by gap per axis, up
    # to gap·√2 at their corners (two boxes corner to corner were never compared).
    b = bound(fp)
    return any(
        math.dist(f.center, fp.center) <= b + bound(f) + 2 * gap and overlap(fp, f, gap)
        for f in placed
    )


Accept = Callable[[int, Mapping[int, Footprint], Footprint], bool]  # (k, placed, pose)


def first_accepted(
    rng: np.random.Generator, s: Shape, region: Region, accept: Callable[[Footprint], bool]
) -> Footprint | None:
    """The first of ``region.attempts`` random poses of ``s`` that ``accept`` takes, or None
    (also when ``s`` is wider than the rectangle).
    """
    if 2 * s.bound > min(region.depth, region.width):
        return None
    for _ in range(region.attempts):
        fp = candidate(rng, s, region)
        if accept(fp):
            return fp
    return None


def sequential_addition(
    rng: np.random.Generator, shapes: list[Shape], order: list[int], region: Region, accept: Accept
) -> list[Footprint] | None:
    """Random sequential addition of ``shapes`` in ``order``; None when an object does not fit.

    Each object takes the first random pose for which ``accept(k, placed, pose)`` holds
    (``placed``: the footprints placed so far, by shape index).
    """
    placed: dict[int, Footprint] = {}
    for k in order:
        fp = first_accepted(rng, shapes[k], region, partial(accept, k, placed))
        if fp is None:
            return None
        placed[k] = fp
    return [placed[k] for k in range(len(shapes))]


def largest_first(shapes: list[Shape], indices: Iterable[int]) -> list[int]:
    """``indices`` ordered by decreasing footprint area (ties in their order)."""
    return sorted(indices, key=lambda i: -shapes[i].area)


def uniform_layout(
    rng: np.random.Generator, shapes: list[Shape], region: Region
) -> list[Footprint] | None:
    """Random sequential addition, largest footprint first; None when an object does not fit."""

    def accept(k: int, placed: Mapping[int, Footprint], fp: Footprint) -> bool:
        return not overlaps_any(fp, placed.values(), region.gap)

    return sequential_addition(
        rng, shapes, largest_first(shapes, range(len(shapes))), region, accept
    )


def movable(shape: Shape, center: tuple[float, float]) -> bool:
    """Whether the accessible layout counts on carrying the object away: the hand closes on it
    and it stands in the side-grasp workspace, farther than ``CARRY_MIN_REACH_M``.
    """
    return (
        shape.grasp_width <= HAND_OPENING_M
        and in_side_grasp_workspace(center)
        and math.hypot(*center) >= CARRY_MIN_REACH_M
    )


def accessible_layout(
    rng: np.random.Generator, shapes: list[Shape], region: Region
) -> list[Footprint] | None:
    """Random sequential addition that keeps the scene clearable by side grasps, or None.

    Shape 0 (the target) is placed first, inside the side-grasp workspace (where it is
    :func:`movable`), then the others largest first. A movable object where one of the first
    ``CLEARING_APPROACHES`` approaches is free of everything placed before it
    (:func:`~qtree_scene.hand_access.free_yaws`) joins the objects counted on for removal, with
    those approaches. Any other object (immovable, or no free approach) stays in the scene for
    good, so it is accepted only where every object counted on keeps at least one of its
    approaches. Removing the objects counted on in the reverse order of placement then always
    finds a free approach for each, the target last: the scene is clearable for the 2-D model.
    """
    free: dict[int, set[float]] = {}  # counted on for removal -> its free approaches [rad]

    def accept(k: int, placed: Mapping[int, Footprint], fp: Footprint) -> bool:
        if k == 0 and not movable(shapes[0], fp.center):
            return False
        if overlaps_any(fp, placed.values(), region.gap):
            return False
        if movable(shapes[k], fp.center):
            yaws = free_yaws(fp.center, placed.values(), CLEARING_APPROACHES)
            if yaws:
                free[k] = set(yaws)
                return True
        hits = {p: blocked_yaws(placed[p].center, y, fp) for p, y in free.items()}
        if all(free[p] - hits[p] for p in free):
            for p in free:
                free[p] -= hits[p]
            return True
        return False

    order = [0, *largest_first(shapes, range(1, len(shapes)))]
    return sequential_addition(rng, shapes, order, region, accept)


def in_clutter(k: int, footprints: list[Footprint], shapes: list[Shape]) -> bool:
    """Object k has a neighbour nearer the base in its approach corridor and one farther away."""
    c = np.asarray(footprints[k].center)
    reach = float(np.linalg.norm(c))
    axis = c / reach
    blocked = farther = False
    for i, fp in enumerate(footprints):
        if i == k:
            continue
        d = np.asarray(fp.center)
        along = float(d @ axis)
        lateral = abs(float(d[0] * axis[1] - d[1] * axis[0]))
        if along < reach and lateral < CORRIDOR_HALF_WIDTH_M + shapes[i].bound:
            blocked = True
        if float(np.linalg.norm(d)) > reach:
            farther = True
    return blocked and farther


def pick_target(
    rng: np.random.Generator, footprints: list[Footprint], shapes: list[Shape]
) -> int | None:
    """Index of the target: among the clutter if possible, always inside the workspace."""
    inside = [
        k
        for k, fp in enumerate(footprints)
        if in_side_grasp_workspace(fp.center) and shapes[k].grasp_width <= HAND_OPENING_M
    ]
    if not inside:
        return None
    if len(footprints) > 1:
        far = max(range(len(footprints)), key=lambda k: math.hypot(*footprints[k].center))
        inside = [k for k in inside if k != far] or inside
    cluttered = [k for k in inside if in_clutter(k, footprints, shapes)]
    pool = cluttered or inside
    return int(pool[int(rng.integers(len(pool)))])
