"""Grasp families of the planner: the paper's side grasp and a top grasp (#30). No ROS import.

EE frame: z = approach, x = across the fingers (the closing direction), y = z × x. Both families
are named by a yaw ψ [rad] and close the fingers along the same horizontal direction
v = (−sin ψ, cos ψ, 0), so :func:`~.hand_model.grasp_width` is the width across the fingers of
either:

* ``'side'`` (paper, Sect. 3.1): approach horizontal at ψ, EE y up, the hand at the object's
  mid-height (:func:`side_rotation`);
* ``'top'``: approach straight down, the fingers closing on the object's top
  (:data:`TOP_FINGER_REACH_M` below the EE origin), lift straight up (:func:`top_rotation`).
  In packed clutter the hand then passes above the neighbours instead of between them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from qtree_scene.scene import ObjectSpec

GRASP_FAMILIES = ('side', 'top')  # every family the planner knows, in no particular order
PAPER_GRASP_FAMILIES = ('side',)  # the paper's setting (Tables 1-3 are measured with it)
TOP_YAWS = 8  # closing directions of a top grasp, spanning a half turn [-]
# Open fingertips beyond the EE origin along the approach (hand_model: z up to 0.023 m) [m].
TOP_FINGER_REACH_M = 0.023
TOP_MIN_GRIP_M = 0.015  # shallowest top grasp: the EE origin this far below the top [m]


@dataclass(frozen=True)
class Approach:
    """One candidate grasp: its family and the yaw ψ [rad] naming its orientation."""

    family: str
    yaw: float

    def __str__(self) -> str:
        return f'{self.family} grasp at yaw {self.yaw:.2f} rad'


def side_rotation(yaw: float) -> np.ndarray:
    """Side-grasp EE orientation: z (approach) horizontal at ``yaw`` [rad], y up; shape (3, 3)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[-s, 0.0, c], [c, 0.0, s], [0.0, 1.0, 0.0]])


def top_rotation(yaw: float) -> np.ndarray:
    """Top-grasp EE orientation: z (approach) down, x (across the fingers) (−sin ψ, cos ψ, 0),
    as in a side grasp at the same ``yaw`` [rad]; shape (3, 3).
    """
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[-s, c, 0.0], [c, s, 0.0], [0.0, 0.0, -1.0]])


def rotation(approach: Approach) -> np.ndarray:
    """EE orientation (3, 3) of ``approach``."""
    if approach.family == 'top':
        return top_rotation(approach.yaw)
    return side_rotation(approach.yaw)


def top_yaws(position: Sequence[float] | np.ndarray, count: int = TOP_YAWS) -> list[float]:
    """Closing yaws of a top grasp [rad]: the fingers across the base direction first (the
    wrist's natural turn), then ±π/count, ±2π/count, ... (a half turn in all: the open hand
    is nearly symmetric under a half turn, joint 7 turns it further).
    """
    base = math.atan2(position[1], position[0])
    step = math.pi / count
    return [base + step * ((i + 1) // 2) * (1 if i % 2 else -1) for i in range(count)]


def candidate_approaches(
    position: Sequence[float] | np.ndarray,
    families: Sequence[str],
    side_yaws: Sequence[float] | np.ndarray,
) -> list[Approach]:
    """Every approach to try, family by family in the order of ``families``.

    Args:
        position: the object's centre [m] (3,).
        families: grasp families, each of :data:`GRASP_FAMILIES`.
        side_yaws: the side approaches' yaws [rad] (``cartesian_path.approach_yaws``).
    """
    out: list[Approach] = []
    for family in families:
        yaws = top_yaws(position) if family == 'top' else side_yaws
        out += [Approach(family, float(y)) for y in yaws]
    return out


def top_grasp_problem(obj: ObjectSpec, depth_m: float, table_clearance_m: float) -> str | None:
    """Why ``obj`` cannot be grasped from above, else None.

    Args:
        obj: the object.
        depth_m: how deep the EE origin may go below its top [m]
            (:meth:`~.hand_model.HandModel.top_grasp_depth`): at least :data:`TOP_MIN_GRIP_M`.
        table_clearance_m: room [m] the open fingertips keep above the table (the planner's
            obstacle activation distance plus its margin).
    """
    if depth_m < TOP_MIN_GRIP_M:
        return (
            f'{obj.id!r} does not go {TOP_MIN_GRIP_M * 1000:.0f} mm between the open fingers '
            f'from above ({depth_m * 1000:.0f} mm with the margin)'
        )
    height = obj.height if obj.shape == 'cylinder' else obj.size[2]
    needed = depth_m + TOP_FINGER_REACH_M + table_clearance_m
    if height < needed:
        return (
            f'{obj.id!r} is {height * 1000:.0f} mm tall, a top grasp needs {needed * 1000:.0f} mm '
            '(the open fingertips reach below its top)'
        )
    return None


def check_families(families: object) -> tuple[str, ...]:
    """``families`` as a tuple of grasp family names.

    Raises:
        ValueError: not a non-empty sequence of distinct names of :data:`GRASP_FAMILIES`.
    """
    if isinstance(families, str) or not isinstance(families, Sequence) or not families:
        raise ValueError(f'must be a non-empty list of {GRASP_FAMILIES}, got {families!r}')
    names = tuple(families)
    unknown = [f for f in names if f not in GRASP_FAMILIES]
    if unknown:
        raise ValueError(f'unknown grasp family {unknown[0]!r}: one of {GRASP_FAMILIES}')
    if len(set(names)) != len(names):
        raise ValueError(f'grasp families repeated: {list(names)}')
    return names
