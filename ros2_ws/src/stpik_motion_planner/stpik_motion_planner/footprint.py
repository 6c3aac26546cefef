"""The part of the workspace one planner computation looked at (#32 item 4; no ROS import).

Every scene query of the planner (:meth:`.collision.RobotBodies.scene_proximities`,
``scene_clear``, :meth:`.collision.SceneWorld.probe_hits`) first culls its (body, object) pairs
with one lower bound (:func:`.kernels.scene_candidates`): a pair goes on to ``fcl.distance`` only
when the distance from the body's bounding-sphere centre ``c`` to a box around the object is
below the sphere's radius ``r`` plus the query's threshold ``t`` (at or below, for inclusive
queries). An object that no cull of a computation lets through never entered it: each step, and
the result, is the same bit for bit without it or with it anywhere such (#28's replay memo,
:class:`.collision.QueryLog`, rests on the same fact).

A query's result depends only on the objects it finds within its threshold (a proximity list,
a probe's hit list, a clearance bool that stops at its first hit): an object that no query of a
computation found never changed its course, and one that no query could find would not change
it either. A :class:`Footprint` is a recorder of those queries (``recorders`` of the robot
bodies and of the scene worlds): :meth:`Footprint.region` keeps the objects found, the balls
``(c, r + t)`` of the robot-body queries binned into cubic cells of :data:`CELL_M` (per cell the
largest reach), and each probe query's geometry and pose. :meth:`Region.may_meet` answers
whether a query could find an object: exactly for the probes, conservatively for the robot
bodies (never False for an object some ball reaches).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import fcl
import numpy as np
from qtree_scene.scene import ObjectSpec

from stpik_motion_planner.collision import (
    SceneQuery,
    cull_half_extents,
    probe_distance,
)
from stpik_motion_planner.result import PlanResult

CELL_M = 0.01  # edge of the cells the balls' centres are binned in [m]
# Farthest a ball's centre lies from its cell's centre [m] (half the cell's diagonal).
CELL_SLACK_M = 0.5 * math.sqrt(3.0) * CELL_M
BOUND_EPS_M = 1e-9  # rounding room of the bound comparison [m]
_CELL_OFFSET = 1 << 20  # cell indices shifted positive for the 21-bit packing (+-10 km) [-]


@dataclass(frozen=True)
class Region:
    """What a computation's scene queries looked at (:meth:`Footprint.region`).

    Attributes:
        centres: cells of the robot-body balls: their centres [m] (M, 3).
        reach: per cell, the largest ball radius (body radius + threshold) of a ball centred in
            it, plus :data:`CELL_SLACK_M` [m] (M,).
        met: the objects some query found within its threshold (a query's result depends on
            those only; as specs: a moved object is another spec).
        complete: every query of the computation was recorded (False: an answer reused from a
            memo that kept no queries, or a check made outside the queries, such as the
            verifier's).
        probes: the probe queries (:meth:`.collision.SceneWorld.probe_hits`) as
            ``(geometry, pose, threshold)``, checked exactly by :meth:`may_meet`.
        probe_centres: their balls' centres [m] (P, 3); probe_reach: radius + threshold [m] (P,).
    """

    centres: np.ndarray
    reach: np.ndarray
    met: frozenset[ObjectSpec]
    complete: bool
    probes: tuple[tuple[fcl.CollisionGeometry, fcl.Transform, float], ...] = ()
    probe_centres: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    probe_reach: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def may_meet(self, obj: ObjectSpec) -> bool:
        """Whether some query could find ``obj`` within its threshold (False is certain).

        Robot-body balls: a ball centred at ``c`` in a cell centred at ``g`` has
        ``|c - g| <= CELL_SLACK_M``, so ``dist(c, box) >= dist(g, box) - CELL_SLACK_M``; the
        cell's reach holds that slack, and a pair out of reach of its cull is never found.
        Probes: the cull's bound, then the probe's own ``fcl.distance`` to ``obj`` (the call
        :meth:`.collision.SceneWorld.probe_hits` makes), so their answer is exact.
        """
        if np.any(_box_distance(self.centres, obj) <= self.reach + BOUND_EPS_M):
            return True
        near = np.flatnonzero(_box_distance(self.probe_centres, obj) < self.probe_reach)
        if near.size == 0:
            return False
        for k in near:
            geometry, pose, threshold = self.probes[k]
            if probe_distance(obj, geometry, pose) < threshold:
                return True
        return False


def _box_distance(points: np.ndarray, obj: ObjectSpec) -> np.ndarray:
    """Distance [m] (N,) of ``points`` [m] (N, 3) to the box the culls bound ``obj`` with."""
    hx, hy, hz = cull_half_extents(obj)
    d = points - np.asarray(obj.position, dtype=float)
    cos, sin = math.cos(obj.yaw), math.sin(obj.yaw)
    x = np.maximum(np.abs(d[:, 0] * cos + d[:, 1] * sin) - hx, 0.0)
    y = np.maximum(np.abs(d[:, 1] * cos - d[:, 0] * sin) - hy, 0.0)
    z = np.maximum(np.abs(d[:, 2]) - hz, 0.0)
    return np.sqrt(x * x + y * y + z * z)


class Footprint:
    """A recorder of one computation's scene queries (see the module docstring).

    Use it where a ``list`` of :class:`~.collision.SceneQuery` is a recorder: push it on the
    ``recorders`` of the robot bodies and of every scene world probed, pop it after.
    """

    def __init__(self) -> None:
        self._queries: list[SceneQuery] = []
        self._complete = True
        self.why_incomplete = ''

    def append(self, query: SceneQuery, /) -> None:
        """Record one scene query."""
        self._queries.append(query)

    def extend(self, queries: Iterable[SceneQuery], /) -> None:
        """Record the queries of a result reused from a memo (they replay in this scene)."""
        self._queries.extend(queries)

    def lose(self, why: str) -> None:
        """Note that part of the computation was not recorded (``why``, for the log)."""
        self._complete = False
        self.why_incomplete = self.why_incomplete or why

    def __len__(self) -> int:
        return len(self._queries)

    def region(self) -> Region:
        """The robot-body balls binned in cells of :data:`CELL_M`, the probes, the objects met."""
        queries = self._queries
        met = frozenset().union(*[q.hits for q in queries])
        bodies = [q for q in queries if q.probe is None]
        probes = [q for q in queries if q.probe is not None]
        probe_centres = np.array([q.centres[0] for q in probes], dtype=float).reshape(-1, 3)
        probe_reach = np.array([q.radii[0] + q.threshold for q in probes], dtype=float)
        probe_list = tuple((*q.probe, q.threshold) for q in probes if q.probe is not None)
        centres, reach = _binned(bodies)
        return Region(centres, reach, met, self._complete, probe_list, probe_centres, probe_reach)


def _binned(queries: list[SceneQuery]) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres [m] (M, 3) of the queries' balls and each cell's reach [m] (M,)."""
    if not queries:
        return np.zeros((0, 3)), np.zeros(0)
    centres = np.concatenate([np.asarray(q.centres, dtype=float) for q in queries])
    reach = np.concatenate([np.asarray(q.radii, dtype=float) + q.threshold for q in queries])
    cells = np.floor(centres / CELL_M).astype(np.int64) + _CELL_OFFSET
    keys = (cells[:, 0] << 42) | (cells[:, 1] << 21) | cells[:, 2]
    order = np.lexsort((reach, keys))  # by cell, then reach: each cell's largest last
    keys, reach = keys[order], reach[order]
    last = np.r_[keys[1:] != keys[:-1], True]
    keys, largest = keys[last], reach[last]
    mask = (1 << 21) - 1
    cells = np.column_stack([keys >> 42, (keys >> 21) & mask, keys & mask]) - _CELL_OFFSET
    return (cells + 0.5) * CELL_M, largest + CELL_SLACK_M


@dataclass(frozen=True)
class PlannedAnswer:
    """An infeasible answer as :meth:`.planner.MotionPlanner.plan` gave it (before its blockers)
    and what its plan looked at.

    Attributes:
        result: the plan's answer, without blockers.
        region: its footprint (:meth:`Footprint.region`).
    """

    result: PlanResult
    region: Region
