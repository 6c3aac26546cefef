"""Blockers of an infeasible relocation: which movable objects stand in the way (no ROS import).

For every candidate approach of an object (every other one of the planner's own side yaws
``approach_yaws`` and, when it grasps from above too, of its top yaws, :mod:`.grasps`) the planner
is run once in the scene with every movable object removed (statics only). An approach that
fails there is blocked by something immovable (reach, joint limits, the table). An approach that
succeeds gives a whole motion (pre-grasp, grasp, lift, carry with the object attached, place,
return); the arm and the carried object are swept densely along it and the distance of every
movable object of the full scene to the sweep is kept. Both are cached per object: they do not
depend on which objects are relocated. The sweeps share the request's time limit: when it runs
out before every approach was swept, the answer names the blockers of the approaches swept so far
(never ``blocked_by_immovable``) and says so; the next uncached request about that object goes on
from the first approach not swept yet.

For a request ``(relocated, object)`` the blockers of an approach are the objects, not yet
relocated, closer than :data:`HIT_MARGIN_M` to its sweep. The answer is the approach with the
fewest blockers (ties: the planner's yaw order); its blockers sorted nearest the base first.
Every working approach's blockers are reported too (``approach_blockers``, fewest first): the
object needs all blockers of one approach removed, which a task planner can use (a hitting set).
When every working approach is free of blockers at that margin (the planner failed although the
swept motion is clear: its own Cartesian path differed), the objects within
:data:`NEAR_MARGIN_M` of the best sweep are named instead. No working approach at all gives
``blocked_by_immovable=True`` and no ids.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from qtree_scene.scene import ObjectSpec

from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.result import PlanResult, Reason, ReasonFamily, reason_family

if TYPE_CHECKING:
    from stpik_motion_planner.geometric_planner import GeometricPlanner

HIT_MARGIN_M = 0.01  # an object closer than this to the swept arm blocks the approach [m]
NEAR_MARGIN_M = 0.05  # fallback: objects this close to the sweep deflect the arm [m]
SWEEP_STEP_RAD = 0.05  # largest joint change between two swept configurations [rad]


@dataclass(frozen=True)
class Sweep:
    """One candidate approach of one object, planned with every movable object removed.

    Attributes:
        yaw: approach yaw [rad].
        works: the motion exists in the statics-only scene.
        distances: movable object id -> smallest distance to the swept arm or carried object
            [m], only objects closer than :data:`NEAR_MARGIN_M`.
        family: grasp family of the approach (:mod:`.grasps`).
        motion: the statics-only answer swept (None when it does not work), kept to measure
            the distances again after a scene change (:meth:`BlockerFinder.adopt`).
    """

    yaw: float
    works: bool
    distances: dict[str, float]
    family: str = 'side'
    motion: PlanResult | None = field(default=None, compare=False, repr=False)

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
        complete: every approach was swept (False: the time limit ran out first).
        approaches: the blockers of every working approach swept, fewest first (ties: yaw
            order), each nearest the base first.
    """

    ids: tuple[str, ...]
    immovable: bool
    yaw: float = float('nan')
    complete: bool = True
    approaches: tuple[tuple[str, ...], ...] = ()


class BlockerFinder:
    """Blockers for the requests of one :class:`~stpik_motion_planner.planner.MotionPlanner`,
    swept with its :class:`~.geometric_planner.GeometricPlanner` (no cache).

    Attributes:
        sweeps: per object id, one :class:`Sweep` per candidate approach (lazily filled).
        time_s: total wall time spent computing sweeps [s].
    """

    def __init__(self, planner: GeometricPlanner) -> None:
        self.planner = planner
        self.sweeps: dict[str, list[Sweep]] = {}
        self.partial: dict[str, list[Sweep]] = {}  # objects whose sweeps the deadline cut short
        self.time_s = 0.0
        # False: answers go out without blockers (benchmarks timing the planner alone).
        self.enabled = True

    def find(
        self, object_id: str, relocated: Iterable[str], deadline: float = math.inf
    ) -> Blockers:
        """Blockers of relocating ``object_id`` once ``relocated`` are gone (valid request).

        Args:
            object_id: the object to relocate.
            relocated: the objects already relocated.
            deadline: ``time.perf_counter()`` value by which to stop sweeping [s].
        """
        done = frozenset(relocated)
        sweeps, complete = self._sweeps(object_id, deadline)
        working = [s for s in sweeps if s.works]
        if not working:
            return Blockers((), complete, complete=complete)
        best = min(working, key=lambda s: len(s.blockers(done, HIT_MARGIN_M)))
        ids = best.blockers(done, HIT_MARGIN_M)
        if not ids:
            ids = best.blockers(done, NEAR_MARGIN_M)
        approaches = sorted(
            (tuple(self._from_base(s.blockers(done, HIT_MARGIN_M))) for s in working), key=len
        )
        return Blockers(tuple(self._from_base(ids)), False, best.yaw, complete, tuple(approaches))

    def _from_base(self, ids: list[str]) -> list[str]:
        """``ids`` sorted nearest the base first (ties: by id)."""
        scenario = self.planner.scenario
        return sorted(ids, key=lambda i: (math.hypot(*scenario.object(i).position[:2]), i))

    def annotate(
        self,
        result: PlanResult,
        object_id: str,
        relocated: Iterable[str],
        deadline: float = math.inf,
    ) -> PlanResult:
        """``result`` with its blockers when it is an infeasible planning answer (2xx).

        Args:
            result: the planner's answer.
            object_id: the object it is about.
            relocated: the objects already relocated.
            deadline: ``time.perf_counter()`` value by which the sweeps stop [s].

        Returns:
            The annotated answer; when the deadline cut the sweeps short, its blockers are those
            of the approaches swept so far and its message says so.
        """
        if not self.enabled or result.feasible:
            return result
        if reason_family(result.reason) != ReasonFamily.PLANNING_FAILURE:
            return result
        start = time.perf_counter()
        found = self.find(object_id, relocated, deadline)
        spent = time.perf_counter() - start
        timings = {**result.timings, 'blockers': spent}
        if not found.complete:
            named = ', '.join(found.ids[:5]) or 'none yet'
            message = f'{result.message}; blockers (time limit hit, not every approach swept): '
            message += named
        elif found.immovable:
            message = f'{result.message}; blocked by nothing movable (no approach in reach)'
        elif found.ids:
            message = f'{result.message}; blockers: {", ".join(found.ids[:5])}'
        else:
            message = f'{result.message}; no blocker found'
        return replace(
            result,
            message=message,
            blocking_ids=found.ids,
            blocked_by_immovable=found.immovable,
            approach_blockers=found.approaches,
            planning_time=result.planning_time + spent,
            timings=timings,
        )

    def _sweeps(self, object_id: str, deadline: float) -> tuple[list[Sweep], bool]:
        """The object's sweeps and whether every approach has been swept."""
        if object_id in self.sweeps:
            return self.sweeps[object_id], True
        start = time.perf_counter()
        sweeps = self.partial.pop(object_id, [])
        complete = self._compute(object_id, sweeps, deadline)
        self.time_s += time.perf_counter() - start
        (self.sweeps if complete else self.partial)[object_id] = sweeps
        return sweeps, complete

    def _compute(self, object_id: str, out: list[Sweep], deadline: float) -> bool:
        """Append the sweeps after the ``len(out)`` done to ``out``; False if cut short."""
        from stpik_motion_planner.cartesian_path import approach_yaws
        from stpik_motion_planner.grasps import candidate_approaches, top_yaws

        planner = self.planner
        c = planner.config
        scenario = planner.scenario
        obj = scenario.object(object_id)
        movable = [o for o in scenario.objects if o.role != 'static' and o.id != object_id]
        others = [o.id for o in movable]
        full = SceneWorld(movable)
        centre = np.asarray(obj.position, dtype=float)
        # Every other approach of the planner (twice its step): blocker reports are a heuristic,
        # one sweep per object and yaw is their whole cost.
        count, step = (c.approach_directions + 1) // 2, 2 * c.approach_yaw_step_rad
        side = approach_yaws(centre, count, step)
        approaches = candidate_approaches(centre, c.grasp_families, side)
        if 'top' in c.grasp_families:  # every other top yaw too, like the side ones
            top = set(top_yaws(centre)[::2])
            approaches = [a for a in approaches if a.family != 'top' or a.yaw in top]
        for approach in approaches[len(out) :]:
            if time.perf_counter() >= deadline:
                return False
            result = planner.plan(
                object_id, others, slot_index=0, deadline=deadline, approaches=[approach]
            )
            if result.reason == Reason.TIMEOUT and time.perf_counter() >= deadline:
                return False  # cut by the request's deadline (its own limit: a failed approach)
            if not result.feasible:
                out.append(Sweep(approach.yaw, False, {}, approach.family))
                continue
            distances = self._distances(result, obj, full)
            out.append(Sweep(approach.yaw, True, distances, approach.family, result))
        return True

    def adopt(self, old: BlockerFinder, changed: set[str], now: Iterable[ObjectSpec]) -> int:
        """Take the complete sweeps of ``old`` for the objects not in ``changed``; the number of
        objects whose sweeps were taken.

        The caller makes sure that the two planners share the statics, home and drop slot 0
        (:mod:`.answer_reuse`). WHY a sweep stays true: it is planned with every movable object
        removed, so its motion depends on the statics, home, slot 0 and the object only (all
        unchanged); its distances are those of the unchanged objects (same poses) and of the
        changed ones measured again here along the same motion, as they stand ``now``.

        Args:
            old: the blocker finder of the planner of the scene before the change.
            changed: ids of the objects that moved, appeared or disappeared.
            now: the changed objects as they stand in this finder's scene.
        """
        now = [o for o in now if o.role != 'static']
        taken = 0
        for object_id, sweeps in old.sweeps.items():
            if object_id in changed or object_id in self.sweeps:
                continue
            obj = self.planner.scenario.object(object_id)
            world = SceneWorld(o for o in now if o.id != object_id)
            adopted = []
            for sweep in sweeps:
                distances = {i: d for i, d in sweep.distances.items() if i not in changed}
                if sweep.works and world.objects:
                    if sweep.motion is None:
                        break  # a sweep made before motions were kept: cannot be measured
                    distances.update(self._distances(sweep.motion, obj, world))
                adopted.append(replace(sweep, distances=distances))
            else:
                self.sweeps[object_id] = adopted
                taken += 1
        return taken

    def _distances(self, result: PlanResult, obj, scene: SceneWorld) -> dict[str, float]:
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
                n = max(1, math.ceil(float(np.max(np.abs(b - a))) / SWEEP_STEP_RAD))
                for t in np.arange(1, n + 1) / n:
                    for p in self._near(a + (b - a) * t, scene):
                        found[p.name_b] = min(found.get(p.name_b, math.inf), p.distance)
        finally:
            stpik.bodies.detach()
        return {i: d for i, d in found.items() if d <= NEAR_MARGIN_M}

    def _near(self, q: np.ndarray, scene: SceneWorld) -> list:
        """(arm body, object) pairs closer than :data:`NEAR_MARGIN_M` at ``q`` [rad] (7,)."""
        s = self.planner.stpik
        s.place_bodies(q)
        return s.bodies.scene_proximities(scene, NEAR_MARGIN_M)
