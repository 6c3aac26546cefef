"""2-D footprints of objects standing on the table: circles and rotated rectangles (no ROS).

Used by scenario validation: two objects may not overlap on the table, and no object may enter
the keep-out disc around the robot base.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from qtree_scene.scene import ObjectSpec


@dataclass(frozen=True)
class Footprint:
    """Outline of an object on the table plane (world x, y).

    Attributes:
        center: centre [m], shape (2,).
        yaw: rotation about world z [rad] (rectangles only).
        radius: circle radius [m], 0 for rectangles.
        half_size: rectangle half edges along its own x, y [m]; (0, 0) for circles.
    """

    center: tuple[float, float]
    yaw: float = 0.0
    radius: float = 0.0
    half_size: tuple[float, float] = (0.0, 0.0)

    @property
    def is_circle(self) -> bool:
        """True for a circle, False for a rectangle."""
        return self.radius > 0.0

    def corners(self) -> np.ndarray:
        """Rectangle corners in the world plane [m], shape (4, 2)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        hx, hy = self.half_size
        local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
        return local @ np.array([[c, s], [-s, c]]) + np.asarray(self.center)

    def distance_to_point(self, point: tuple[float, float]) -> float:
        """Distance [m] from ``point`` to the footprint (0 inside it)."""
        d = np.asarray(point, dtype=float) - np.asarray(self.center)
        if self.is_circle:
            return max(0.0, float(np.hypot(*d)) - self.radius)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        local = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
        outside = np.maximum(np.abs(local) - np.asarray(self.half_size), 0.0)
        return float(np.hypot(*outside))


def footprint_of(obj: ObjectSpec) -> Footprint:
    """Footprint of a scenario object (cylinder → circle, box → rotated rectangle)."""
    center = (obj.position[0], obj.position[1])
    if obj.shape == 'cylinder':
        return Footprint(center=center, radius=obj.radius)
    return Footprint(center=center, yaw=obj.yaw, half_size=(obj.size[0] / 2, obj.size[1] / 2))


def _axes(rect: Footprint) -> list[np.ndarray]:
    c, s = math.cos(rect.yaw), math.sin(rect.yaw)
    return [np.array([c, s]), np.array([-s, c])]


def overlap(a: Footprint, b: Footprint, gap: float = 0.0) -> bool:
    """Whether two footprints come closer than ``gap`` [m] (touching counts as overlap at gap 0).

    Circles: centre distance; circle and rectangle: distance from the centre to the rectangle;
    two rectangles: separating axis theorem over the four edge normals, grown by ``gap``.
    """
    if a.is_circle and b.is_circle:
        return math.dist(a.center, b.center) <= a.radius + b.radius + gap
    if a.is_circle or b.is_circle:
        circle, rect = (a, b) if a.is_circle else (b, a)
        return rect.distance_to_point(circle.center) <= circle.radius + gap
    ca, cb = a.corners(), b.corners()
    for axis in _axes(a) + _axes(b):
        pa, pb = ca @ axis, cb @ axis
        if pa.max() + gap < pb.min() or pb.max() + gap < pa.min():
            return False
    return True
