"""STPIK with two fallbacks, used by the planner: random IK restarts and RRTConnect transits.

A check used to answer "infeasible" when the single ready-posture IK seed of the pre-grasp (or of
the pose above the drop slot) stalled, or when the straight joint move between two solved
configurations touched an obstacle, although another IK branch or a detour existed: on 300 random
questions on generated clutter, 30 such answers the reference planner solved, 23 of them with
these two fallbacks (``benchmarks/results/false_infeasible.md``). No ROS import.

* :meth:`RobustStpik.converge`: after a failed solve from the planner's seed, up to
  ``config.ik_restarts`` seeds drawn uniformly in the joint ranges ([−π, 2π] on continuous
  joints), from a generator seeded by ``config.seed`` and the target pose, so that the same
  question gets the same seeds whatever was asked before (answers are cached by set,
  Assumption 2).
* :meth:`RobustStpik.transit`: when the straight joint move collides, joint-space RRTConnect
  (:mod:`.rrt_connect`) for at most ``config.rrt_iterations`` iterations (0 turns it off), its
  random stream seeded from the question (``config.seed``, both ends), resampled to at most
  ``step_rad`` per joint per sample. Validity: the joint limits and the self-hit and scene
  *activation* distances, as for the straight transit: a detour STPIK's set-based tasks could
  not follow is no detour (#29: the RRT accepted 5 mm where the obstacle task acts at 25 mm).
  ``config.rrt_transit_s`` only caps its wall time: past it the check answers TIMEOUT (not
  cached), so no cached answer depends on the machine's speed.

Every trajectory still passes the planner's independent verifier before it is returned.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import OrderedDict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import cast

import numpy as np
import pinocchio as pin

from stpik_motion_planner.collision import QueryList, QueryLog, SceneWorld
from stpik_motion_planner.exceptions import MotionPlannerError, PlanningTimeout, copy_error
from stpik_motion_planner.rrt_connect import RrtConnect, question_seed
from stpik_motion_planner.stpik import Stpik, joint_segment

MEMO_QUERIES = 300_000  # scene queries the memo holds (about 100 MB), oldest dropped [-]
MEMO_ENTRY_QUERIES = 5_000  # a result with more queries is reused in its own scene only [-]
MEMO_PER_KEY = 8  # results kept per question (different scenes) [-]
SEED_RESOLUTION = 1e4  # target pose quantum of the restart generator's seed [1/m] [-]
RRT_RANGE_RAD = 0.5  # longest RRTConnect extension (Euclidean in joint space) [rad]
RRT_SHORTCUTS = 50  # random shortcut attempts on a found path [-]


@dataclass(frozen=True)
class _Outcome:
    """A remembered deterministic result (:meth:`RobustStpik._remembered`).

    Attributes:
        scene: the scene's objects it was computed in.
        queries: its scene queries (None: too many to keep, reused in ``scene`` only).
        ok: True for a returned value, False for a raised planner error.
        value: the joint array [rad] (or None) returned, or the error raised.
        args: the error's original arguments (its message).
    """

    scene: tuple
    queries: QueryLog | None
    ok: bool
    value: object
    args: tuple

    @property
    def size(self) -> int:
        """Scene queries held [-] (at least 1, for the memo's budget)."""
        return max(1, len(self.queries) if self.queries is not None else 0)

    def again(self) -> np.ndarray | None:
        """The value again (a copy), or raise a copy of the error with its original message."""
        if self.ok:
            return None if self.value is None else np.array(self.value, copy=True)
        raise copy_error(cast(MotionPlannerError, self.value), self.args)  # not ok: the error


class RobustStpik(Stpik):
    """:class:`~.stpik.Stpik` with random IK restarts and RRTConnect transits.

    Attributes:
        fallbacks: whether the fallbacks run (off inside :meth:`plain`).
    """

    fallbacks = True

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # Deterministic results (#28), by question without its scene (:meth:`_key`): the
        # fallback pass re-asks the plain pass's questions, and the next plans ask most of them
        # again in scenes that differ only far from the arm. Kept until :meth:`forget`.
        self._memo: OrderedDict[tuple, list[_Outcome]] = OrderedDict()
        self._memo_queries = 0  # scene queries held by the memo [-]
        self.memo_hits = 0  # questions answered from the memo [-]

    def forget(self) -> None:
        """Drop the remembered deterministic results."""
        self._memo.clear()
        self._memo_queries = 0

    def _remembered(
        self, key: tuple, scene: SceneWorld, compute: Callable[[], np.ndarray | None]
    ) -> np.ndarray | None:
        """``compute()``, or what it gave (a copy) or raised (its planner error again) before.

        A result is reused in the scene it was computed in, or in any scene where every scene
        query it made (:class:`~.collision.SceneQuery`) lets through the same pairs: the robot
        bodies (same question) then meet the same objects, so each step, and the result, is
        the same bit for bit (the objects the cull ruled out never entered the computation).
        PlanningTimeout is never remembered (it depends on the clock, not on the question).
        The error raised again is a copy with the original message (the planner prefixes the
        phase to the message of the error it catches).
        """
        objects = tuple(scene.objects.values())
        for outcome in self._memo.get(key, ()):
            if outcome.scene == objects or (
                outcome.queries is not None and outcome.queries.replays_in(scene)
            ):
                self._memo.move_to_end(key)
                self.memo_hits += 1
                for recorder in self.bodies.recorders:  # an enclosing computation's queries
                    if outcome.queries is not None:
                        recorder.extend(outcome.queries.queries)
                    else:  # its queries were not kept: the enclosing log proves nothing else
                        recorder.lose('an STPIK result reused from the memo without its queries')
                return outcome.again()
        log = QueryList()
        self.bodies.recorders.append(log)
        try:
            value = compute()
        except PlanningTimeout:
            raise
        except MotionPlannerError as err:
            self._keep(key, objects, log, False, err, err.args)
            raise
        finally:
            self.bodies.recorders.pop()
        copy = None if value is None else np.array(value, copy=True)
        self._keep(key, objects, log, True, copy, ())
        return value

    def _keep(
        self, key: tuple, scene: tuple, log: QueryList, ok: bool, value, args: tuple
    ) -> None:
        """Remember an outcome under ``key``, within :data:`MEMO_QUERIES` (oldest dropped);
        one of more than :data:`MEMO_ENTRY_QUERIES` queries, or whose log missed some (a nested
        result reused without its queries), is reused in its own scene only.
        """
        keep = log.complete and len(log) <= MEMO_ENTRY_QUERIES
        queries = QueryLog(log) if keep else None
        outcome = _Outcome(scene, queries, ok, value, args)
        entries = self._memo.setdefault(key, [])
        self._memo.move_to_end(key)
        entries.append(outcome)
        self._memo_queries += outcome.size
        if len(entries) > MEMO_PER_KEY:
            self._memo_queries -= entries.pop(0).size
        while self._memo_queries > MEMO_QUERIES and len(self._memo) > 1:
            _, dropped = self._memo.popitem(last=False)
            self._memo_queries -= sum(o.size for o in dropped)

    def _key(self, name: str, *arrays: np.ndarray, extra: tuple = ()) -> tuple:
        """Hashable identity of a deterministic question without its scene: arrays by value,
        the carried object, the configuration's values.
        """
        config = self.config
        return (
            name,
            *(np.asarray(a, dtype=float).tobytes() for a in arrays),
            self.bodies.attach_key,
            extra,
            tuple(getattr(config, f.name) for f in dataclasses.fields(config)),
        )

    def _plain_converge(self, seed, target, scene, iterations, deadline) -> np.ndarray:
        key = self._key('converge', seed, target.homogeneous, extra=(iterations,))
        return cast(  # converge gives a configuration or raises, never None
            np.ndarray,
            self._remembered(
                key, scene, lambda: Stpik.converge(self, seed, target, scene, iterations, deadline)
            ),
        )

    def track(self, q, samples, scene, tight, deadline=np.inf, reference=None):
        """:meth:`Stpik.track`, remembered per plan (deterministic; see :meth:`forget`)."""
        poses = np.array([s.homogeneous for s in samples])
        ref = np.asarray(q if reference is None else reference, dtype=float)
        key = self._key('track', q, poses, ref, extra=tuple(bool(t) for t in tight))
        return self._remembered(
            key, scene, lambda: Stpik.track(self, q, samples, scene, tight, deadline, reference)
        )

    @property
    def has_fallbacks(self) -> bool:
        """Whether the config enables any fallback (restarts > 0 or an RRT budget)."""
        return self.config.ik_restarts > 0 or self.config.rrt_iterations > 0

    @contextmanager
    def plain(self) -> Iterator[None]:
        """Within the block: the plain STPIK, no fallback (the planner's first pass)."""
        self.fallbacks = False
        try:
            yield
        finally:
            self.fallbacks = True

    def converge(self, seed, target, scene, iterations=40, deadline=np.inf):
        """:meth:`Stpik.converge` from ``seed``, then from ``config.ik_restarts`` random seeds.

        Raises:
            The first solve's error when every restart fails too; PlanningTimeout at once.
        """
        try:
            return self._plain_converge(seed, target, scene, iterations, deadline)
        except PlanningTimeout:
            raise
        except MotionPlannerError as err:
            if not self.fallbacks:
                raise
            first = err
        rng = np.random.default_rng(_pose_seed(self.config.seed, target))
        low, high = np.maximum(self.lower, -math.pi), np.minimum(self.upper, math.pi * 2)
        for _ in range(int(self.config.ik_restarts)):
            try:
                return self._plain_converge(
                    rng.uniform(low, high), target, scene, iterations, deadline
                )
            except PlanningTimeout:
                raise
            except MotionPlannerError:
                continue
        raise first

    def transit(self, q_a, q_b, scene, deadline=np.inf):
        """Straight joint move, else RRTConnect in joint space (see the module docstring)."""
        try:
            key = self._key('transit', q_a, q_b)
            return self._remembered(
                key, scene, lambda: Stpik.transit(self, q_a, q_b, scene, deadline)
            )
        except PlanningTimeout:
            raise
        except MotionPlannerError as err:
            if (
                not self.fallbacks
                or self.config.rrt_iterations <= 0
                or (self.config.rrt_transit_s <= 0.0)
            ):
                raise
            a, b = np.asarray(q_a, dtype=float), np.asarray(q_b, dtype=float)
            path = self._remembered(
                self._key('rrt', a, b), scene, lambda: self.rrt(a, b, scene, deadline)
            )
            if path is None:
                raise err from None
            return path

    def valid(self, q: np.ndarray, scene: SceneWorld) -> bool:
        """Within the joint limits, and the self-hit and scene pairs beyond their *activation*
        distances (what the straight :meth:`~.stpik.Stpik.transit` requires).
        """
        if np.any(q < self.lower) or np.any(q > self.upper):
            return False
        # Collision only (#28): placements without Jacobians (bit-identical to those of
        # kinematics), pairs up to the thresholds only, the first hit ends the check.
        c = self.config
        self.place_bodies(q)
        start = time.perf_counter()
        clear = self.bodies.self_clear(c.self_activation_m) and self.bodies.scene_clear(
            scene, c.obstacle_activation_m
        )
        self.collision_time += time.perf_counter() - start
        return clear

    def rrt(
        self, q_a: np.ndarray, q_b: np.ndarray, scene: SceneWorld, deadline: float = np.inf
    ) -> np.ndarray | None:
        """RRTConnect q_a → q_b [rad] (7,): samples after q_a up to q_b (n, 7), or None.

        None at once when an end itself is invalid, and after ``config.rrt_iterations``
        iterations without a path. The same ends (and seed) give the same samples in any
        process, whatever was asked before (#29).

        Raises:
            PlanningTimeout: ``deadline`` (a ``time.perf_counter()`` value) or the
                ``config.rrt_transit_s`` wall-time cap passed (before the search or during it).
        """
        c = self.config
        now = time.perf_counter()
        if deadline <= now:
            raise PlanningTimeout.past(deadline, c.time_limit_s)
        if not (self.valid(q_a, scene) and self.valid(q_b, scene)):
            return None
        cap = min(deadline, now + float(c.rrt_transit_s))
        # Continuous joints have infinite limits: search within ±π around both ends there.
        ends = np.vstack([q_a, q_b])
        low = np.where(np.isfinite(self.lower), self.lower, ends.min(axis=0) - math.pi)
        high = np.where(np.isfinite(self.upper), self.upper, ends.max(axis=0) + math.pi)
        seed = question_seed(int(c.seed), q_a.tobytes(), q_b.tobytes())
        search = RrtConnect(
            lambda q: self.valid(q, scene),
            low,
            high,
            np.random.default_rng(seed),
            range_rad=RRT_RANGE_RAD,
            resolution_rad=c.step_rad / 2,
            deadline=cap,
            on_deadline=lambda: PlanningTimeout.past(cap, cap - now),
        )
        waypoints = search.solve(q_a, q_b, int(c.rrt_iterations))
        if waypoints is None:
            return None
        waypoints = search.shortcut(waypoints, RRT_SHORTCUTS)
        out = [waypoints[0]]
        for q in waypoints[1:]:  # samples ≤ step_rad apart, as the straight transit gives
            out += list(joint_segment(out[-1], q, c.step_rad))
        return np.array(out[1:])


def _pose_seed(seed: int, target: pin.SE3) -> list[int]:
    """Non-negative integers identifying (config seed, target pose) for ``default_rng``."""
    values = np.r_[target.translation, target.rotation.ravel()]
    return [int(seed), *(round(float(v + 10.0) * SEED_RESOLUTION) for v in values)]
