"""Typed exceptions of the motion planner, all under :class:`MotionPlannerError` (no ROS import).

Every exception carries the :class:`~stpik_motion_planner.result.Reason` it maps to, so the planner
turns any of them into a :class:`~stpik_motion_planner.result.PlanResult` in one place.
"""

from __future__ import annotations

import time

from stpik_motion_planner.result import Reason


class MotionPlannerError(Exception):
    """Base class of every error raised by the motion-planner core."""

    reason: Reason = Reason.INVALID_REQUEST


def copy_error(err: MotionPlannerError, args: tuple | None = None) -> MotionPlannerError:
    """A copy of ``err`` (same type and attributes) with ``args`` (default: its own), so a
    remembered failure raised again is never changed by its next catcher (#28).
    """
    again = type(err).__new__(type(err))
    again.__dict__.update(err.__dict__)
    again.args = err.args if args is None else args
    return again


class InvalidRequest(MotionPlannerError):  # noqa: N818
    """A request or scene cannot be planned for (unknown id, duplicates, NaN pose...)."""

    def __init__(self, reason: Reason, message: str) -> None:
        self.reason = reason
        super().__init__(message)


class InvalidConfig(MotionPlannerError, ValueError):  # noqa: N818
    """A :class:`~stpik_motion_planner.config.PlannerConfig` value is out of range."""

    def __init__(self, name: str, value: object, problem: str) -> None:
        self.name = name
        self.value = value
        super().__init__(f'{name}={value!r}: {problem}')


class NoCartesianPath(MotionPlannerError):  # noqa: N818
    """No approach direction has a collision-free Cartesian path for the hand."""

    reason = Reason.NO_CARTESIAN_PATH

    def __init__(self, object_id: str, detail: str) -> None:
        self.object_id = object_id
        super().__init__(f'no collision-free Cartesian path to {object_id!r}: {detail}')


class IkNotConverged(MotionPlannerError):  # noqa: N818
    """STPIK could not track the end-effector path within tolerance."""

    reason = Reason.IK_NOT_CONVERGED

    def __init__(
        self, sample: int, residual_m: float, residual_rad: float, detail: str = ''
    ) -> None:
        self.sample = sample
        self.residual_m = residual_m
        self.residual_rad = residual_rad
        super().__init__(
            f'tracking error at sample {sample}: {residual_m * 1000:.1f} mm, '
            f'{residual_rad:.3f} rad' + (f' ({detail})' if detail else '')
        )


class JointLimitViolated(MotionPlannerError):  # noqa: N818
    """A joint left its mechanical range (or was held at it while tracking failed)."""

    reason = Reason.JOINT_LIMIT

    def __init__(self, joint: int, value: float, lower: float, upper: float) -> None:
        self.joint = joint
        self.value = value
        self.lower = lower
        self.upper = upper
        super().__init__(
            f'joint {joint + 1} at {value:.3f} rad, range [{lower:.3f}, {upper:.3f}] rad'
        )


class TooClose(MotionPlannerError):  # noqa: N818
    """Two bodies came closer than a margin: the base of the collision errors.

    Attributes:
        bodies: the two bodies (link names, or a link and an object id).
        distance_m: their distance [m].
    """

    def __init__(self, bodies: tuple[str, str], distance_m: float, what: str) -> None:
        self.bodies = bodies
        self.distance_m = distance_m
        super().__init__(f'{what}: distance {distance_m * 1000:.1f} mm')


class SelfCollision(TooClose):
    """Two links of the arm came closer than the self-hit margin."""

    reason = Reason.SELF_COLLISION

    def __init__(self, link_a: str, link_b: str, distance_m: float) -> None:
        super().__init__((link_a, link_b), distance_m, f'self-hit {link_a} / {link_b}')


class SceneCollision(TooClose):
    """A link (or the grasped object) came closer to a scene object than the safety margin."""

    reason = Reason.SCENE_COLLISION

    def __init__(self, link: str, object_id: str, distance_m: float) -> None:
        super().__init__((link, object_id), distance_m, f'{link} hits {object_id!r}')


class VerificationFailed(MotionPlannerError):  # noqa: N818
    """The independent verifier (:mod:`.verifier`) rejected a trajectory STPIK accepted."""

    reason = Reason.VERIFICATION_FAILED

    def __init__(self, detail: str, carried: bool = False) -> None:
        if carried:
            self.reason = Reason.CARRIED_COLLISION
        super().__init__(f'trajectory rejected by the verifier: {detail}')


class NoPlacement(MotionPlannerError):  # noqa: N818
    """No drop slot is left for the object (see ``qtree_scene.placement``)."""

    reason = Reason.NO_PLACEMENT


class ObjectTooBig(MotionPlannerError):  # noqa: N818
    """The object does not fit between the fingers of the open hand."""

    reason = Reason.OBJECT_TOO_BIG


class PlanningTimeout(MotionPlannerError):  # noqa: N818
    """The check ran past ``PlannerConfig.time_limit_s``.

    Attributes:
        elapsed_s: planning time when the limit was noticed [s] (from the start of the check).
        limit_s: the time limit [s].
    """

    reason = Reason.TIMEOUT

    def __init__(self, elapsed_s: float, limit_s: float) -> None:
        """Args: ``elapsed_s`` since the check started [s], not the overrun; ``limit_s`` [s]."""
        self.elapsed_s = elapsed_s
        self.limit_s = limit_s
        super().__init__(f'planning took {elapsed_s:.3f} s > time limit {limit_s:.3f} s')

    @classmethod
    def past(cls, deadline: float, limit_s: float) -> PlanningTimeout:
        """The timeout noticed now for a check whose ``deadline`` is start + ``limit_s``.

        Args:
            deadline: ``time.perf_counter()`` value at which the check had to end [s].
            limit_s: the time limit [s].
        """
        return cls(time.perf_counter() - (deadline - limit_s), limit_s)
