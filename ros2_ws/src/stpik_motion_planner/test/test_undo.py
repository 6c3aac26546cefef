"""Undoing a stopped relocation (#32): the executed path backwards, re-timed from 0."""

from __future__ import annotations

import numpy as np
import pytest
from stpik_motion_planner.undo import reversed_samples

TIMES = np.array([0.0, 1.0, 2.0, 4.0])
JOINTS = np.outer([0.0, 0.1, 0.3, 0.7], np.ones(7))


def test_from_between_two_samples_back_to_the_start() -> None:
    times, joints = reversed_samples(TIMES, JOINTS, 1.5, 0.0)
    np.testing.assert_allclose(times, [0.0, 0.5, 1.5])
    np.testing.assert_allclose(joints[:, 0], [0.2, 0.1, 0.0])  # q(1.5) interpolated first


def test_back_to_an_inner_sample_keeps_the_planned_speeds() -> None:
    times, joints = reversed_samples(TIMES, JOINTS, 4.0, 1.0)
    np.testing.assert_allclose(times, [0.0, 2.0, 3.0])
    np.testing.assert_allclose(joints[:, 3], [0.7, 0.3, 0.1])
    speeds = np.abs(np.diff(joints[:, 0]) / np.diff(times))
    np.testing.assert_allclose(speeds, [0.2, 0.2])  # the plan's own joint speeds, reversed


def test_a_stop_at_the_very_start_is_a_two_sample_standstill() -> None:
    times, joints = reversed_samples(TIMES, JOINTS, 0.0, 0.0)
    assert len(times) == 2 and times[-1] > 0.0
    np.testing.assert_allclose(joints[0], joints[-1])


def test_going_forward_is_refused() -> None:
    with pytest.raises(ValueError, match='after'):
        reversed_samples(TIMES, JOINTS, 1.0, 2.0)
