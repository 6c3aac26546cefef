"""The joint-state watchdog and the open-loop arrival test (stpik_motion_planner.state_watch)."""

from __future__ import annotations

import numpy as np
from stpik_motion_planner.state_watch import SETTLED_RAD_S, ProgressWatch, SilenceWatch, arrived


def test_silence_grows_while_checks_come_on_time() -> None:
    watch = SilenceWatch(stall_s=0.5)
    watch.start(10.0)
    t = 10.0
    while t < 14.0:
        t += 0.01
        silent = watch.silence(last_message_time=10.0, now=t)
    assert abs(silent - 4.0) < 0.02  # a publisher that stopped is caught


def test_silence_counts_from_the_last_message_or_the_start() -> None:
    watch = SilenceWatch()
    watch.start(5.0)
    assert abs(watch.silence(last_message_time=-1.0, now=5.2) - 0.2) < 1e-9  # from the start
    assert abs(watch.silence(last_message_time=5.3, now=5.4) - 0.1) < 1e-9  # from the message


def test_our_own_stall_is_not_the_publishers_silence() -> None:
    """Before the fix the watchdog said 3.5 s of silence the moment both processes woke."""
    watch = SilenceWatch(stall_s=0.5)
    watch.start(0.0)
    for k in range(1, 101):  # 1 s of on-time checks, messages arriving
        watch.silence(last_message_time=k * 0.01, now=k * 0.01)
    # This process froze for 3.5 s; the queued messages have not been taken yet.
    assert watch.silence(last_message_time=1.0, now=4.5) == 0.0
    # Checks on time again: if no message comes now, the silence counts from the wake-up.
    assert abs(watch.silence(last_message_time=1.0, now=4.51) - 0.01) < 1e-9
    silent = 0.0
    t = 4.51
    while t < 8.0:
        t += 0.01
        silent = watch.silence(last_message_time=1.0, now=t)
    assert silent > 3.0  # a real silence after the wake-up is still caught


GOAL = np.zeros(7)


def test_an_arm_still_moving_through_the_tolerance_band_has_not_arrived() -> None:
    """Before the fix a position check released the object mid-motion (4.1 mm, not 20 mm)."""
    q = np.full(7, 0.04)
    assert not arrived(q, 0.3, GOAL, 0.1, elapsed_s=5.0, duration_s=4.0)
    assert arrived(q, 0.0, GOAL, 0.1, elapsed_s=5.0, duration_s=4.0)


def test_arrival_needs_the_segment_time_and_the_tolerance() -> None:
    q = np.full(7, 0.04)
    assert not arrived(q, 0.0, GOAL, 0.1, elapsed_s=1.0, duration_s=4.0)  # not sent long enough
    assert not arrived(q, 0.0, GOAL, 0.01, elapsed_s=5.0, duration_s=4.0)  # off by 0.04 rad
    assert not arrived(None, 0.0, GOAL, 0.1, elapsed_s=5.0, duration_s=4.0)  # no joint state
    assert arrived(q, None, GOAL, 0.1, elapsed_s=5.0, duration_s=4.0)  # no velocities published
    assert not arrived(q, SETTLED_RAD_S, GOAL, 0.1, elapsed_s=5.0, duration_s=4.0)


def test_a_slow_segment_is_not_stalled_while_its_reference_moves() -> None:
    """The README demo ticked at 27 Hz instead of 100: its first segment took 2.7x the plan's
    time and a fixed "duration + execution_timeout_s" wait failed it. Only a reference that
    does not move for the timeout counts."""
    watch = ProgressWatch(plan_time=0.0, now=100.0)
    for k in range(1, 500):  # 0.1 s of wall time, 0.0027 s of plan time per look: 50 s in all
        assert watch.stalled_for(plan_time=0.0027 * k, now=100.0 + 0.1 * k) == 0.0
    assert watch.stalled_for(plan_time=0.0027 * 499, now=100.0 + 0.1 * 499 + 31.0) == 31.0
    assert watch.stalled_for(plan_time=2.0, now=200.0) == 0.0  # moving again: the count restarts
