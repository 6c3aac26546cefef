"""Sweep-first checks and blockers: which movable objects stand in the way (no ROS import).

For every candidate approach yaw of an object (:func:`.grasp_choice.candidate_yaws`) the
planner is run once in the scene with every movable object removed (statics only). An approach
that fails there is blocked by something immovable (reach, joint limits, the table). An approach
that succeeds gives a whole motion (pre-grasp, grasp, lift, carry with the object attached,
place, return); the arm and the carried object are swept densely along it and the distance of
every movable object of the full scene to the sweep is kept. Both are cached per object: they do
not depend on which objects are relocated.

A request ``(relocated, object)`` (:meth:`BlockerFinder.check`) is then answered so:

1. no working approach: infeasible with ``blocked_by_immovable=True`` and no ids;
2. a working approach whose sweep keeps :data:`HIT_MARGIN_M` from every remaining object: its
   motion, verified against the remaining objects every :data:`VERIFY_STEP_RAD` with the
   planner's safety margin, is the (feasible) answer: an object with a free approach is
   graspable whatever the planner's clutter heuristics (corridor box, STPIK deflections) say;
3. else the planner in the real scene on the working approaches; if it fails, the blockers of an
   approach are the objects, not yet relocated, closer than :data:`HIT_MARGIN_M` to its sweep;
   the answer names those of the approach with the fewest (ties: yaw order), nearest the base
   first. If that approach has none (step 2's verification failed narrowly), the objects within
   :data:`NEAR_MARGIN_M` of its sweep are named.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.result import PlanResult, Reason

if TYPE_CHECKING:
    from stpik_motion_planner.planner import MotionPlanner

HIT_MARGIN_M = 0.01  # an object closer than this to the swept arm blocks the approach [m]
NEAR_MARGIN_M = 0.05  # fallback: objects this close to the sweep deflect the arm [m]
SWEEP_STEP_RAD = 0.1  # largest joint change between two swept configurations [rad]
SWEEP_SLOT = 3  # drop slot of the sweeps' motions (the far corner: the arm stretched) [-]
VERIFY_STEP_RAD = 0.02  # the same when a reused motion is verified against the scene [rad]


@dataclass(frozen=True)
class Sweep:
    """One candidate approach of one object, planned with every movable object removed.

    Attributes:
        yaw: approach yaw [rad].
        works: the motion exists in the statics-only scene.
        distances: movable object id -> smallest distance to the swept arm or carried object
            [m], only objects closer than :data:`NEAR_MARGIN_M`.
        motion: the statics-only plan (when it works).
        failure: the statics-only answer (when it does not).
        slot: drop-zone slot index the motion places the object in.
    """

    yaw: float
    works: bool
    distances: dict[str, float]
    motion: PlanResult | None = None
    failure: PlanResult | None = None
    slot: int = -1

    def blockers(self, relocated: frozenset[str], margin: float) -> list[str]:
        """Ids within ``margin`` [m] of the sweep that are not relocated."""
        return [i for i, d in self.distances.items() if d <= margin and i not in relocated]


@dataclass(frozen=True)
class Blockers:
    """The blockers of one request.

    Attributes:
        ids: objects whose removal the planner believes necessary, nearest the base first.
        immovable: no approach works even with every movable object removed.
        yaw: yaw of the chosen approach [rad] (NaN when ``immovable``).
        clear: the chosen approach has no object within :data:`HIT_MARGIN_M` (``ids`` then
            holds the objects within :data:`NEAR_MARGIN_M`).
    """

    ids: tuple[str, ...]
    immovable: bool
    yaw: float = float('nan')
    clear: bool = False


class BlockerFinder:
    """Sweep-first checks and blockers for one :class:`~.planner.MotionPlanner`.

    Attributes:
        sweeps: per object id, approach index -> :class:`Sweep` (lazily filled).
        time_s: total wall time spent computing sweeps [s].
    """

    def __init__(self, planner: MotionPlanner) -> None:
        self.planner = planner
        self.sweeps: dict[str, dict[int, Sweep]] = {}
        self.time_s = 0.0

    def check(self, object_id: str, relocated: Iterable[str]) -> PlanResult:
        """Plan a valid request, using the object's sweeps (no cache; see the module docstring).

        Sweeps are computed lazily in yaw order: the first working approach whose sweep is clear
        and whose motion verifies ends the check (a free object costs one plan).
        """
        relocated = list(relocated)
        start = time.perf_counter()
        done = frozenset(relocated)
        for index in range(len(self._yaws(object_id))):
            sweep = self._sweep(object_id, index)
            if sweep.works and not sweep.blockers(done, HIT_MARGIN_M):
                reused = self._reuse(object_id, relocated, sweep)
                if reused is not None:
                    return replace(reused, planning_time=_since(start))
        sweeps = self._sweeps(object_id)
        working = [s for s in sweeps if s.works]
        if not working:
            first = sweeps[0].failure
            if any(s.failure.reason == Reason.TIMEOUT for s in sweeps):
                self.sweeps.pop(object_id, None)  # may work on a quieter machine
                return replace(first, reason=Reason.TIMEOUT, planning_time=_since(start))
            message = f'{first.message}; blocked by nothing movable (no approach in reach)'
            return replace(
                first, message=message, blocked_by_immovable=True, planning_time=_since(start)
            )
        result = self.planner.plan(object_id, relocated, yaws=[s.yaw for s in working])
        if result.feasible or not 200 <= int(result.reason) < 300:
            return replace(result, planning_time=_since(start))
        best = min(working, key=lambda s: len(s.blockers(done, HIT_MARGIN_M)))
        found = self._blockers(best, done)
        note = f'; blockers: {", ".join(found[:5])}' if found else '; no blocker found'
        return replace(
            result,
            message=result.message + note,
            blocking_ids=found,
            planning_time=_since(start),
        )

    def find(self, object_id: str, relocated: Iterable[str]) -> Blockers:
        """Blockers of relocating ``object_id`` once ``relocated`` are gone (valid request)."""
        done = frozenset(relocated)
        working = [s for s in self._sweeps(object_id) if s.works]
        if not working:
            return Blockers((), True)
        best = min(working, key=lambda s: len(s.blockers(done, HIT_MARGIN_M)))
        return Blockers(
            self._blockers(best, done), False, best.yaw, not best.blockers(done, HIT_MARGIN_M)
        )

    def _blockers(self, sweep: Sweep, done: frozenset[str]) -> tuple[str, ...]:
        ids = sweep.blockers(done, HIT_MARGIN_M) or sweep.blockers(done, NEAR_MARGIN_M)
        scenario = self.planner.scenario
        ids.sort(key=lambda i: (math.hypot(*scenario.object(i).position[:2]), i))
        return tuple(ids)

    def _reuse(self, object_id: str, relocated: list[str], sweep: Sweep) -> PlanResult | None:
        """The sweep's motion for this request's drop slot if it clears the remaining objects."""
        planner = self.planner
        scenario = planner.scenario
        obj = scenario.object(object_id)
        gone = {*relocated, object_id}
        movable = [o for o in scenario.objects if o.role != 'static' and o.id not in gone]
        result = sweep.motion
        if sweep.slot != len(relocated):
            others = [o.id for o in scenario.objects if o.role != 'static' and o.id != object_id]
            result = planner.plan(object_id, others, yaws=[sweep.yaw], slot_index=len(relocated))
        if result is None or not result.feasible:
            return None
        margin = planner.config.obstacle_min_distance_m
        distances = self._distances(result, obj, SceneWorld(movable), VERIFY_STEP_RAD)
        for name, d in distances.items():  # the fine check refines the coarse sweep
            sweep.distances[name] = min(sweep.distances.get(name, math.inf), d)
        if any(d <= margin for d in distances.values()):
            return None
        message = (
            f'feasible (approach yaw {sweep.yaw:.2f} rad; planned without the movable objects, '
            'verified against them)'
        )
        return replace(result, message=message)

    def _yaws(self, object_id: str) -> list[float]:
        from stpik_motion_planner.grasp_choice import candidate_yaws

        centre = np.asarray(self.planner.scenario.object(object_id).position, dtype=float)
        return candidate_yaws(centre, self.planner.config)

    def _sweeps(self, object_id: str) -> list[Sweep]:
        """Every candidate approach's sweep of ``object_id``."""
        return [self._sweep(object_id, i) for i in range(len(self._yaws(object_id)))]

    def _sweep(self, object_id: str, index: int) -> Sweep:
        """The sweep of approach ``index`` of ``object_id`` (computed once)."""
        cached = self.sweeps.setdefault(object_id, {})
        if index not in cached:
            start = time.perf_counter()
            cached[index] = self._compute(object_id, self._yaws(object_id)[index])
            self.time_s += time.perf_counter() - start
        return cached[index]

    def _compute(self, object_id: str, yaw: float) -> Sweep:
        planner = self.planner
        scenario = planner.scenario
        obj = scenario.object(object_id)
        movable = [o for o in scenario.objects if o.role != 'static' and o.id != object_id]
        others = [o.id for o in movable]
        result = planner.plan(object_id, others, yaws=[yaw], slot_index=SWEEP_SLOT)
        if not result.feasible:
            return Sweep(yaw, False, {}, failure=result)
        distances = self._distances(result, obj, SceneWorld(movable))
        return Sweep(yaw, True, distances, motion=result, slot=SWEEP_SLOT)

    def _distances(
        self, result: PlanResult, obj, scene: SceneWorld, step_rad: float = SWEEP_STEP_RAD
    ) -> dict[str, float]:
        """Smallest distance of each movable object to the arm along ``result``'s motion [m]."""
        stpik = self.planner.stpik
        robot = self.planner.robot
        q = result.joint_trajectory
        world_obj = pin.SE3(
            pin.rpy.rpyToMatrix(0.0, 0.0, obj.yaw), np.asarray(obj.position, dtype=float)
        )
        offset = pin.SE3(robot.ee_pose(q[result.grasp_index])).actInv(world_obj)
        found: dict[str, float] = {}
        try:
            for index in range(1, len(q)):
                if index == result.grasp_index + 1:
                    stpik.bodies.attach(obj, offset, settle_m=0.0)
                if index == result.release_index + 1:
                    stpik.bodies.detach()
                a, b = q[index - 1], q[index]
                n = max(1, math.ceil(float(np.max(np.abs(b - a))) / step_rad))
                for t in np.arange(1, n + 1) / n:
                    for p in self._near(a + (b - a) * t, scene):
                        found[p.name_b] = min(found.get(p.name_b, math.inf), p.distance)
        finally:
            stpik.bodies.detach()
        return {i: d for i, d in found.items() if d <= NEAR_MARGIN_M}

    def _near(self, q: np.ndarray, scene: SceneWorld) -> list:
        """(arm body, object) pairs closer than :data:`NEAR_MARGIN_M` at ``q`` [rad] (7,)."""
        s = self.planner.stpik
        pin.forwardKinematics(s.model, s.data, q)
        pin.updateFramePlacements(s.model, s.data)
        pin.updateGeometryPlacements(s.model, s.data, s.geometry_model, s.geometry_data)
        s.bodies.place(s.geometry_data.oMg, s.data.oMf[s.ee_frame])
        return s.bodies.scene_proximities(scene, NEAR_MARGIN_M)


def _since(start: float) -> float:
    return time.perf_counter() - start
