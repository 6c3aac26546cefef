"""The motion planner's request front: validates a relocation request, answers it from the
set-keyed cache or plans it (:class:`~.geometric_planner.GeometricPlanner`), adds the blockers of
an infeasible answer (:mod:`.blockers`) and caches the answer (paper Sect. 3.1). No ROS import.

The answer is keyed on ``(frozenset(R), o)`` (:mod:`.cache`): the geometric planner plans
against a scene that depends on the set R only (Assumption 2, see :mod:`.geometric_planner`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Callable, Iterable

import numpy as np
from jaco2_description.model import Jaco2Model
from qtree_scene.scene import ObjectSpec, Scenario

from stpik_motion_planner.blockers import BlockerFinder
from stpik_motion_planner.cache import FeasibilityCache
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import InvalidRequest
from stpik_motion_planner.footprint import Footprint, PlannedAnswer
from stpik_motion_planner.geometric_planner import GeometricPlanner
from stpik_motion_planner.hand_model import HandModel
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.robust_stpik import RobustStpik
from stpik_motion_planner.scene_checks import validate_request, validate_scenario
from stpik_motion_planner.verifier import TrajectoryVerifier


class MotionPlanner:
    """Feasibility checks (and trajectories) for relocating objects of one scenario.

    Attributes:
        geometry: the geometric planner (no cache) every uncached answer is planned with.
        cache: results by ``(frozenset(relocated_ids), object_id)``.
        footprints: the infeasible answers' plans before their blockers, with the part of the
            workspace each looked at (:mod:`.footprint`), by cache key.
        blockers: the blocker sweeps of infeasible answers.
    """

    def __init__(
        self,
        scenario: Scenario,
        config: PlannerConfig | None = None,
        model: Jaco2Model | None = None,
    ) -> None:
        """Build the planner.

        Raises:
            InvalidRequest: (``INVALID_SCENE``) the scenario has NaN poses, bad sizes, ...
        """
        validate_scenario(scenario)
        self.geometry = GeometricPlanner(
            scenario,
            config if config is not None else PlannerConfig(),
            model if model is not None else Jaco2Model(),
        )
        self.cache = FeasibilityCache()
        # .answer_reuse keeps these across a scene change that stays out of them.
        self.footprints: dict[tuple[frozenset[str], str], PlannedAnswer] = {}
        self.blockers = BlockerFinder(self.geometry)

    @property
    def scenario(self) -> Scenario:
        """The scene planned against."""
        return self.geometry.scenario

    @property
    def config(self) -> PlannerConfig:
        """The tunable numbers the next plans use."""
        return self.geometry.config

    @config.setter
    def config(self, config: PlannerConfig) -> None:
        self.geometry.config = config

    @property
    def robot(self) -> Jaco2Model:
        """The arm's model."""
        return self.geometry.robot

    @property
    def stpik(self) -> RobustStpik:
        """The STPIK solver of the plans."""
        return self.geometry.stpik

    @property
    def hand(self) -> HandModel:
        """The hand's geometry of the Cartesian probes."""
        return self.geometry.hand

    @property
    def verifier(self) -> TrajectoryVerifier:
        """The independent check of every returned trajectory."""
        return self.geometry.verifier

    @property
    def home_q(self) -> np.ndarray:
        """Start configuration of every plan [rad], shape (7,)."""
        return self.geometry.home_q

    def configured(self, config: PlannerConfig) -> contextlib.AbstractContextManager[None]:
        """Plan with ``config`` inside (:meth:`.GeometricPlanner.configured`)."""
        return self.geometry.configured(config)

    @property
    def plan(self) -> Callable[..., PlanResult]:
        """:meth:`.GeometricPlanner.plan`: plan without the cache (the request must be valid)."""
        return self.geometry.plan

    def planning_scene(
        self, object_id: str, relocated: Iterable[str], envelopes: bool = True
    ) -> list[ObjectSpec]:
        """Bodies standing while ``object_id`` is relocated after ``relocated``
        (:meth:`.GeometricPlanner.planning_scene`).
        """
        return self.geometry.planning_scene(object_id, relocated, envelopes)

    def slot_position(self, index: int, obj: ObjectSpec) -> np.ndarray:
        """Centre [m] (3,) of ``obj`` standing in drop slot ``index``."""
        return self.geometry.slot_position(index, obj)

    def check(self, object_id: str, relocated_ids: Iterable[str]) -> PlanResult:
        """Can ``object_id`` be relocated once ``relocated_ids`` are gone? Uses the cache.

        Bad requests give ``feasible=False`` with a 1xx reason; never raises.
        """
        relocated = list(relocated_ids)
        answer = self.precheck(object_id, relocated)
        if answer is not None:
            return answer
        deadline = time.perf_counter() + self.config.time_limit_s  # the whole answer's budget
        cpu_start = time.thread_time()
        footprint = Footprint()
        planned = self.plan(object_id, relocated, footprint=footprint)
        # Blockers cut short by the deadline stay in the cached answer (its feasibility is
        # final); the sweeps go on at the next uncached request about the same object.
        result = self.blockers.annotate(planned, object_id, relocated, deadline)
        result = dataclasses.replace(result, cpu_time=time.thread_time() - cpu_start)
        if result.reason != Reason.TIMEOUT:  # a timeout may pass on a quieter machine
            self.cache.put(object_id, relocated, result)
            if not result.feasible:  # kept for a scene change (.answer_reuse)
                if planned.timings.get('verify', 0.0) > 0.0:
                    footprint.lose('the verifier ran: its checks are not culled queries')
                key = (frozenset(relocated), object_id)
                self.footprints[key] = PlannedAnswer(planned, footprint.region())
        return result

    def precheck(self, object_id: str, relocated: list[str]) -> PlanResult | None:
        """The answer that needs no planning (a bad request or a cache hit), else None.

        Cheap (O(len(relocated)), no STPIK state touched), so a server may call it concurrently
        with a running :meth:`plan` and answer bad requests without waiting for the planner.
        """
        try:
            validate_request(self.scenario, object_id, relocated)
        except InvalidRequest as err:
            return PlanResult(False, err.reason, str(err))
        cached = self.cache.get(object_id, relocated)
        if cached is not None:
            return dataclasses.replace(cached, from_cache=True)
        return None
