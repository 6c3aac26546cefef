"""ArmObserver (#26): latency and offset of a delayed arm from the streamed references."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from stpik_motion_planner.arm_observer import MAX_LATENCY_S, ArmObserver

PERIOD = 0.01  # control period [s]


def _references(ticks: int) -> np.ndarray:
    """A smooth joint path [rad] (ticks, 7) with turns (so shifts in time are told apart)."""
    t = np.arange(ticks) * PERIOD
    phases = np.linspace(0.0, 2.0, 7)
    return 0.3 * np.sin(0.8 * t[:, None] + phases) + 0.1 * np.sin(2.1 * t[:, None] + 2 * phases)


def _observe(latency: int, offset: np.ndarray, noise_rad: float = 0.0, ticks: int = 400):
    """Stream the path, measure it ``latency`` ticks late + ``offset``; the observer and the
    plan times it returned."""
    refs = _references(ticks)
    rng = np.random.default_rng(3)
    observer = ArmObserver(PERIOD)
    observer.start(refs[0], 0.0)
    shown = []
    for k in range(1, ticks):
        arm = refs[max(0, k - 1 - latency)] + offset  # ``latency`` ticks behind the newest
        shown.append(observer.measured(arm + rng.normal(0.0, noise_rad, 7)))
        observer.sent(refs[k], k * PERIOD)
    return observer, shown


@pytest.mark.parametrize('latency', [0, 3, 12, 25])
def test_the_latency_and_the_plan_time_a_measurement_shows_are_found(latency) -> None:
    observer, shown = _observe(latency, np.zeros(7))
    assert observer.latency_ticks == latency  # ticks behind the newest reference
    assert shown[-1] == pytest.approx((len(shown) - 1 - latency) * PERIOD)
    assert np.abs(observer.offset).max() < 1e-9


def test_a_constant_offset_is_not_taken_for_a_latency() -> None:
    """Matched on positions, a 0.05 rad shoulder offset passed for 8 ticks of latency (the
    offset half learnt); matched on the motion, both are right."""
    offset = np.array([0.0, 0.05, 0.0, 0.0, 0.0, 0.0, -0.02])
    observer, _ = _observe(6, offset)
    assert observer.latency_ticks == 6
    assert observer.offset == pytest.approx(offset, abs=1e-6)


def test_measurement_noise_does_not_make_the_latency_jump() -> None:
    """One tick's match is noise (1 mrad: the shift jumped between 0 and 30 ticks); averaged, it
    stays within a tick of the truth and the offset within noise."""
    observer, _ = _observe(8, np.zeros(7), noise_rad=0.001)
    assert abs(observer.latency_ticks - 8) <= 1
    assert np.abs(observer.offset).max() < 0.004


def test_an_offset_at_rest_is_learnt_before_anything_moves() -> None:
    observer = ArmObserver(PERIOD)
    q = np.full(7, 0.2)
    offset = np.array([0.0, 0.03, 0.0, 0.0, 0.0, 0.0, 0.0])
    observer.start(q, 1.5)
    for _ in range(100):
        assert observer.measured(q + offset) == 1.5
        observer.sent(q, 1.5)
    assert observer.offset == pytest.approx(offset, abs=1e-5)
    assert observer.predicted(q) == pytest.approx(q + offset, abs=1e-5)


@settings(max_examples=25, deadline=None)
@given(latency=st.integers(0, round(MAX_LATENCY_S / PERIOD) - 2), shift=st.floats(-0.05, 0.05))
def test_any_latency_in_range_with_any_offset_is_found(latency, shift) -> None:
    offset = np.full(7, shift)
    observer, _ = _observe(latency, offset)
    assert observer.latency_ticks == latency
    assert observer.offset == pytest.approx(offset, abs=1e-6)


def test_a_new_start_away_from_the_last_reference_forgets_the_old_references() -> None:
    """After a stop the node holds the arm where it was measured and starts the way back from
    there: matched against the references before the stop, the node tests logged 28-90.7 mm of
    "tracking error" on the way back while the arm was on its path."""
    observer, _ = _observe(4, np.zeros(7))
    q_hold = _references(400)[200]  # far from the last streamed reference
    observer.start(q_hold, 2.0)
    for _ in range(3):
        assert observer.measured(q_hold) == 2.0  # the arm shows the new start
        observer.sent(q_hold, 2.0)
    assert observer.latency_ticks == 4  # what was learnt about the round trip is kept


def test_the_next_segment_keeps_the_references_the_arm_still_follows() -> None:
    observer, shown = _observe(6, np.zeros(7))
    last_q, last_t = observer._sent[-1]
    observer.start(last_q, last_t)
    assert observer.measured(_references(400)[399 - 1 - 6]) == pytest.approx(shown[-1] + PERIOD)


def test_another_motion_starting_on_the_last_reference_forgets_the_old_plan_times() -> None:
    """The way back after a failed grasp starts where the arm rests, bit for bit the last
    reference: kept, its first measurement was matched with the forward motion's plan times
    (636 mm of "tracking error", every run of the soak of 6839f76)."""
    observer, _ = _observe(2, np.zeros(7))
    last_q, _ = observer._sent[-1]
    observer.start(last_q, 0.0, same_motion=False)
    assert observer.measured(last_q) == 0.0
