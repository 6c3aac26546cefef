"""The geometric planner: one relocation planned with no cache (paper Sect. 3.1, Figure 2): the
grasp geometry of each approach, the Cartesian sampling, the STPIK legs, the joint transits, the
independent verification and the result. No ROS import.

:class:`~.planner.MotionPlanner` is the request front over it (validation, the set-keyed cache,
the blocker sweeps); the sweeps of :mod:`.blockers` call :meth:`GeometricPlanner.plan` with their
own approaches and slot, so this module imports neither.

Relocated objects leave the clutter and stand in the drop slots of :mod:`qtree_scene.placement`
(the k-th relocation uses slot k, the simulator stands them there too). A plan for object o
after the set R plans against: the objects not in R ∪ {o} at their initial poses, and one
conservative envelope per occupied slot 0 … |R|−1 (largest radius and height over R, plus
:data:`ENVELOPE_MARGIN_M`). Both depend on the SET R only, never on the order R was relocated
in, so the answer keyed on ``(frozenset(R), o)`` in :mod:`.cache` stays valid (Assumption 2,
made true by construction; slot k's placement never touches slots < k, see
:func:`qtree_scene.placement.drop_slots`). Every trajectory returned has passed the independent
:class:`~.verifier.TrajectoryVerifier` against that scene; a rejection is a planner defect and
is answered ``VERIFICATION_FAILED`` / ``CARRIED_COLLISION``, never returned.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from jaco2_description.model import HAND_OPENING_M, Jaco2Model
from qtree_scene.placement import (
    PLACEMENT_TOLERANCE_M,
    Slot,
    drop_slots,
    occupied_envelopes,
    slot_centre,
    slot_position,
    top_place_slots,
)
from qtree_scene.scene import ObjectSpec, Scenario

from stpik_motion_planner.cartesian_path import (
    CartesianPath,
    CartesianSampler,
    approach_yaws,
    interpolate,
)
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import (
    IkNotConverged,
    JointLimitViolated,
    MotionPlannerError,
    NoCartesianPath,
    NoPlacement,
    ObjectTooBig,
    PlanningTimeout,
    SceneCollision,
    SelfCollision,
    VerificationFailed,
)
from stpik_motion_planner.footprint import Footprint
from stpik_motion_planner.grasps import (
    Approach,
    candidate_approaches,
    rotation,
    top_grasp_problem,
)
from stpik_motion_planner.hand_model import HandModel, grasp_width
from stpik_motion_planner.path_memo import SampledPaths
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.robust_stpik import RobustStpik
from stpik_motion_planner.stpik import READY, READY_TOP, Stpik
from stpik_motion_planner.verifier import STOP_CLEARANCE_M, Carried, TrajectoryVerifier

HAND_BELOW_EE_M = 0.06  # lowest point of the hand below the EE origin in a side grasp [m]
HAND_HALF_HEIGHT_M = 0.0525  # half the hand's extent across the approach axis [m]
CARRY_MIN_Z_M = 0.3  # lowest EE height of the carry transit [m]
MIN_SEGMENT_S = 0.05  # shortest time between two trajectory samples [s]
# The simulator stands placed objects on their slot (qtree_scene.placement.settle_pose) [m].
ENVELOPE_MARGIN_M = PLACEMENT_TOLERANCE_M
HOVER_M = 0.12  # height above the pre-grasp of the descent when the joint line is blocked [m]
# Room the open fingers of a top grasp keep from the object beyond the scene margin (#30: a
# bottle taken 29 mm deep was 4.8 mm from finger 1 on the way out; the fingers narrow toward
# the palm). HAND_OPENING_M has its own 5 mm per side already [m].
TOP_GRASP_ROOM_M = 0.005


class GeometricPlanner:
    """Plans for relocating objects of one scenario, without a cache (the request is valid).

    Attributes:
        scenario: the scene planned against.
        config: tunable numbers.
        robot: the arm's model.
        stpik: the STPIK solver with its fallbacks (:mod:`.robust_stpik`).
        hand: the hand's geometry for the Cartesian probes (:mod:`.hand_model`).
        verifier: the independent check of every returned trajectory.
        home_q: start configuration of every plan [rad], shape (7,).
        home_pose: the end-effector pose at ``home_q``.
    """

    def __init__(self, scenario: Scenario, config: PlannerConfig, model: Jaco2Model) -> None:
        """Build the planner's parts for ``scenario`` (validated by the caller)."""
        self.scenario = scenario
        self.config = config
        self.robot = model
        self.stpik = RobustStpik(self.robot, self.config)
        self.hand = HandModel(self.robot, self.config.pregrasp_standoff_m)
        # Proves the executor's stop distance on every pair, the whole carried object included.
        self.verifier = TrajectoryVerifier(self.robot, clearance_m=STOP_CLEARANCE_M)
        # Sampled Cartesian paths by approach, with their probes' logs (:meth:`_sample`).
        self._sampled = SampledPaths()
        self.home_q = np.asarray(scenario.home, dtype=float)
        self.home_pose = pin.SE3(self.robot.ee_pose(self.home_q))

    @contextlib.contextmanager
    def configured(self, config: PlannerConfig) -> Iterator[None]:
        """Plan with ``config`` inside (the planner and its STPIK solver); restored after."""
        before = self.config
        self.config = self.stpik.config = config
        try:
            yield
        finally:
            self.config = self.stpik.config = before

    def slot_position(self, index: int, obj: ObjectSpec) -> np.ndarray:
        """Centre [m] (3,) of ``obj`` standing in drop slot ``index`` (qtree_scene.placement)."""
        return slot_position(self.scenario, index, obj)

    def planning_scene(
        self, object_id: str, relocated: Iterable[str], envelopes: bool = True
    ) -> list[ObjectSpec]:
        """Bodies standing while ``object_id`` is relocated after the set ``relocated``.

        The objects not relocated (initial poses, statics included; not ``object_id``) and, with
        ``envelopes``, one envelope per occupied drop slot
        (:func:`qtree_scene.placement.occupied_envelopes`).
        """
        relocated = set(relocated)
        removed = relocated | {object_id}
        standing = [o for o in self.scenario.objects if o.id not in removed]
        if not envelopes:
            return standing
        if 'top' not in self.config.grasp_families:
            return standing + occupied_envelopes(self.scenario, relocated, ENVELOPE_MARGIN_M)
        # Each relocated object stands on its side slot or its top slot (#30): both envelopes.
        return standing + [
            envelope
            for slots in top_place_slots(self.scenario)
            for envelope in occupied_envelopes(
                self.scenario, relocated, ENVELOPE_MARGIN_M, slots=slots
            )
        ]

    def slots(self, family: str) -> tuple[Slot, ...]:
        """The drop slots a relocation with a ``family`` grasp fills, in relocation order: all
        of :func:`~qtree_scene.placement.drop_slots` when the planner grasps from the side only
        (the paper's setting), else those of :func:`~qtree_scene.placement.top_place_slots`.
        """
        if 'top' not in self.config.grasp_families:
            return drop_slots(self.scenario)
        side, top = top_place_slots(self.scenario)
        return top if family == 'top' else side

    def plan(
        self,
        object_id: str,
        relocated: list[str],
        yaws: Sequence[float] | None = None,
        slot_index: int | None = None,
        deadline: float | None = None,
        approaches: Sequence[Approach] | None = None,
        footprint: Footprint | None = None,
    ) -> PlanResult:
        """Plan without the cache (the request must be valid).

        Args:
            object_id: the object to relocate.
            relocated: the objects already relocated (gone from the clutter).
            yaws: candidate side-approach yaws [rad] (default: the planner's own approaches of
                every family of ``config.grasp_families``).
            slot_index: drop slot to place in with no placed objects standing (the blocker
                sweeps of :mod:`.blockers`); default: slot ``len(relocated)`` with the occupied
                slots 0 … len(relocated)−1 standing as envelopes.
            deadline: ``time.perf_counter()`` value to stop at [s], if earlier than the time
                limit (the blocker sweeps share their request's budget).
            approaches: the candidate grasps (family and yaw), instead of ``yaws``.
            footprint: records every scene query of the plan (:mod:`.footprint`), if given.
        """
        c = self.config
        start = time.perf_counter()
        deadline = min(start + c.time_limit_s, math.inf if deadline is None else deadline)
        timings = {'sampling': 0.0, 'stpik': 0.0, 'collision': 0.0, 'verify': 0.0}
        obj = self.scenario.object(object_id)
        index = len(relocated) if slot_index is None else slot_index
        bad = _unplaceable(obj, index, {f: self.slots(f) for f in c.grasp_families})
        if bad is not None:
            return PlanResult(False, bad.reason, str(bad), planning_time=_since(start))
        standing = self.planning_scene(object_id, relocated, envelopes=slot_index is None)
        scene = SceneWorld(standing)
        if not math.isclose(self.hand.standoff_m, c.pregrasp_standoff_m):
            self.hand = HandModel(self.robot, c.pregrasp_standoff_m)  # config changed since
        sampler = CartesianSampler(scene, c, self.hand)
        centre = np.asarray(obj.position, dtype=float)
        if approaches is None and yaws is not None:
            approaches = [Approach('side', float(y)) for y in yaws]
        elif approaches is None:
            side = approach_yaws(centre, c.approach_directions, c.approach_yaw_step_rad)
            approaches = candidate_approaches(centre, c.grasp_families, side)
        recording = (self.stpik.bodies, scene, sampler.movable) if footprint is not None else ()
        with _recording(footprint, recording):
            return self._plan_approaches(
                obj, index, approaches, sampler, standing, start, deadline, timings
            )

    def _plan_approaches(
        self,
        obj: ObjectSpec,
        index: int,
        approaches: Sequence[Approach],
        sampler: CartesianSampler,
        standing: list[ObjectSpec],
        start: float,
        deadline: float,
        timings: dict[str, float],
    ) -> PlanResult:
        """:meth:`plan` from its candidate ``approaches`` on: ``obj`` to drop slot ``index``
        among ``standing`` (``sampler.scene`` holds them), started at ``start`` [s].
        """
        c = self.config
        scene = sampler.scene
        object_id = obj.id
        failures: list[MotionPlannerError] = []
        try:
            # Pass 1: every approach with the plain STPIK (fast); pass 2, only when all failed:
            # the sampled approaches again with the fallbacks of .robust_stpik (IK restarts,
            # RRTConnect transits). Same feasibility as one pass with fallbacks, far faster.
            sampled = []
            for approach in approaches:
                width = grasp_width(obj, approach.yaw)  # the fingers close alike in each family
                if width > HAND_OPENING_M:  # #30: the width at THIS approach, boxes at any yaw
                    failures.append(
                        ObjectTooBig(
                            f'{obj.id!r} is {width * 1000:.0f} mm across the fingers in a '
                            f'{approach}, the open hand closes on at most '
                            f'{HAND_OPENING_M * 1000:.0f} mm'
                        )
                    )
                    continue
                slots = self.slots(approach.family)
                if index >= len(slots):  # #30: this family's slots are full
                    failures.append(_no_slot(obj, index, slots, approach.family))
                    continue
                slot, slot_yaw = slot_centre(self.scenario, slots[index], obj), slots[index].yaw
                t0 = time.perf_counter()
                path = self._sample(sampler, scene, obj, approach, slot, slot_yaw, failures)
                timings['sampling'] += time.perf_counter() - t0
                if path is None:
                    continue
                sampled.append(path)
                with self.stpik.plain():
                    done = self._attempt(path, scene, standing, obj, deadline, timings, failures)
                if done is not None:
                    return self._success(path, *done, start, timings)
            for path in sampled if self.stpik.has_fallbacks else ():
                done = self._attempt(path, scene, standing, obj, deadline, timings, failures)
                if done is not None:
                    return self._success(path, *done, start, timings)
            if time.perf_counter() > deadline:
                raise PlanningTimeout(time.perf_counter() - start, c.time_limit_s)
        except PlanningTimeout as err:
            return PlanResult(
                False, Reason.TIMEOUT, str(err), planning_time=_since(start), timings=timings
            )
        error = _most_informative(failures, object_id)
        return PlanResult(
            False, error.reason, str(error), planning_time=_since(start), timings=timings
        )

    def _attempt(
        self,
        path: CartesianPath,
        scene: SceneWorld,
        standing: list[ObjectSpec],
        obj: ObjectSpec,
        deadline: float,
        timings: dict[str, float],
        failures: list[MotionPlannerError],
    ) -> tuple[np.ndarray, int, int] | None:
        """Track one sampled approach and verify it: (trajectory, grasp, release) or None.

        A failure is appended to ``failures``; PlanningTimeout propagates.
        """
        try:
            trajectory, grasp_index, release_index = self._track(
                path, scene, obj, deadline, timings
            )
        except PlanningTimeout:
            raise
        except MotionPlannerError as err:
            failures.append(err)
            return None
        t0 = time.perf_counter()
        report = self.verifier.verify(
            trajectory, standing, Carried(obj, grasp_index, release_index)
        )
        timings['verify'] += time.perf_counter() - t0
        if not report.ok:
            carried = any('carried' in (v.name_a, v.name_b) for v in report.violations)
            failures.append(
                VerificationFailed(f'yaw {path.approach_yaw:.2f} rad: {report.summary()}', carried)
            )
            return None
        return trajectory, grasp_index, release_index

    def _sample(
        self,
        sampler: CartesianSampler,
        scene: SceneWorld,
        obj: ObjectSpec,
        approach: Approach,
        slot: np.ndarray,
        slot_yaw: float,
        failures: list,
    ) -> CartesianPath | None:
        """The Cartesian path of one approach (:meth:`_sample_path`), remembered (#28).

        Keyed on what the path depends on besides the probed scene (:mod:`.path_memo`): the
        request, the height of the tallest movable object and the configuration.
        """
        config = self.config
        tallest = max(
            (o.top_z for o in scene.objects.values() if o.role != 'static'), default=None
        )
        key = (
            obj,
            approach,
            np.asarray(slot, dtype=float).tobytes(),
            float(slot_yaw),
            tallest,
            tuple(getattr(config, f.name) for f in dataclasses.fields(config)),
        )
        return self._sampled.path(
            key,
            (sampler.scene, sampler.movable),
            tuple(scene.objects.values()),
            lambda found: self._sample_path(
                sampler, obj, approach, (slot, slot_yaw), tallest, found
            ),
            failures,
        )

    def _sample_path(
        self,
        sampler: CartesianSampler,
        obj: ObjectSpec,
        approach: Approach,
        drop: tuple[np.ndarray, float],
        tallest_m: float | None,
        failures: list,
    ) -> CartesianPath | None:
        """Sample the Cartesian path of ``approach``, or append its failure and return None.

        Args:
            sampler: the probes of the scene planned against.
            obj: the object relocated.
            approach: its grasp family and approach yaw.
            drop: the slot centre [m] (3,) and the slot's yaw [rad].
            tallest_m: top of the tallest movable object [m] (None: there is none).
            failures: where a failure is appended.
        """
        slot, slot_yaw = drop
        c = self.config
        yaw, top = approach.yaw, approach.family == 'top'
        where = f'{approach.family} grasp at yaw {yaw:.2f} rad' if top else f'yaw {yaw:.2f} rad'
        grasp_rotation = rotation(approach)
        axis = grasp_rotation[:, 2]
        centre = np.asarray(obj.position, dtype=float)
        half = obj.height / 2 if obj.shape == 'cylinder' else obj.size[2] / 2
        if top:  # the fingers close on the top; the palm stays above it (.grasps)
            room = c.obstacle_min_distance_m + TOP_GRASP_ROOM_M  # the fingers off the object
            depth = self.hand.top_grasp_depth(obj, yaw, room)
            short = top_grasp_problem(obj, depth, c.obstacle_activation_m + 0.005)
            if short is not None:
                failures.append(NoCartesianPath(obj.id, f'no {where}: {short}'))
                return None
            grasp_z = centre[2] + half - depth
            grasp = pin.SE3(grasp_rotation, np.r_[centre[:2], grasp_z])
            below = grasp_z - (centre[2] - half)  # the object hangs this far below the EE
        else:
            # Mid-height, raised on short objects so the hand keeps its margin to the table.
            low = centre[2] - half + HAND_HALF_HEIGHT_M + c.obstacle_activation_m + 0.005
            grasp_z = min(max(centre[2], low), centre[2] + half - 0.01)
            depth = min(c.grasp_depth_m, self._palm_room(obj, yaw))
            grasp = pin.SE3(grasp_rotation, np.r_[centre[:2], grasp_z] + depth * axis)
            below = max(half, HAND_BELOW_EE_M)
        blockers = sampler.corridor_blockers(grasp)
        if blockers:
            failures.append(
                NoCartesianPath(
                    obj.id,
                    f'approach corridor of the open hand at {where} is blocked by '
                    + ', '.join(blockers),
                )
            )
            return None
        pregrasp = pin.SE3(grasp_rotation, grasp.translation - c.pregrasp_standoff_m * axis)
        # The palm ball, inside the hand at both ends (home and pre-grasp orientations).
        free = sampler.free_path(
            self.hand.ball_point(self.home_pose), self.hand.ball_point(pregrasp)
        )
        if not free:
            failures.append(NoCartesianPath(obj.id, f'no free path to the pre-grasp at {where}'))
            return None
        highest = obj.position[2] if tallest_m is None else tallest_m
        carry_z = max(highest + c.lift_clearance_m + below, grasp.translation[2] + 0.05)
        lift = pin.SE3(grasp_rotation, np.r_[grasp.translation[:2], carry_z])
        slot = slot + np.r_[0.0, 0.0, grasp_z - centre[2]]  # EE height at release
        step_m, step_rad = c.step_m, c.step_rad
        options = []
        for place_yaw in (slot_yaw, slot_yaw + math.pi / 2, slot_yaw - math.pi / 2):
            place_rotation = rotation(Approach(approach.family, place_yaw))
            above = pin.SE3(place_rotation, np.r_[slot[:2], max(carry_z, CARRY_MIN_Z_M)])
            place = pin.SE3(place_rotation, slot)
            # Side: up and back along the approach; top: straight up (back is up).
            up_and_back = np.r_[0.0, 0.0, 1.0] - (0.0 if top else place_rotation[:, 2])
            retreat = pin.SE3(place_rotation, slot + c.retreat_m * up_and_back)
            options.append(
                (
                    above,
                    interpolate(above, place, step_m, step_rad),
                    interpolate(place, retreat, step_m, step_rad),
                )
            )
        return CartesianPath(
            free,
            pregrasp,
            interpolate(pregrasp, grasp, step_m, step_rad),
            interpolate(grasp, lift, step_m, step_rad),
            options,
            yaw,
            approach.family,
        )

    def _palm_room(self, obj: ObjectSpec, yaw: float) -> float:
        """Deepest EE origin beyond the object axis [m] keeping the palm off the object.

        The palm's front face is :attr:`HandModel.palm_front_m` behind the EE origin; the object
        reaches its half depth along the approach (a box turned by ``obj.yaw - yaw``) toward it.
        Negative for deep boxes: the EE then stops short of the axis (3 cm cylinders: +4 mm).
        """
        if obj.shape == 'cylinder':
            half = float(obj.radius)
        else:
            turn = obj.yaw - yaw
            half = abs(obj.size[0] * math.cos(turn)) / 2 + abs(obj.size[1] * math.sin(turn)) / 2
        return self.hand.palm_front_m - half - self.config.obstacle_min_distance_m

    def _track(
        self,
        path: CartesianPath,
        scene: SceneWorld,
        obj: ObjectSpec,
        deadline: float,
        timings: dict[str, float],
    ) -> tuple[np.ndarray, int, int]:
        """STPIK along the Cartesian legs, collision-checked joint transits between them.

        Returns:
            Joint trajectory [rad] (N, 7) starting at home, grasp index, release index.
        """
        stpik = self.stpik
        stpik.reset_timers()
        t0 = time.perf_counter()
        phase = 'pre-grasp'

        def loose_then_tight(n: int) -> list[bool]:
            return [False] * (n - 1) + [True]

        try:
            ready = READY_TOP if path.grasp_family == 'top' else READY
            seed = stpik.ready_posture(path.pregrasp.translation, self.home_q[0], ready)
            # Until the grasp the object itself stands in the way of the arm.
            with_obj = SceneWorld([*scene.objects.values(), obj])
            q_pre = stpik.converge(seed, path.pregrasp, with_obj, deadline=deadline)
            band = self.config.joint_limit_activation_rad
            _outside_limit_band(q_pre, stpik, band)
            phase = 'transit to pre-grasp'
            to_pre = self._transit_to_pregrasp(q_pre, path.pregrasp, with_obj, deadline)
            phase = 'approach'
            # Tight on every sample: the open fingertips pass 20 mm from the object (verifier).
            approach = stpik.track(
                q_pre, path.approach, scene, [True] * len(path.approach), deadline
            )
            world_obj = pin.SE3(
                pin.rpy.rpyToMatrix(0.0, 0.0, obj.yaw), np.asarray(obj.position, dtype=float)
            )
            # Held where the hand really is at the grasp (#29: the commanded pose was used, up
            # to the tracking tolerance away).
            in_hand = self.robot.ee_pose(approach[-1]).actInv(world_obj)
            stpik.bodies.attach(
                obj,
                in_hand,
                settle_m=self.config.obstacle_activation_m + 0.002,  # set down: rows inactive
            )
            phase = 'lift'
            lift = stpik.track(approach[-1], path.lift, scene, [False] * len(path.lift), deadline)
            phase = 'above the drop zone'
            for option, (above, place_leg, retreat_leg) in enumerate(path.place_options):  # noqa: B007
                try:
                    q_above = self._above_pose(lift[-1], above, scene, deadline, ready)
                    _outside_limit_band(q_above, stpik, band, 'pose above the drop slot')
                    # The same pose, its continuous joints the fewest turns from the lift's end:
                    # the carry transit does not spin the wrist with the object in the hand.
                    q_above = stpik.nearest_turn(q_above, lift[-1])
                    break
                except PlanningTimeout:
                    raise
                except MotionPlannerError:
                    if option == len(path.place_options) - 1:
                        raise
            phase = 'carry'
            carry = self._upright_carry(lift[-1], q_above, in_hand, scene, deadline)
            q_above = carry[-1]
            phase = 'place'
            place = stpik.track(
                q_above, place_leg, scene, loose_then_tight(len(place_leg)), deadline
            )
            stpik.bodies.detach()
            phase = 'retreat'
            # Away from the object just placed, with it in the scene (#29: it was left out).
            after = SceneWorld([*scene.objects.values(), self._placed(obj, place[-1], in_hand)])
            retreat = stpik.track(
                place[-1], retreat_leg, after, [False] * len(retreat_leg), deadline
            )
            phase = 'return home'
            try:
                home = stpik.transit(retreat[-1], self.home_q, after, deadline)
            except (SceneCollision, SelfCollision):
                # Rise straight up first (Cartesian, STPIK), then the joint line home.
                end = retreat_leg[-1]
                up = pin.SE3(end.rotation, end.translation + np.r_[0.0, 0.0, HOVER_M])
                leg = interpolate(end, up, self.config.step_m, self.config.step_rad)
                rise = stpik.track(retreat[-1], leg, after, [False] * len(leg), deadline)
                home = np.vstack([rise, stpik.transit(rise[-1], self.home_q, after, deadline)])
            retreat = np.vstack([retreat, home])
        except MotionPlannerError as err:
            family = f'{path.grasp_family} grasp at ' if path.grasp_family != 'side' else ''
            err.args = (f'{phase} at {family}yaw {path.approach_yaw:.2f} rad: {err}',)
            raise
        finally:
            stpik.bodies.detach()
            timings['collision'] += stpik.collision_time
            timings['stpik'] += time.perf_counter() - t0 - stpik.collision_time
        parts = [self.home_q[None], to_pre, approach, lift, carry, place]
        grasp_index = sum(len(p) for p in parts[:3]) - 1
        release_index = sum(len(p) for p in parts) - 1
        return np.vstack([*parts, retreat]), grasp_index, release_index

    def _upright_carry(
        self,
        q_lift: np.ndarray,
        q_above: np.ndarray,
        in_hand: pin.SE3,
        scene: SceneWorld,
        deadline: float,
    ) -> np.ndarray:
        """Carry from the lift's end to the pose above the drop slot, the object upright.

        The joint transit first (collision-checked, RRTConnect when blocked); when it tilts the
        object's axis more than ``config.carry_tilt_limit_rad`` from vertical, an STPIK-tracked
        Cartesian carry instead (around the base like the wrist, EE orientation held by the EE
        task, eq. 6), ending within the tracking tolerance of the pose above the slot.

        Args:
            q_lift: start, the lift's end [rad] (7,).
            q_above: goal, the pose above the drop slot [rad] (7,).
            in_hand: the object's pose in the EE frame.
            scene: the carry's collision scene (the carried object attached by the caller).
            deadline: ``time.perf_counter()`` value by which to stop [s].

        Returns:
            Samples after ``q_lift`` [rad] (n, 7), the last one the pose above the slot.
        """
        limit = self.config.carry_tilt_limit_rad
        carry = self.stpik.transit(q_lift, q_above, scene, deadline)
        if self._carried_tilts(carry, in_hand).max(initial=0.0) <= limit:
            return carry
        c = self.config
        start, goal = self.robot.ee_pose(q_lift), self.robot.ee_pose(q_above)
        leg = interpolate(start, goal, c.step_m, c.step_rad, wrist_arc=True)
        tight = [False] * (len(leg) - 1) + [True]
        carry = self.stpik.track(q_lift, leg, scene, tight, deadline, reference=q_above)
        tilts = self._carried_tilts(carry, in_hand)
        worst = int(np.argmax(tilts))
        if tilts[worst] > limit:  # the EE task's tolerance admits more than the limit
            raise IkNotConverged(
                worst,
                0.0,
                float(tilts[worst] - limit),
                f'the carried object tilts {math.degrees(tilts[worst]):.1f} deg from upright, '
                f'limit {math.degrees(limit):.1f} deg',
            )
        return carry

    def _carried_tilts(self, q: np.ndarray, in_hand: pin.SE3) -> np.ndarray:
        """Angle [rad] (n,) of the carried object's axis from the world vertical at each of the
        configurations ``q`` [rad] (n, 7).
        """
        axis = in_hand.rotation[:, 2]  # the object's z axis in the EE frame
        cosines = np.array([self.robot.ee_pose(x).rotation[2] @ axis for x in q])
        return np.arccos(np.clip(cosines, -1.0, 1.0))

    def _above_pose(
        self,
        q_lift: np.ndarray,
        above: pin.SE3,
        scene: SceneWorld,
        deadline: float,
        ready: np.ndarray = READY,
    ) -> np.ndarray:
        """IK of the pose above the drop slot, first from the lift's end ``q_lift`` [rad] (7,)
        (its arm family: the carry transit then keeps the object upright, #29), else from the
        ready posture turned toward the slot (before #29 the only seed).
        """
        stpik = self.stpik
        try:
            return stpik.converge(q_lift, above, scene, deadline=deadline)
        except PlanningTimeout:
            raise
        except MotionPlannerError:
            seed = stpik.ready_posture(above.translation, q_lift[0], ready)
            return stpik.converge(seed, above, scene, deadline=deadline)

    def _placed(self, obj: ObjectSpec, q_release: np.ndarray, in_hand: pin.SE3) -> ObjectSpec:
        """``obj`` where the hand at ``q_release`` [rad] leaves it: position and yaw of the
        released pose (#29: the "after" scene stood it at the commanded slot with yaw 0).
        """
        pose = self.robot.ee_pose(q_release) * in_hand
        yaw = math.atan2(pose.rotation[1, 0], pose.rotation[0, 0])
        return dataclasses.replace(obj, position=tuple(pose.translation), yaw=yaw)

    def _transit_to_pregrasp(
        self, q_pre: np.ndarray, pregrasp: pin.SE3, scene: SceneWorld, deadline: float
    ) -> np.ndarray:
        """Home → pre-grasp: a joint line, else a joint line to a pose above it and a descent.

        The descent (:data:`HOVER_M`, Cartesian, STPIK) keeps the hand off the object whose top
        a joint line swinging down onto the pre-grasp can clip.
        """
        stpik = self.stpik
        try:
            return stpik.transit(self.home_q, q_pre, scene, deadline)
        except (SceneCollision, SelfCollision):
            hover = pin.SE3(pregrasp.rotation, pregrasp.translation + np.r_[0.0, 0.0, HOVER_M])
            q_hover = stpik.converge(q_pre, hover, scene, deadline=deadline)
            _outside_limit_band(
                q_hover, stpik, self.config.joint_limit_activation_rad, 'pose above the pre-grasp'
            )
            down = interpolate(hover, pregrasp, self.config.step_m, self.config.step_rad)
            to_hover = stpik.transit(self.home_q, q_hover, scene, deadline)
            descent = stpik.track(q_hover, down, scene, [True] * len(down), deadline)
            return np.vstack([to_hover, descent])

    def _success(
        self,
        path: CartesianPath,
        trajectory: np.ndarray,
        grasp_index: int,
        release_index: int,
        start: float,
        timings: dict[str, float],
    ) -> PlanResult:
        velocity = np.asarray(self.robot.limits.velocity) * self.config.velocity_scale
        steps = np.max(np.abs(np.diff(trajectory, axis=0)) / velocity, axis=1)
        times = np.concatenate([[0.0], np.cumsum(np.maximum(steps, MIN_SEGMENT_S))])
        ee_path = np.array([pin.SE3ToXYZQUAT(self.robot.ee_pose(q)) for q in trajectory])
        how = f'{path.grasp_family} grasp, ' if path.grasp_family != 'side' else 'approach '
        return PlanResult(
            True,
            Reason.SUCCESS,
            f'feasible ({how}yaw {path.approach_yaw:.2f} rad)',
            times=times,
            joint_trajectory=trajectory,
            ee_path=ee_path,
            grasp_index=grasp_index,
            release_index=release_index,
            planning_time=_since(start),
            timings=timings,
            approach_yaw=path.approach_yaw,
            grasp_family=path.grasp_family,
        )


def _since(start: float) -> float:
    return time.perf_counter() - start


def _outside_limit_band(q: np.ndarray, stpik: Stpik, band: float, what: str = 'pre-grasp') -> None:
    """Refuse an IK solution a leg starts from (the pre-grasp, the pose above the drop slot, the
    hover pose) inside the joint-limit activation band: its tracker could not leave it.

    Raises:
        JointLimitViolated: a limited joint within ``band`` [rad] of a limit.
    """
    margin = np.minimum(q - stpik.lower, stpik.upper - q)
    j = int(np.argmin(margin))
    if margin[j] < band:
        err = JointLimitViolated(j, float(q[j]), stpik.lower[j], stpik.upper[j])
        err.args = (f'{err} ({what} within the {band:.2f} rad joint-limit activation band)',)
        raise err


def _no_slot(obj: ObjectSpec, index: int, slots: Sequence[Slot], family: str) -> NoPlacement:
    where = '' if family == 'side' else f' for a {family} grasp'
    return NoPlacement(
        f'no free drop slot{where} for {obj.id!r}: relocation {index + 1} of a scene with room '
        f'for {len(slots)} (qtree_scene.placement.drop_slots)'
    )


def _unplaceable(
    obj: ObjectSpec, index: int, slots: dict[str, tuple[Slot, ...]]
) -> MotionPlannerError | None:
    """NO_PLACEMENT (no family has slot ``index``) / OBJECT_TOO_BIG before any planning, else
    None. ``slots``: per grasp family, its slots (:meth:`GeometricPlanner.slots`).
    """
    if all(index >= len(s) for s in slots.values()):
        family, most = max(slots.items(), key=lambda item: len(item[1]))
        return _no_slot(obj, index, most, family)
    width = 2 * obj.radius if obj.shape == 'cylinder' else min(obj.size[0], obj.size[1])
    if width > HAND_OPENING_M:
        return ObjectTooBig(
            f'{obj.id!r} is {width * 1000:.0f} mm across, the open hand closes on at most '
            f'{HAND_OPENING_M * 1000:.0f} mm'
        )
    return None


def _most_informative(failures: list[MotionPlannerError], object_id: str) -> MotionPlannerError:
    """A verifier rejection first, else the first STPIK failure, else the first sampling one;
    OBJECT_TOO_BIG (an approach at which the object is too wide) or NO_PLACEMENT (a grasp family
    whose slots are full) only when every approach was.
    """
    others = [err for err in failures if not isinstance(err, (ObjectTooBig, NoPlacement))]
    failures = others or failures
    for err in failures:
        if isinstance(err, VerificationFailed):
            return err
    for err in failures:
        if not isinstance(err, NoCartesianPath):
            return err
    if failures:
        return failures[0]
    return NoCartesianPath(object_id, 'no approach direction tried')


@contextlib.contextmanager
def _recording(footprint: Footprint | None, holders: Sequence[Any]) -> Iterator[None]:
    """``footprint`` on the ``recorders`` of ``holders`` (robot bodies, scene worlds) inside."""
    for holder in holders:
        holder.recorders.append(footprint)
    try:
        yield
    finally:
        for holder in holders:
            holder.recorders.remove(footprint)
