"""Which side-grasp approaches of an object are free, on the table plane (no ROS, no planner).

The Jaco² side grasp comes in horizontally: the approach axis points away from the base at one of
the yaws the motion planner tries (its azimuth, then ± ``YAW_STEP_RAD``, ± 2 · ``YAW_STEP_RAD``,
...), and the open hand sweeps from the pre-grasp (``STANDOFF_M`` back) to the grasp. Seen from
above, the swept hand is three rectangles along the approach axis, in metres from the object axis
(u along the approach, v across it), measured on the j2s7s300 URDF by
``stpik_motion_planner.hand_model`` (fingers at 0.2 rad):

* fingers:   |v| ≤ 0.105, u ∈ [−0.067 − standoff, 0.024];
* palm:      |v| ≤ 0.055, u ∈ [−0.161 − standoff, −0.038];
* wrist (link 6, radius 0.032): |v| ≤ 0.033, u ∈ [−0.296 − standoff, −0.160].

Each is grown by ``MARGIN_M``. ``stpik_motion_planner/test/test_hand_access.py`` checks that these
rectangles contain the planner's swept hand hull, so a yaw called blocked here is blocked for the
planner's corridor test too (the converse does not hold: the planner also needs IK and free arm
links). Heights are ignored: an object lower than the hand still counts as in the way.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from qtree_scene.footprint import Footprint, overlap

YAW_STEP_RAD = 0.2  # stpik_motion_planner PlannerConfig.approach_yaw_step_rad [rad]
APPROACH_DIRECTIONS = 17  # PlannerConfig.approach_directions [-]
STANDOFF_M = 0.1  # PlannerConfig.pregrasp_standoff_m [m]
MARGIN_M = 0.01  # growth of the hand rectangles [m] (planner failure distance 5 mm + slack)
# (half width across the approach, rear end, front end) of each swept hand part, before the
# standoff is added to the rear end [m].
HAND_PARTS_M: tuple[tuple[float, float, float], ...] = (
    (0.105, -0.067, 0.024),  # open fingers
    (0.055, -0.161, -0.038),  # palm (link 7)
    (0.033, -0.296, -0.160),  # wrist (link 6)
)


def approach_yaws(
    center: Sequence[float], count: int = APPROACH_DIRECTIONS, step: float = YAW_STEP_RAD
) -> list[float]:
    """Approach yaws [rad] in the planner's order: the azimuth of ``center``, then ±step, ..."""
    base = math.atan2(center[1], center[0])
    return [base + step * ((i + 1) // 2) * (1 if i % 2 else -1) for i in range(count)]


def swept_hand(center: Sequence[float], yaw: float) -> list[Footprint]:
    """Rectangles [m] covering the hand swept pre-grasp → grasp on an object at ``center``."""
    u = (math.cos(yaw), math.sin(yaw))
    parts = []
    for half_width, rear, front in HAND_PARTS_M:
        rear -= STANDOFF_M
        mid = (rear + front) / 2
        parts.append(
            Footprint(
                center=(center[0] + mid * u[0], center[1] + mid * u[1]),
                yaw=yaw,
                half_size=((front - rear) / 2 + MARGIN_M, half_width + MARGIN_M),
            )
        )
    return parts


# No point of the swept hand is farther than this from the object axis [m].
HAND_REACH_M = (
    math.hypot(
        max(STANDOFF_M - rear for _, rear, _ in HAND_PARTS_M), max(w for w, _, _ in HAND_PARTS_M)
    )
    + 2 * MARGIN_M
)


def bound(fp: Footprint) -> float:
    """Radius [m] of the circle about ``fp.center`` that contains the footprint."""
    return fp.radius if fp.is_circle else math.hypot(*fp.half_size)


def blocked_yaws(center: Sequence[float], yaws: Iterable[float], other: Footprint) -> set[float]:
    """The ``yaws`` [rad] whose swept hand at ``center`` meets the footprint ``other``."""
    if math.dist(center, other.center) > HAND_REACH_M + bound(other):
        return set()
    return {
        y
        for y in yaws
        if any(
            math.dist(part.center, other.center) <= bound(part) + bound(other)
            and overlap(part, other)
            for part in swept_hand(center, y)
        )
    }


def free_yaws(
    center: Sequence[float], others: Iterable[Footprint], count: int = APPROACH_DIRECTIONS
) -> list[float]:
    """The first ``count`` approach yaws [rad] at ``center`` whose swept hand meets no others."""
    yaws = approach_yaws(center, count)
    blocked: set[float] = set()
    for other in others:
        blocked |= blocked_yaws(center, [y for y in yaws if y not in blocked], other)
        if len(blocked) == len(yaws):
            return []
    return [y for y in yaws if y not in blocked]
