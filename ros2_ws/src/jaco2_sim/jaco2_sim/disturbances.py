"""Disturbances of the simulated arm, for testing closed-loop execution (no ROS import).

All are off by default. :class:`Disturbances` holds the validated values; the integrator applies
the joint offset and the velocity-limit scale (:meth:`JointIntegrator.disturb`),
:class:`CommandDelay` the command latency and :class:`MeasurementNoise` the noise of the
published joint state (the true state is never noisy).

* ``joint_offset_rad`` (7,): the joint servos settle at command + offset [rad], a calibration
  error an open-loop executor cannot see but the measured state shows.
* ``latency_s``: every command (trajectory or streamed point) takes effect this late [s].
* ``velocity_limit_scale``: the arm only reaches this fraction of its velocity limits [-]
  (1 = nominal).
* ``noise_rad``: standard deviation of zero-mean Gaussian noise on the published joint
  positions [rad], seeded by ``noise_seed``.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from qtree_node_support.ranges import range_problem

from jaco2_sim.exceptions import DisturbanceError

MAX_OFFSET_RAD = 0.5  # largest joint offset accepted [rad]
MAX_LATENCY_S = 2.0  # largest command latency accepted [s]
MAX_NOISE_RAD = 0.1  # largest measurement noise accepted [rad]
MIN_VELOCITY_SCALE = 0.05  # smallest velocity-limit scale accepted [-]


@dataclass(frozen=True)
class Disturbances:
    """Validated disturbance values (see the module docstring for their meaning and units)."""

    joint_offset_rad: tuple[float, ...] = (0.0,) * 7
    latency_s: float = 0.0
    velocity_limit_scale: float = 1.0
    noise_rad: float = 0.0
    noise_seed: int = 0

    def __post_init__(self) -> None:
        offset = tuple(float(v) for v in _numbers('joint_offset_rad', self.joint_offset_rad))
        if len(offset) != 7:
            raise DisturbanceError(f'joint_offset_rad: 7 values expected, got {len(offset)}')
        if any(abs(v) > MAX_OFFSET_RAD for v in offset):
            raise DisturbanceError(f'joint_offset_rad: each |value| must be ≤ {MAX_OFFSET_RAD}')
        object.__setattr__(self, 'joint_offset_rad', offset)
        _in_range('latency_s', self.latency_s, 0.0, MAX_LATENCY_S)
        _in_range('velocity_limit_scale', self.velocity_limit_scale, MIN_VELOCITY_SCALE, 1.0)
        _in_range('noise_rad', self.noise_rad, 0.0, MAX_NOISE_RAD)
        if isinstance(self.noise_seed, bool) or not isinstance(self.noise_seed, int):
            raise DisturbanceError(f'noise_seed: an integer expected, got {self.noise_seed!r}')
        if self.noise_seed < 0:
            raise DisturbanceError(f'noise_seed: must be ≥ 0, got {self.noise_seed}')

    @property
    def active(self) -> bool:
        """True when any disturbance is on."""
        return self != Disturbances(noise_seed=self.noise_seed)


def _numbers(name: str, values: Sequence[Any]) -> list[float]:
    try:
        out = [float(v) for v in values]
    except (TypeError, ValueError):
        raise DisturbanceError(f'{name}: numbers expected, got {values!r}') from None
    if not all(math.isfinite(v) for v in out):
        raise DisturbanceError(f'{name}: every value must be finite, got {out}')
    return out


def _in_range(name: str, value: Any, low: float, high: float) -> None:
    problem = range_problem(value, low, high)
    if problem is not None:
        raise DisturbanceError(f'{name}: {problem}, got {value!r}')


@dataclass
class CommandDelay:
    """FIFO of commands that take effect ``latency_s`` after they were received.

    Attributes:
        latency_s: delay [s] (0: every command is due at once).
    """

    latency_s: float = 0.0
    _queue: deque = field(default_factory=deque)

    def push(self, now: float, command: Any) -> None:
        """Queue ``command`` received at ``now`` [s]."""
        self._queue.append((now + self.latency_s, command))

    def due(self, now: float) -> list[Any]:
        """Commands whose time has come at ``now`` [s], oldest first (removed from the queue)."""
        out = []
        while self._queue and self._queue[0][0] <= now + 1e-9:
            out.append(self._queue.popleft()[1])
        return out

    def clear(self) -> None:
        """Drop every pending command."""
        self._queue.clear()

    def __len__(self) -> int:
        return len(self._queue)


class MeasurementNoise:
    """Seeded Gaussian noise on measured joint positions."""

    def __init__(self, sigma_rad: float = 0.0, seed: int = 0) -> None:
        self.sigma = float(sigma_rad)
        self._rng = np.random.default_rng(seed)

    def measure(self, q: np.ndarray) -> np.ndarray:
        """``q`` [rad] (7,) plus noise (a copy; ``q`` itself when the noise is off)."""
        if self.sigma == 0.0:
            return np.asarray(q, dtype=float)
        return np.asarray(q, dtype=float) + self._rng.normal(0.0, self.sigma, len(q))


# ROS parameter of the sim node -> Disturbances field.
PARAMETER_FIELDS = {
    'joint_offset_rad': 'joint_offset_rad',
    'command_latency_s': 'latency_s',
    'velocity_limit_scale': 'velocity_limit_scale',
    'measurement_noise_rad': 'noise_rad',
    'noise_seed': 'noise_seed',
}


def from_parameters(values: dict[str, Any]) -> Disturbances:
    """:class:`Disturbances` from sim-node parameter values (names of :data:`PARAMETER_FIELDS`).

    Raises:
        DisturbanceError: a value is NaN, negative, out of range or of the wrong type; the
            message names the parameter.
    """
    fields: dict[str, Any] = {}
    for parameter, name in PARAMETER_FIELDS.items():
        if parameter in values:
            value = values[parameter]
            fields[name] = tuple(value) if name == 'joint_offset_rad' else value
    try:
        return Disturbances(**fields)
    except DisturbanceError as err:
        text = str(err)
        for parameter, name in PARAMETER_FIELDS.items():
            if text.startswith(f'{name}:'):
                text = parameter + text[len(name) :]
        raise DisturbanceError(text) from None


class DisturbedDrive:
    """The integrator behind the disturbances: commands go through the latency queue, the offset
    and velocity-limit scale act in the integrator, the measurement is noisy.

    Attributes:
        sim: the integrator (its ``q`` is the true state).
        disturbances: the values in force.
    """

    def __init__(self, sim: Any, disturbances: Disturbances | None = None) -> None:
        self.sim = sim
        self.applied_kind = ''  # kind of the command in force: 'trajectory', 'point' or ''
        self.delay = CommandDelay()
        self.noise = MeasurementNoise()
        self.disturbances = Disturbances()
        self.configure(disturbances or Disturbances())

    def configure(self, disturbances: Disturbances) -> None:
        """Put ``disturbances`` in force (pending commands keep their due times)."""
        self.disturbances = disturbances
        self.sim.disturb(disturbances.joint_offset_rad, disturbances.velocity_limit_scale)
        self.delay.latency_s = disturbances.latency_s
        self.noise = MeasurementNoise(disturbances.noise_rad, disturbances.noise_seed)

    def command(self, kind: str, *args: Any) -> bool:
        """Apply now, or queue when there is latency: ``('trajectory', names, times, positions,
        velocities)`` or ``('point', names, positions)``.

        Returns:
            True when applied now and some positions were clamped to the joint limits.

        Raises:
            TrajectoryError: (applied now) a malformed command; the current motion is kept.
        """
        if self.delay.latency_s > 0.0:
            self.delay.push(self.sim.time, (kind, args))
            return False
        return self._apply(kind, args)

    def apply_due(self) -> list[str]:
        """Apply the queued commands that are due; the errors of the malformed ones."""
        errors = []
        for kind, args in self.delay.due(self.sim.time):
            try:
                self._apply(kind, args)
            except Exception as err:  # reported; the sim keeps running
                errors.append(str(err))
        return errors

    def measured(self) -> np.ndarray:
        """The measured arm angles [rad] (7,): true state + noise."""
        return self.noise.measure(self.sim.q)

    def _apply(self, kind: str, args: tuple) -> bool:
        clamped = self.sim.set_point(*args) if kind == 'point' else self.sim.set_reference(*args)
        self.applied_kind = kind  # after the integrator accepted it
        return clamped
