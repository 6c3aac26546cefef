"""The open hand from the URDF collision boxes, in the end-effector frame (no ROS import).

Used to check the hand constants of :mod:`qtree_scene.placement` (slot layout) and the grasp
opening of the planner (``OBJECT_TOO_BIG``). EE frame: z = approach, x = across the fingers,
y = up in a side grasp (:func:`~stpik_motion_planner.cartesian_path.grasp_rotation`).
"""

from __future__ import annotations

import itertools

import numpy as np
from jaco2_description.model import EE_FRAME, Jaco2Model


def _corners(geometry: object) -> np.ndarray:
    if hasattr(geometry, 'halfSide'):
        return np.array(list(itertools.product([-1.0, 1.0], repeat=3))) * geometry.halfSide
    r, h = float(geometry.radius), float(geometry.halfLength)
    a = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    ring = np.c_[r * np.cos(a), r * np.sin(a)]
    return np.vstack([np.c_[ring, np.full(24, z)] for z in (-h, h)])


def hand_points(robot: Jaco2Model) -> dict[str, np.ndarray]:
    """Corner points [m] of every body rigid with the EE (link 7 + fingers), EE frame, (k, 3)."""
    ee = robot.model.frames[robot.frame_id(EE_FRAME)]
    out = {}
    for link, g in zip(robot.collision_links, robot.geometry_model.geometryObjects, strict=True):
        if g.parentJoint != ee.parentJoint:
            continue
        joint_to_geometry = g.placement
        points = [ee.placement.actInv(joint_to_geometry.act(c)) for c in _corners(g.geometry)]
        out[link] = np.array(points)
    return out


def open_hand_box(robot: Jaco2Model) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned box (lower, upper) [m] (3,) in the EE frame containing the open hand."""
    points = np.vstack(list(hand_points(robot).values()))
    return points.min(axis=0), points.max(axis=0)


def finger_opening(robot: Jaco2Model) -> float:
    """Gap [m] across the open fingertips (EE x) at the EE origin height, inner faces."""
    tips = [p for name, p in hand_points(robot).items() if 'finger_tip' in name]
    positive = min(p[:, 0].min() for p in tips if p[:, 0].mean() > 0)
    negative = max(p[:, 0].max() for p in tips if p[:, 0].mean() < 0)
    return float(positive - negative)
