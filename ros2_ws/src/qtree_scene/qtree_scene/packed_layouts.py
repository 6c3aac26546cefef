"""Packed household layouts of the generator (#30 item 3): clutter as people leave it (no ROS).

Four patterns, all with household objects at their real sizes (:mod:`qtree_scene.household`)
and gaps of :data:`GAP_RANGE_M` (1-2.5 cm) between neighbours:

* ``packed_rows``: rows of objects side by side in front of the target (between it and the
  robot), the target alone in its row;
* ``packed_shelf``: shelf rows front to back, the target in the back row among its neighbours;
* ``packed_ring``: the objects packed around the target, nearest first (rings);
* ``packed_mixed``: boxes at mixed yaw packed around and in front of the target.

The target (a can, a glass or a small box) stands :data:`TARGET_REACH_M` from the base axis:
in reach of a side grasp and of a grasp from above. Every object stands within
:data:`CLUTTER_REACH_M` of the base axis and :data:`MAX_AZIMUTH_RAD` of straight ahead, so the
drop slots beside and behind the robot stay free. Rows run across the radial direction of the
target ("in front" = toward the base).
"""

from __future__ import annotations

import math

import numpy as np

from qtree_scene.footprint import Footprint
from qtree_scene.household import OBSTACLE_KINDS, TARGET_KINDS, draw_household, household_shape
from qtree_scene.layouts import Shape, overlaps_any

PACKED_LAYOUTS = ('packed_rows', 'packed_ring', 'packed_shelf', 'packed_mixed')
GAP_RANGE_M = (0.01, 0.025)  # free distance between packed neighbours [m]
TARGET_REACH_M = (0.52, 0.62)  # target centre from the base axis [m]
TARGET_AZIMUTH_RAD = 0.35  # |azimuth| of the target [rad]
CLUTTER_REACH_M = (0.3, 0.75)  # every object centre from the base axis [m]
MAX_AZIMUTH_RAD = 0.8  # |azimuth| of every object [rad]
ROW_HALF_WIDTH_M = 0.26  # half length of a row across the radial direction [m]
BOXES = ('small_box', 'small_box', 'food_box', 'food_box', 'cereal_box')  # drawn uniformly
RING_ANGLES = 48  # directions tried around the target by the ring packing [-]
STEP_M = 0.004  # radial step of the ring packing [m]


def footprint(shape: Shape, centre: tuple[float, float], yaw: float) -> Footprint:
    """The footprint of ``shape`` at ``centre`` [m] and ``yaw`` [rad]."""
    if shape.box:
        return Footprint(centre, yaw=yaw, half_size=(shape.sx / 2, shape.sy / 2))
    return Footprint(centre, radius=shape.radius)


def in_bounds(fp: Footprint, keepout: float) -> bool:
    """Centre within the clutter reach and azimuth, footprint clear of the keep-out disc."""
    reach = math.hypot(*fp.center)
    low, high = CLUTTER_REACH_M
    bound = fp.radius or math.hypot(*fp.half_size)
    return (
        low <= reach <= high
        and abs(math.atan2(fp.center[1], fp.center[0])) <= MAX_AZIMUTH_RAD
        and reach - bound > keepout
    )


def packed_layout(
    layout: str, rng: np.random.Generator, n_obstacles: int, keepout: float
) -> tuple[list[Shape], list[Footprint]] | None:
    """Shapes and footprints of one packed scene, the target first; None if N did not fit.

    Args:
        layout: one of :data:`PACKED_LAYOUTS`.
        rng: the generator's random numbers.
        n_obstacles: obstacles around the target.
        keepout: the robot keep-out radius [m].
    """
    target = household_shape(rng, TARGET_KINDS[int(rng.integers(len(TARGET_KINDS)))])
    reach = float(rng.uniform(*TARGET_REACH_M))
    azimuth = float(rng.uniform(-TARGET_AZIMUTH_RAD, TARGET_AZIMUTH_RAD))
    radial = np.array([math.cos(azimuth), math.sin(azimuth)])
    yaw = azimuth + math.pi / 2  # a box target's long side across the radial direction
    placed = [footprint(target, tuple(reach * radial), yaw)]
    kinds = BOXES if layout == 'packed_mixed' else OBSTACLE_KINDS
    shapes = [target, *draw_household(rng, n_obstacles, kinds)]
    if layout in ('packed_rows', 'packed_shelf'):
        ok = _rows(rng, shapes, placed, radial, reach, layout == 'packed_shelf', keepout)
    else:
        ok = _around(rng, shapes, placed, layout == 'packed_mixed', radial, keepout)
    return (shapes, placed) if ok else None


def _rows(
    rng: np.random.Generator,
    shapes: list[Shape],
    placed: list[Footprint],
    radial: np.ndarray,
    reach: float,
    shelf: bool,
    keepout: float,
) -> bool:
    """Rows across ``radial``: the target's row (its neighbours with ``shelf``), then rows in
    front of it, then behind it; each object beside the last one of its row, alternating
    sides, a random gap apart.
    """
    across = np.array([-radial[1], radial[0]])
    yaw = math.atan2(across[1], across[0])  # boxes' long side along the row
    target_depth = _depth(shapes[0])
    rows = [(reach, target_depth)]  # (distance along radial, half depth)
    pending = list(range(1, len(shapes)))
    row_ends = {0: [_half(shapes[0]), _half(shapes[0])]} if shelf else {}
    row = 0 if shelf else None
    front = reach - target_depth
    back = reach + target_depth
    while pending:
        if row is None or not _row_has_room(row_ends[row]):
            gap = float(rng.uniform(*GAP_RANGE_M))
            depth = max(_depth(shapes[k]) for k in pending[:4])
            if front - gap - 2 * depth > CLUTTER_REACH_M[0]:
                centre = front - gap - depth
                front = centre - depth
            elif back + gap + 2 * depth < CLUTTER_REACH_M[1]:
                centre = back + gap + depth
                back = centre + depth
            else:
                return False
            rows.append((centre, depth))
            row = len(rows) - 1
            row_ends[row] = [0.0, 0.0]
            first = True
        else:
            first = False
        k = pending.pop(0)
        ends = row_ends[row]
        side = 0 if ends[0] <= ends[1] else 1
        gap = float(rng.uniform(*GAP_RANGE_M))
        half = _half(shapes[k])
        offset = 0.0 if first else ends[side] + gap + half
        sign = 1.0 if side == 0 else -1.0
        if first:
            ends[0] = ends[1] = half
        else:
            ends[side] = offset + half
        xy = rows[row][0] * radial + sign * offset * across
        fp = footprint(shapes[k], (float(xy[0]), float(xy[1])), yaw)
        if not in_bounds(fp, keepout) or overlaps_any(fp, placed, GAP_RANGE_M[0] - 1e-9):
            ends[side] = math.inf  # that side of the row is full: the object tries again
            pending.insert(0, k)
            if math.isinf(ends[0]) and math.isinf(ends[1]):
                row = None
            continue
        placed.append(fp)
    return True


def _row_has_room(ends: list[float]) -> bool:
    return min(ends) < ROW_HALF_WIDTH_M


def _half(shape: Shape) -> float:
    """Half the extent along the row (a box's long side lies along it) [m]."""
    return max(shape.sx, shape.sy) / 2 if shape.box else shape.radius


def _depth(shape: Shape) -> float:
    """Half the extent across the row [m]."""
    return min(shape.sx, shape.sy) / 2 if shape.box else shape.radius


def _around(
    rng: np.random.Generator,
    shapes: list[Shape],
    placed: list[Footprint],
    mixed: bool,
    radial: np.ndarray,
    keepout: float,
) -> bool:
    """Each obstacle as near the target as it goes at a random gap, over :data:`RING_ANGLES`
    directions (the nearest wins: rings form); ``mixed``: boxes at random yaw, directions in
    front of the target (toward the base) and beside it only.
    """
    centre = np.asarray(placed[0].center)
    toward_base = math.atan2(-radial[1], -radial[0])
    for shape in shapes[1:]:
        gap = float(rng.uniform(*GAP_RANGE_M))
        yaw = float(rng.uniform(-math.pi, math.pi)) if mixed else math.atan2(radial[1], radial[0])
        start = float(rng.uniform(0.0, 2 * math.pi))
        best = _nearest(shape, placed, centre, yaw, gap, keepout, start, toward_base, mixed)
        if best is None and mixed:  # the front is full: behind the target too
            best = _nearest(shape, placed, centre, yaw, gap, keepout, start, 0.0, False)
        if best is None:
            return False
        placed.append(best[1])
    return True


def _nearest(
    shape: Shape,
    placed: list[Footprint],
    centre: np.ndarray,
    yaw: float,
    gap: float,
    keepout: float,
    start: float,
    toward_base: float,
    front: bool,
) -> tuple[float, Footprint] | None:
    """The free pose of ``shape`` nearest the target ``centre`` over the directions tried
    (``front``: within ±0.6 π of ``toward_base``, else all around from ``start``).
    """
    best = None
    for i in range(RING_ANGLES):
        if front:
            angle = toward_base + 0.6 * math.pi * (2 * i / (RING_ANGLES - 1) - 1)
        else:
            angle = start + 2 * math.pi * i / RING_ANGLES
        direction = np.array([math.cos(angle), math.sin(angle)])
        distance = placed[0].radius or min(placed[0].half_size)
        while distance < 0.35:
            fp = footprint(shape, tuple(centre + distance * direction), yaw)
            if not overlaps_any(fp, placed, gap):
                break
            distance += STEP_M
        else:
            continue
        if in_bounds(fp, keepout) and (best is None or distance < best[0]):
            best = (distance, fp)
    return best
