"""Where the arm is and will be, from delayed measurements: a Smith predictor (no ROS import).

The closed loop streams a joint reference every tick and reads the arm back through
``/joint_states``; both legs go through DDS and two executors, so a measurement shows the arm as
it was one or more ticks ago, and the arm reaches a reference one or more ticks after it was
sent. On a loaded machine the round trip grows to 5-20 ticks (#26). Correcting the reference
with ``x_d(t) ⊖ x(q_measured)`` then integrates an error that is mostly the delay itself: the
reference overshoots, the arm follows it a round trip later, and the loop oscillates (on s1's O4
plan with 10 + 10 ticks of delay: 77 mm off the plan, the fingers 0.3 mm from the table).

:class:`ArmObserver` keeps the references it streamed and the last measurements. The latency
``l`` (in ticks, up to :data:`MAX_LATENCY_S`) is the shift that best matches the arm's last
motion, ``q_m(k) − q_m(k − D)``, with the references' ``ref(k − l) − ref(k − l − D)``
(:data:`MOTION_TICKS` = D), its squared misfit averaged per shift over
:data:`LATENCY_TIME_CONSTANT_S` of motion (one tick's match is noise: with 1 mrad of
measurement noise the shift jumped between 0 and 30 ticks), and a new shift is taken only when
its misfit is under :data:`SWITCH_RATIO` of the current one's (at constant joint velocity every
shift moves alike; the first average, after one tick, chose 28 ticks on the execution
benchmark's noise_1mrad s3:O2 run and called the arm 58 mm off). A difference, so a constant
offset cannot pass for a latency (matched
on positions, 0.05 rad on the shoulder was half explained as 8 ticks of latency and came back as
a 14 mm deviation at the next turn of the path). At rest nothing is matched and the last
latency is kept; until the first motion is matched the latency is the shift whose reference is
nearest to ``q_m − offset``, and the offset is learnt only while the references stand still
(then any latency shows the same reference). Each measurement is then compared with the
reference it shows, which gives

* the arm's offset from what it is sent (an actuator offset, an arm that runs slower than the
  reference), low-pass filtered with :data:`OFFSET_TIME_CONSTANT_S`;
* the plan time the arm should have been at when it was measured, so the tracking error is the
  arm's deviation from the plan, not the distance the plan moved during the round trip;
* the predicted arm, ``q_ref + offset``: the configuration the controller corrects (no delay in
  that loop, so it cannot oscillate), while the safety checks stay on the measured arm.

An arm held back (by an obstacle, a stalled servo) looks like a longer latency only up to
:data:`MAX_LATENCY_S`; beyond it the matched reference stays the oldest one, the deviation grows
and the tracking check stops the arm.
"""

from __future__ import annotations

from collections import deque

import numpy as np

MAX_LATENCY_S = 0.3  # longest round trip the observer explains as latency [s]
OFFSET_TIME_CONSTANT_S = 0.1  # low-pass of the arm's offset from its reference [s]
MOTION_TICKS = 10  # D: the latency is matched on the motion over this many ticks
MIN_MOTION_RAD = 0.01  # ... when the arm moved at least this much in them [rad] (noise ~1 mrad)
LATENCY_TIME_CONSTANT_S = 0.5  # averaging of the misfit of each latency [s]
MIN_MOTION_SAMPLES = 20  # ticks of motion matched before the latency counts as measured
SWITCH_RATIO = 0.5  # another latency is taken when its misfit is under this share of the current


class ArmObserver:
    """Latency, offset and predicted arm from the streamed references and the measurements.

    Attributes:
        offset: estimated measured − followed reference [rad], shape (7,).
        latency_ticks: ticks between a reference and the measurement that shows it (last match).
    """

    def __init__(self, period: float) -> None:
        """``period``: control period [s]."""
        self.period = period
        self.max_latency_ticks = max(1, round(MAX_LATENCY_S / period))
        self._sent: deque[tuple[np.ndarray, float]] = deque(
            maxlen=self.max_latency_ticks + MOTION_TICKS + 1
        )
        self._measured: deque[np.ndarray] = deque(maxlen=MOTION_TICKS + 1)
        self._misfit = np.zeros(self.max_latency_ticks + 1)  # averaged squared misfit per lag
        self._samples = 0  # ticks of motion averaged in it
        self.offset = np.zeros(7)
        self.latency_ticks = 0

    def start(self, q_ref: np.ndarray, plan_time: float, same_motion: bool = True) -> None:
        """A segment starts at reference ``q_ref`` [rad] (7,), plan time ``plan_time`` [s].

        The references of the previous segment are kept when it ended on ``q_ref`` (the arm may
        still be following them). Otherwise (the first segment, or a new start after a stop,
        where the arm was held where it was measured) the history restarts at ``q_ref``: the arm
        no longer follows the old references (kept, the way back after a stop was "90.7 mm off"
        in the node tests while on its path). It restarts too when ``same_motion`` is False:
        the plan times of another motion mean nothing in this one (the way back after a failed
        grasp starts where the arm rests, bit for bit the last reference, and was matched with
        the forward motion's plan times: "636 mm off", every soak run). The offset and the
        latency statistics are kept.
        """
        q_ref = np.array(q_ref, dtype=float)
        if same_motion and self._sent and np.array_equal(self._sent[-1][0], q_ref):
            return
        self._sent.clear()
        self._measured.clear()
        self._sent.append((q_ref, float(plan_time)))

    def sent(self, q_ref: np.ndarray, plan_time: float) -> None:
        """The reference ``q_ref`` [rad] (7,) was streamed, aiming at plan time ``plan_time``."""
        self._sent.append((np.array(q_ref, dtype=float), float(plan_time)))

    def measured(self, q: np.ndarray) -> float:
        """Take the measurement ``q`` [rad] (7,); returns the plan time it should show [s].

        The latency is matched on the last motion (see the module); the offset moves toward
        ``q −`` the reference of that latency.
        """
        q = np.asarray(q, dtype=float)
        self._measured.append(q.copy())
        references = np.array([r for r, _ in self._sent])  # oldest first
        newest = len(references) - 1
        motion = q - self._measured[0]
        if (
            len(self._measured) > MOTION_TICKS
            and newest >= self.max_latency_ticks + MOTION_TICKS
            and np.linalg.norm(motion) >= MIN_MOTION_RAD
        ):
            lags = np.arange(self.max_latency_ticks + 1)
            shifted = references[newest - lags] - references[newest - lags - MOTION_TICKS]
            self._samples += 1
            beta = max(1.0 / self._samples, self.period / LATENCY_TIME_CONSTANT_S)
            self._misfit += beta * (np.sum((motion - shifted) ** 2, axis=1) - self._misfit)
        identified = self._samples >= MIN_MOTION_SAMPLES
        if identified:
            best = int(np.argmin(self._misfit))  # the smallest on a tie
            if self._misfit[best] < SWITCH_RATIO * self._misfit[self.latency_ticks]:
                self.latency_ticks = best
        else:
            lags = np.arange(min(self.max_latency_ticks, newest) + 1)
            misfit = np.linalg.norm(q - self.offset - references[newest - lags], axis=1)
            self.latency_ticks = int(lags[np.argmin(misfit)])
        index = max(0, newest - self.latency_ticks)
        window = references[max(0, newest - self.max_latency_ticks) :]
        still = float(np.max(np.ptp(window, axis=0))) < MIN_MOTION_RAD
        if identified or still:
            alpha = min(1.0, self.period / OFFSET_TIME_CONSTANT_S)
            self.offset += alpha * ((q - references[index]) - self.offset)
        return self._sent[index][1]

    def predicted(self, q_ref: np.ndarray) -> np.ndarray:
        """Where the arm goes on the reference ``q_ref`` [rad] (7,): ``q_ref + offset``."""
        return np.asarray(q_ref, dtype=float) + self.offset
