"""When is the arm's joint-state stream silent, when has an open-loop segment arrived, and when
has a closed-loop segment stopped making progress?

Plain Python (no ROS): the execution classes of the ``motion_planner`` node call these with
``time.monotonic()`` times and the last ``sensor_msgs/JointState``.
"""

from __future__ import annotations

import math

import numpy as np

STALL_S = 0.5  # a check this late after the previous one means this process did not run [s]
SETTLED_RAD_S = 0.01  # an arm whose joints all move slower than this is at rest [rad/s]
# (the simulator publishes exactly 0 at rest; 0.01 leaves room for a real arm's encoder noise)


class SilenceWatch:
    """Silence of the joint-state stream [s], not counting time this process itself was stalled.

    Comparing the last message's arrival with the clock blames the simulator when the watching
    process did not run (CPU starvation, a pause): the simulator's messages are then waiting in
    our queue. Seen in the node tests with two test workers on 2 cores: the simulator and the
    motion planner both froze for 3.5 s and the planner stopped the arm for the simulator's
    "silence" the moment both woke. A check that comes more than ``stall_s`` after the previous
    one restarts the count, so the queued messages get their chance; a simulator that really
    stopped publishing is still caught ``timeout_s`` later, since the checks then come on time.
    """

    def __init__(self, stall_s: float = STALL_S) -> None:
        self.stall_s = stall_s
        self._last_check = -math.inf
        self._since = -math.inf

    def start(self, now: float) -> None:
        """Begin watching at ``now`` [s]: silence counts from here at most."""
        self._since = self._last_check = now

    def silence(self, last_message_time: float, now: float) -> float:
        """Seconds without a message [s] at ``now``, given the last one's arrival time [s]."""
        if now - self._last_check > self.stall_s:
            self._since = now  # we were not running: the gap is ours, not the publisher's
        self._last_check = now
        return now - max(last_message_time, self._since)


class ProgressWatch:
    """Time [s] since a closed-loop segment's reference last advanced along the plan.

    The closed loop moves its reference one control period per tick, so a machine that ticks
    late follows the plan slower but still follows it (the README demo ticked at 27 Hz instead
    of 100); a wait of "the segment's duration + a margin" ended such a segment as failed. What
    is wrong is a reference that does not move at all.
    """

    def __init__(self, plan_time: float, now: float) -> None:
        self._plan_time, self._since = plan_time, now

    def stalled_for(self, plan_time: float, now: float) -> float:
        """Seconds at ``now`` [s] since the reference time (``plan_time`` [s]) last changed."""
        if plan_time != self._plan_time:
            self._plan_time, self._since = plan_time, now
        return now - self._since


def arrived(
    q: np.ndarray | None,
    speed: float | None,
    q_goal: np.ndarray,
    tolerance_rad: float,
    elapsed_s: float,
    duration_s: float,
) -> bool:
    """Has an open-loop segment ended at ``q_goal``?

    The arm must be within ``tolerance_rad`` of the goal on every joint, after the segment's
    ``duration_s`` [s] and at rest (fastest joint below :data:`SETTLED_RAD_S`; ``speed`` None when
    the joint states carry no velocities). A position check alone fired while the arm was still
    travelling through the tolerance band, so the object was released wherever the arm happened
    to be (test_closed_loop_execution, open loop with a 0.05 rad servo offset: 4.1 mm instead of
    the offset's 20 mm under load).

    Args:
        q: measured arm joints [rad], shape (7,), or None before the first joint state.
        speed: largest |joint velocity| [rad/s] of the last joint state, or None.
        q_goal: the segment's last sample [rad], shape (7,).
        tolerance_rad: the ``goal_tolerance_rad`` parameter [rad].
        elapsed_s: time since the segment was sent [s].
        duration_s: the segment's duration [s].
    """
    if q is None or elapsed_s < duration_s:
        return False
    if np.max(np.abs(q - q_goal)) >= tolerance_rad:
        return False
    return speed is None or speed < SETTLED_RAD_S
