"""Reason codes and the result of one feasibility check (no ROS import).

The :class:`Reason` values equal the constants of ``qtree_msgs/srv/RelocateObject`` (nav2 style:
``SUCCESS=0``, request errors 1xx, planning failures 2xx, run-time failures 3xx).
"""

from __future__ import annotations

import dataclasses
from dataclasses import KW_ONLY, dataclass, field
from enum import IntEnum

import numpy as np


class Reason(IntEnum):
    """Why a relocation is (in)feasible; equal to the ``RelocateObject.srv`` constants."""

    SUCCESS = 0
    UNKNOWN_OBJECT = 101
    ALREADY_RELOCATED = 102
    INVALID_REQUEST = 103
    NO_SCENE = 104
    INVALID_SCENE = 105
    NO_CARTESIAN_PATH = 201
    IK_NOT_CONVERGED = 202
    JOINT_LIMIT = 203
    SELF_COLLISION = 204
    SCENE_COLLISION = 205
    VERIFICATION_FAILED = 206
    NO_PLACEMENT = 207
    OBJECT_TOO_BIG = 208
    CARRIED_COLLISION = 209
    TIMEOUT = 301
    EXECUTION_FAILED = 302
    PLANNER_BUSY = 303  # not planned: the queue was full; ask again later (#18)
    SCENE_CHANGED = 304  # the scene changed under the execution; undone, re-plan (#32)
    GRASP_FAILED = 305  # the attach service refused the grasp; undone, re-plan (#32)


class ReasonFamily(IntEnum):
    """The families of ``RelocateObject.srv``'s reason codes (nav2/MoveIt style: the hundreds)."""

    SUCCESS = 0
    REQUEST_ERROR = 1  # 1xx: the request or scene is wrong; asking again gives the same answer
    PLANNING_FAILURE = 2  # 2xx: planned, infeasible (-1 of eq. 8)
    RUNTIME_FAILURE = 3  # 3xx: time-out, busy, execution: says nothing about feasibility
    UNKNOWN = 9  # negative or >= 400: no family of the .srv (a client cannot read the answer)


def reason_family(code: int) -> ReasonFamily:
    """Family of a reason code, also of a 1xx-3xx code this planner does not know (a newer one)."""
    family = int(code) // 100
    if code < 0 or family > ReasonFamily.RUNTIME_FAILURE:
        return ReasonFamily.UNKNOWN
    return ReasonFamily(family) if code else ReasonFamily.SUCCESS


def _empty(*shape: int) -> np.ndarray:
    return np.zeros(shape)


@dataclass(frozen=True)
class PlanResult:
    """Outcome of one relocation check.

    Attributes:
        feasible: True when the object can be grasped and relocated.
        reason: :class:`Reason` code (``SUCCESS`` iff ``feasible``).
        message: human-readable explanation.
        times: time from start of each trajectory sample [s], shape (N,).
        joint_trajectory: joint angles of each sample [rad], shape (N, 7).
        ee_path: sampled Cartesian end-effector path, xyz [m] + quaternion xyzw, shape (M, 7).
        grasp_index: trajectory index where the object is attached (-1 if none).
        release_index: trajectory index where the object is released (-1 if none).
        planning_time: wall time of the check [s] (of the original run when from the cache).
        cpu_time: CPU time of the planning thread during the check [s] (same run; 0 when not
            planned, e.g. a bad request). Unlike the wall time, load on other cores leaves it
            unchanged (benchmarks report both, #28).
        timings: wall time by stage: ``'sampling'``, ``'stpik'``, ``'collision'`` [s].
        from_cache: True when answered from the feasibility cache.
        approach_yaw: yaw of the approach axis used for the grasp [rad] (NaN if none); of a
            top grasp, the yaw of its closing direction (:mod:`.grasps`).
        grasp_family: the grasp family of a feasible answer, ``'side'`` or ``'top'`` (#30);
            ``''`` when infeasible.
        blocking_ids: infeasible planning answers: the movable objects whose removal the planner
            believes necessary for its most promising approach (see :mod:`.blockers`).
        blocked_by_immovable: no approach works even with every movable object removed.
        approach_blockers: infeasible planning answers: the blockers of every working approach,
            fewest first (``blocking_ids`` is the first, or the near-miss fallback).
    """

    feasible: bool
    reason: Reason
    message: str
    _: KW_ONLY  # everything after the answer itself by keyword (#27, #28)
    times: np.ndarray = field(default_factory=lambda: _empty(0))
    joint_trajectory: np.ndarray = field(default_factory=lambda: _empty(0, 7))
    ee_path: np.ndarray = field(default_factory=lambda: _empty(0, 7))
    grasp_index: int = -1
    release_index: int = -1
    planning_time: float = 0.0
    cpu_time: float = 0.0
    timings: dict[str, float] = field(default_factory=dict)
    from_cache: bool = False
    approach_yaw: float = float('nan')
    grasp_family: str = ''
    blocking_ids: tuple[str, ...] = ()
    blocked_by_immovable: bool = False
    approach_blockers: tuple[tuple[str, ...], ...] = ()

    def failed(self, reason: Reason, message: str) -> PlanResult:
        """This answer with its motion kept, turned infeasible with ``reason`` and why."""
        return dataclasses.replace(self, feasible=False, reason=reason, message=message)
