"""The ``motion_planner`` node's request handling, thread-safe and without ROS.

:class:`PlannerService` holds the :class:`~stpik_motion_planner.planner.MotionPlanner` of the
current scene, rebuilds it when /scene changes, answers relocation requests and serialises
executions. The node's callbacks (several executor threads) convert messages and call it.

Limits and timing of a request:

- At most ``MAX_RELOCATED_IDS`` (256) relocated ids and ``MAX_ID_CHARS`` (256) characters per id
  (:mod:`.scene_checks`); an id not in the scene is ``UNKNOWN_OBJECT`` whatever its length.
  Answers, log lines and ``/motion_planner/events`` quote at most 5 ids, each cut to 40
  characters; the event carries at most 256 ids of at most 256 characters.
- A request waits up to ``scene_wait_s`` for a first /scene, or for the scene it names
  (``scene_name``: a scene set on the simulator just before may still be on its way), then
  ``NO_SCENE``. Bad requests and cache hits are answered at once, without waiting for the
  planner. Checks that need planning run one at a time (one STPIK state per planner); a request
  waits at most ``request_timeout_s`` for its turn, then ``PLANNER_BUSY``. ``time_limit_s`` bounds
  the planning itself, so an answer takes at most about ``request_timeout_s + time_limit_s``.
  At most :data:`MAX_WAITING_PLANS` requests wait or plan at once; more get ``PLANNER_BUSY`` at
  once, so the executor (``EXECUTOR_THREADS`` threads) always has threads for /joint_states,
  /scene and the other requests.
- One execution at a time (another gets ``EXECUTION_FAILED``); /scene messages received
  meanwhile (the carried object moves) rebuild the planner once, after the execution. If no
  joint state arrives for ``joint_state_timeout_s`` during execution, it stops with
  ``EXECUTION_FAILED`` ("the simulator stopped publishing /joint_states").
- The scene contract (QoS, frame, what "relocated" means) is in ``qtree_msgs/msg/Scene.msg``:
  an object GRASPED or RELOCATED keeps the pose it had while IN_CLUTTER, so carrying it away
  does not rebuild the planner nor empty its cache.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable
from typing import Any

from qtree_scene.message import scenario_from_msg
from qtree_scene.scene import ObjectSpec

from stpik_motion_planner.answer_reuse import carry_over
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import InvalidRequest, MotionPlannerError
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.scene_checks import check_ids_given

MAX_WAITING_PLANS = 8  # requests waiting for or holding the planner at once [-]


class PlannerService:
    """The planner of the current scene, its request queue and the one execution at a time."""

    def __init__(
        self, config: Callable[[], PlannerConfig], log: Callable[[str, str], None]
    ) -> None:
        """Empty until the first scene.

        Args:
            config: gives the node's current planner parameters (called on each rebuild).
            log: ``log(level, line)`` with level ``'info'`` or ``'warning'`` (the node's logger).
        """
        self._config, self._log = config, log
        self._lock = threading.Lock()  # swaps of the planner (held for an assignment only)
        self._scene_swapped = threading.Condition(self._lock)  # a planner or a scene error came
        self._plan_lock = threading.Lock()  # held while planning: one STPIK state per planner
        self._waiting = threading.BoundedSemaphore(MAX_WAITING_PLANS)
        self._scene_lock = threading.Lock()  # one /scene handled at a time
        self._executing = False  # under self._lock
        self._deferred_scene: Any = None  # under self._lock
        self._planner: MotionPlanner | None = None
        self._scene_error = ''
        self._geometry: tuple | None = None
        self._original: dict[str, ObjectSpec] = {}  # objects as last seen IN_CLUTTER

    def reconfigure(self, config: PlannerConfig) -> None:
        """Rebuild the planner of the current scene with ``config`` (cache emptied)."""
        with self._lock:
            if self._planner is not None:
                self._planner = MotionPlanner(self._planner.scenario, config)

    def on_scene(self, msg: Any) -> None:
        """Take a decoded /scene message: rebuild the planner if the scene changed.

        Deferred while an execution runs (the carried object moves with every message).
        """
        with self._lock:
            if self._executing:
                self._deferred_scene = msg
                return
        with self._scene_lock:
            self._rebuild(msg)

    def _rebuild(self, msg: Any) -> None:
        try:
            scenario = scenario_from_msg(msg, original=self._original)
            geometry = (scenario.name, scenario.objects, scenario.drop_zone_center)
            if geometry == self._geometry:
                return
            planner = MotionPlanner(scenario, self._config())
            self._scene_error = ''
            reuse = self._carry_over(planner)
        except (MotionPlannerError, ValueError) as err:  # ScenarioError is a ValueError
            planner, self._scene_error, geometry = None, str(err), None
            self._log('warning', f'scene rejected: {err}')
        with self._lock:
            self._planner, self._geometry = planner, geometry
            self._scene_swapped.notify_all()
        self._original = {o.id: o for o in scenario.objects} if planner else {}
        if planner is not None:
            self._log('info', f'scene {msg.scenario_name!r}: planner rebuilt, {reuse}')

    def _carry_over(self, planner: MotionPlanner) -> str:
        """Keep in ``planner``'s cache the answers of the previous planner a scene change leaves
        true (#32, :mod:`.answer_reuse`); the summary line. Never raises: a failure keeps none.
        """
        old = self._planner
        if old is None:
            return 'no cached answers'
        try:  # a check still running on the old planner answers for the old scene: not kept
            return carry_over(old, planner)
        except Exception as err:  # reuse is an optimisation, never a failure
            return f'kept 0 cached answers ({type(err).__name__}: {err})'

    def answer(
        self,
        object_id: str,
        relocated: list[str],
        received: float,
        wait_s: float,
        scene_name: str = '',
        scene_wait_s: float = 0.0,
    ):
        """Validate and answer from the cache at once; plan (waiting for the planner) if needed.

        Args:
            object_id: the object to relocate.
            relocated: the objects already relocated.
            received: ``time.monotonic()`` of the request [s].
            wait_s: longest wait for the planner from ``received`` (``request_timeout_s``) [s].
            scene_name: the scene the request is about ('' any: the current one).
            scene_wait_s: longest wait from ``received`` for a first scene, or for the scene named
                ``scene_name`` [s].
        """
        try:  # answered at once, scene or not (CI of 9ffde18: the nodes' probe waited 5 s)
            check_ids_given(object_id, relocated)
        except InvalidRequest as err:
            return PlanResult(False, err.reason, str(err))
        planner = self._wait_for_scene(scene_name, received + scene_wait_s)
        if planner is None:
            return self._no_planner()
        if scene_name and planner.scenario.name != scene_name:
            why = (
                f'no /scene {scene_name!r} received within scene_wait_s={scene_wait_s:.1f} s '
                f'(the planner has scene {planner.scenario.name!r})'
            )
            return PlanResult(False, Reason.NO_SCENE, why)
        answer = planner.precheck(object_id, relocated)
        if answer is not None:
            return answer
        if not self._waiting.acquire(blocking=False):
            busy = f'planner busy: {MAX_WAITING_PLANS} requests are already waiting for it'
            return PlanResult(False, Reason.PLANNER_BUSY, busy)
        try:
            remaining_s = max(0.0, received + wait_s - time.monotonic())
            if not self._plan_lock.acquire(timeout=remaining_s):
                busy = f'planner busy: not free within request_timeout_s={wait_s:.1f} s'
                return PlanResult(False, Reason.PLANNER_BUSY, busy)
            try:
                planner = self._planner  # the scene may have changed while waiting
                if planner is None:
                    return self._no_planner()
                return planner.check(object_id, relocated)  # may now be in the cache
            finally:
                self._plan_lock.release()
        finally:
            self._waiting.release()

    def _wait_for_scene(self, scene_name: str, deadline: float) -> MotionPlanner | None:
        """The planner once it serves ``scene_name`` (any when ''), a scene was rejected, or
        ``deadline`` (``time.monotonic()`` [s]) passed; None when there is none.
        """

        def ready() -> bool:
            if self._planner is None:
                return bool(self._scene_error)
            return not scene_name or self._planner.scenario.name == scene_name

        with self._scene_swapped:
            while not ready():
                remaining = deadline - time.monotonic()
                if remaining <= 0.0:
                    break
                self._scene_swapped.wait(remaining)
            return self._planner

    def _no_planner(self) -> PlanResult:
        reason = Reason.INVALID_SCENE if self._scene_error else Reason.NO_SCENE
        return PlanResult(False, reason, self._scene_error or 'no /scene received yet')

    def execute(
        self, result: PlanResult, follow: Callable[[PlanResult], PlanResult]
    ) -> PlanResult:
        """``follow(result)`` unless another execution runs; then the scene deferred meanwhile."""
        with self._lock:
            busy, self._executing = self._executing, True
        if busy:
            failed = 'another relocation is being executed'
            return dataclasses.replace(
                result, feasible=False, reason=Reason.EXECUTION_FAILED, message=failed
            )
        try:
            return follow(result)
        finally:
            with self._lock:
                self._executing = False
                deferred, self._deferred_scene = self._deferred_scene, None
            if deferred is not None:
                self.on_scene(deferred)
