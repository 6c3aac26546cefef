"""Household objects at their real sizes, for the packed layouts of the generator (no ROS).

Sizes [m] (cylinders: radius, height range; boxes: footprint edges x, y and height), as found on
a kitchen table or a pantry shelf (#30: the benchmark's objects were drawn from ranges that let
a side grasp clear them).
"""

from __future__ import annotations

import numpy as np

from qtree_scene.layouts import Shape

# name -> ('cylinder', radius, (h_low, h_high)) or ('box', (sx, sy), (h_low, h_high))
HOUSEHOLD: dict[str, tuple] = {
    'can': ('cylinder', 0.033, (0.115, 0.123)),
    'mug': ('cylinder', 0.04, (0.09, 0.1)),
    'glass': ('cylinder', 0.035, (0.12, 0.15)),
    'bottle': ('cylinder', 0.037, (0.22, 0.28)),
    'small_box': ('box', (0.08, 0.06), (0.09, 0.11)),
    'food_box': ('box', (0.14, 0.05), (0.18, 0.21)),
    'cereal_box': ('box', (0.19, 0.07), (0.27, 0.3)),
}
OBSTACLE_KINDS = tuple(HOUSEHOLD)
TARGET_KINDS = ('can', 'glass', 'small_box')  # narrow enough for the hand at some approach


def household_shape(rng: np.random.Generator, kind: str) -> Shape:
    """One object of ``kind`` (:data:`HOUSEHOLD`), its height drawn in the kind's range."""
    shape, size, (low, high) = HOUSEHOLD[kind]
    height = float(rng.uniform(low, high))
    if shape == 'cylinder':
        return Shape(False, float(size), 2 * float(size), 2 * float(size), height)
    return Shape(True, 0.0, float(size[0]), float(size[1]), height)


def draw_household(rng: np.random.Generator, n: int, kinds: tuple[str, ...]) -> list[Shape]:
    """``n`` objects of kinds drawn uniformly from ``kinds``."""
    return [household_shape(rng, kinds[int(rng.integers(len(kinds)))]) for _ in range(n)]
