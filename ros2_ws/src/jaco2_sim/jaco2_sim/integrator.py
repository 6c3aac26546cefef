"""Kinematic joint integrator of the simulated arm: tracks a reference within the limits (no ROS).

Each :meth:`JointIntegrator.step` advances the arm by one period dt = 1 / rate. The commanded
velocity is the dead-beat tracking velocity v = (q_ref(t + dt) - q) / dt, scaled down uniformly so
that |v_i| ≤ v_max,i for every joint (which keeps the direction of motion in joint space); then
q ← clamp(q + v dt, lower, upper). A reference within the velocity limits is therefore tracked
exactly; a faster one lags and catches up after its end time. q_ref(t) is linear between
points, or a cubic Hermite spline when the points carry velocities. As in ros2_control's joint
trajectory controller, if the first point's time is > 0 the current state is used as the point
at t = 0; a single point at t = 0 means "go there as fast as the limits allow".
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from jaco2_description.model import ARM_JOINTS, JointLimits

from jaco2_sim.exceptions import TrajectoryError

GOAL_TOLERANCE = 1e-4  # a reference is finished when every joint is this close to its end [rad]


class JointIntegrator:
    """State of the 7 arm joints and a reference to track.

    Attributes:
        limits: arm joint limits.
        period: integration step dt [s].
        time: simulated time since construction [s].
        q: arm joint angles [rad], shape (7,), in :data:`ARM_JOINTS` order (read-only view).
        velocity: last commanded joint velocity [rad/s], shape (7,).
    """

    def __init__(
        self, limits: JointLimits, rate_hz: float = 100.0, q0: np.ndarray | None = None
    ) -> None:
        """Create the integrator at ``q0`` [rad] (7,) (default: middle of the limits).

        Raises:
            TrajectoryError: ``rate_hz`` not in (0, 10000] or a bad ``q0``.
        """
        if not (np.isfinite(rate_hz) and 0 < rate_hz <= 10000):
            raise TrajectoryError(f'rate_hz must be in (0, 10000], got {rate_hz}')
        self.limits = limits
        self.period = 1.0 / rate_hz
        self.time = 0.0
        self.velocity = np.zeros(7)
        self._q = np.zeros(7)
        self._times: np.ndarray | None = None  # reference knot times since start [s], (N,)
        self._points: np.ndarray | None = None  # (N, 7) [rad]
        self._speeds: np.ndarray | None = None  # (N, 7) [rad/s] or None
        self._start = 0.0
        self.offset = np.zeros(7)  # the servos settle at reference + offset [rad] (disturbance)
        self.velocity_scale = 1.0  # fraction of the velocity limits reached [-] (disturbance)
        self.reset(0.5 * (limits.lower + limits.upper) if q0 is None else q0)

    @property
    def q(self) -> np.ndarray:
        """Arm joint angles [rad], shape (7,) (read-only)."""
        view = self._q.view()
        view.flags.writeable = False
        return view

    @property
    def active(self) -> bool:
        """True while a reference is being followed."""
        return self._times is not None

    def reset(self, q: np.ndarray) -> None:
        """Teleport to ``q`` [rad] (7,) and drop the reference.

        Raises:
            TrajectoryError: wrong length, non-finite or outside the limits.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (7,) or not np.all(np.isfinite(q)):
            raise TrajectoryError(f'configuration must be 7 finite angles, got {q}')
        if np.any(q < self.limits.lower) or np.any(q > self.limits.upper):
            raise TrajectoryError(f'configuration {q} outside the joint limits')
        self._q = q.copy()
        self.velocity = np.zeros(7)
        self.cancel()

    def cancel(self) -> None:
        """Stop following the reference; the arm holds its position."""
        self._times = self._points = self._speeds = None
        self.velocity = np.zeros(7)

    def disturb(self, joint_offset_rad: Sequence[float], velocity_scale: float) -> None:
        """Set the disturbances: servo offset [rad] (7,) and velocity-limit scale (0, 1] [-].

        Validated by :class:`jaco2_sim.disturbances.Disturbances`.
        """
        self.offset = np.asarray(joint_offset_rad, dtype=float).copy()
        self.velocity_scale = float(velocity_scale)

    def set_reference(
        self,
        joint_names: Sequence[str],
        times: Sequence[float],
        positions: Sequence[Sequence[float]],
        velocities: Sequence[Sequence[float]] | None = None,
    ) -> bool:
        """Start following a reference trajectory from the current time.

        Args:
            joint_names: the 7 arm joint names, any order (columns of positions/velocities).
            times: time of each point since the start [s], shape (N,), ≥ 0, strictly increasing.
            positions: joint angles [rad], shape (N, 7).
            velocities: joint velocities [rad/s], shape (N, 7), or None / empty for linear
                interpolation.

        Returns:
            True if some positions were outside the joint limits and were clamped to them.

        Raises:
            TrajectoryError: wrong names, shapes, times, or non-finite values (the current
                reference, if any, is kept).
        """
        names = list(joint_names)
        if sorted(names) != sorted(ARM_JOINTS):
            raise TrajectoryError(
                f'joint names must be the 7 arm joints {ARM_JOINTS}, got {names}'
            )
        order = [names.index(n) for n in ARM_JOINTS]
        t = _array(times, 'times', (-1,))
        n = t.shape[0]
        if n == 0:
            raise TrajectoryError('trajectory has no points')
        if t[0] < 0 or np.any(np.diff(t) <= 0):
            raise TrajectoryError(f'times must be ≥ 0 and strictly increasing, got {t}')
        p = _array(positions, 'positions', (n, 7))[:, order]
        v = None
        if velocities is not None and len(velocities) > 0:
            v = _array(velocities, 'velocities', (n, 7))[:, order]
        clipped = np.clip(p, self.limits.lower, self.limits.upper)
        clamped = bool(np.any(clipped != p))
        if t[0] > 0:
            t = np.concatenate(([0.0], t))
            clipped = np.vstack((self._q, clipped))
            v = None if v is None else np.vstack((np.zeros(7), v))
        self._times, self._points, self._speeds = t, clipped, v
        self._start = self.time
        return clamped

    def set_point(self, joint_names: Sequence[str], positions: Sequence[float]) -> bool:
        """Go to one configuration [rad] as fast as the velocity limits allow."""
        return self.set_reference(joint_names, [0.0], [positions])

    def reference_at(self, t: float) -> np.ndarray:
        """Reference joint angles [rad] (7,) at ``t`` [s] after the start (held after the end)."""
        if self._times is None or self._points is None:
            return self._q.copy()
        times, points = self._times, self._points
        if t >= times[-1]:
            return points[-1].copy()
        k = int(np.searchsorted(times, t, side='right')) - 1
        k = max(k, 0)
        h = times[k + 1] - times[k]
        s = (t - times[k]) / h
        if self._speeds is None:
            return (1 - s) * points[k] + s * points[k + 1]
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        v = self._speeds
        return h00 * points[k] + h10 * h * v[k] + h01 * points[k + 1] + h11 * h * v[k + 1]

    def step(self) -> bool:
        """Advance one period.

        Returns:
            True if the reference finished in this step (the arm is within
            :data:`GOAL_TOLERANCE` of the last point, after the last point's time).
        """
        self.time += self.period
        if self._times is None or self._points is None:
            self.velocity = np.zeros(7)
            return False
        elapsed = self.time - self._start
        target = np.clip(
            self.reference_at(elapsed) + self.offset, self.limits.lower, self.limits.upper
        )
        v = (target - self._q) / self.period
        ratio = float(np.max(np.abs(v) / (self.limits.velocity * self.velocity_scale)))
        if ratio > 1.0:
            v /= ratio
        previous = self._q
        self._q = np.clip(previous + v * self.period, self.limits.lower, self.limits.upper)
        self.velocity = (self._q - previous) / self.period
        end = np.clip(self._points[-1] + self.offset, self.limits.lower, self.limits.upper)
        if elapsed >= self._times[-1] and np.max(np.abs(self._q - end)) <= GOAL_TOLERANCE:
            self.cancel()
            return True
        return False


def _array(values: object, name: str, shape: tuple[int, ...]) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as err:
        raise TrajectoryError(f'{name}: not numeric ({err})') from None
    if array.ndim != len(shape) or any(
        s not in (-1, a) for s, a in zip(shape, array.shape, strict=True)
    ):
        want = 'x'.join('N' if s == -1 else str(s) for s in shape)
        raise TrajectoryError(f'{name}: shape {array.shape}, expected ({want})')
    if not np.all(np.isfinite(array)):
        raise TrajectoryError(f'{name}: non-finite value (NaN or inf)')
    return array
