"""Tests of jaco2_sim.conversions: trajectory size from CDR bytes, vectorised trajectory arrays."""

from __future__ import annotations

import time

import numpy as np
import pytest
from builtin_interfaces.msg import Duration
from jaco2_description.model import ARM_JOINTS, HOME
from jaco2_sim.conversions import MAX_SCANNED_NAMES, trajectory_arrays, trajectory_size
from jaco2_sim.exceptions import TrajectoryError
from rclpy.serialization import deserialize_message, serialize_message
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint


def _trajectory(n: int, names: list[str] | None = None, frame_id: str = '') -> JointTrajectory:
    msg = JointTrajectory(joint_names=list(ARM_JOINTS) if names is None else names)
    msg.header.frame_id = frame_id
    for k in range(n):
        t = 0.01 * (k + 1)
        msg.points.append(
            JointTrajectoryPoint(
                positions=(HOME + 1e-4 * k).tolist(),
                time_from_start=Duration(sec=int(t), nanosec=round((t % 1) * 1e9) % 10**9),
            )
        )
    return msg


@pytest.mark.parametrize('frame_id', ['', 'a', 'ab', 'abc', 'base_link'])  # every alignment
@pytest.mark.parametrize('names', [[], ['x'], ['ab', 'abc', ''], list(ARM_JOINTS)])
@pytest.mark.parametrize('n', [0, 1, 3])
def test_trajectory_size_reads_the_lengths(frame_id: str, names: list[str], n: int) -> None:
    raw = serialize_message(_trajectory(n, names, frame_id))
    assert trajectory_size(raw) == (len(names), n)


def test_trajectory_size_is_cheap_and_robust() -> None:
    # Bounds are on this process's CPU time, not wall time: other processes on a loaded machine
    # (CI, parallel agents) must not make a cost bound fail.
    raw = serialize_message(_trajectory(100_000))
    start = time.process_time()
    assert trajectory_size(raw) == (7, 100_000)
    assert time.process_time() - start < 0.01
    many = [f'j{k}' for k in range(MAX_SCANNED_NAMES + 1)]
    assert trajectory_size(serialize_message(_trajectory(2, many))) == (len(many), None)
    assert trajectory_size(raw[:20]) is None  # truncated
    assert trajectory_size(b'\x00\x07\x00\x00' + raw[4:]) is None  # not plain CDR
    assert trajectory_size(b'') is None


def test_trajectory_arrays_vectorised() -> None:
    msg = deserialize_message(serialize_message(_trajectory(10_000)), JointTrajectory)
    start = time.process_time()
    names, times, positions, velocities = trajectory_arrays(msg)
    seconds = time.process_time() - start
    assert seconds < 0.05, f'{seconds:.3f} s for 10 000 points'
    assert names == list(ARM_JOINTS) and velocities is None
    np.testing.assert_allclose(times, 0.01 * np.arange(1, 10_001), atol=1e-9)
    np.testing.assert_allclose(np.asarray(positions)[-1], HOME + 1e-4 * 9_999)


def test_trajectory_arrays_velocities_on_some_points() -> None:
    msg = _trajectory(3)
    msg.points[1].velocities = [0.0] * 7
    with pytest.raises(TrajectoryError, match='every point or on none'):
        trajectory_arrays(msg)
