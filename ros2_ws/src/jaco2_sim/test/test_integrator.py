"""Tests of jaco2_sim.integrator: tracking within velocity and position limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jaco2_description.model import ARM_JOINTS, HOME, arm_limits
from jaco2_sim.exceptions import TrajectoryError
from jaco2_sim.integrator import GOAL_TOLERANCE, JointIntegrator

LIMITS = arm_limits()


def _run(sim: JointIntegrator, max_steps: int = 10000) -> list[np.ndarray]:
    states = [sim.q.copy()]
    for _ in range(max_steps):
        finished = sim.step()
        states.append(sim.q.copy())
        if finished:
            return states
    raise AssertionError('reference never finished')


def test_single_point_moves_at_velocity_limit() -> None:
    sim = JointIntegrator(LIMITS, rate_hz=100.0, q0=HOME)
    goal = HOME + np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert sim.set_point(ARM_JOINTS, goal) is False
    states = _run(sim)
    # Joint 1 at its limit of 0.6283 rad/s: 0.3 rad takes ceil(0.3 / 0.006283) = 48 steps.
    assert len(states) - 1 == math.ceil(0.3 / (0.6283 * 0.01))
    np.testing.assert_allclose(states[-1], goal, atol=GOAL_TOLERANCE)
    speeds = np.abs(np.diff(states, axis=0)) / sim.period
    assert np.all(speeds <= LIMITS.velocity + 1e-9)
    assert not sim.active


def test_uniform_scaling_keeps_joint_space_direction() -> None:
    sim = JointIntegrator(LIMITS, q0=HOME)
    delta = np.array([0.4, -0.2, 0.1, 0.0, 0.3, 0.0, -0.5])
    sim.set_point(ARM_JOINTS, HOME + delta)
    sim.step()
    step = sim.q - HOME
    np.testing.assert_allclose(step / np.linalg.norm(step), delta / np.linalg.norm(delta))
    # The binding joint is joint 1 (0.4 / 0.6283 > 0.5 / 0.8378): it moves at its limit.
    assert abs(sim.velocity[0]) == pytest.approx(0.6283)
    assert abs(sim.velocity[6]) == pytest.approx(0.6283 * 0.5 / 0.4)


def test_slow_reference_is_tracked_exactly_and_in_time() -> None:
    sim = JointIntegrator(LIMITS, rate_hz=50.0, q0=HOME)
    times = [0.0, 1.0, 2.0]
    points = [HOME, HOME + 0.2, HOME + 0.3]
    sim.set_reference(ARM_JOINTS, times, points)
    for _ in range(25):  # t = 0.5 s: halfway to the second point
        sim.step()
    np.testing.assert_allclose(sim.q, HOME + 0.1, atol=1e-9)
    states = _run(sim)
    assert sim.time == pytest.approx(2.0)
    np.testing.assert_allclose(states[-1], HOME + 0.3, atol=1e-12)


def test_hermite_reference_with_velocities_and_permuted_names() -> None:
    sim = JointIntegrator(LIMITS, q0=HOME)
    names = list(reversed(ARM_JOINTS))
    goal = HOME + 0.2
    sim.set_reference(names, [0.0, 1.0], [HOME[::-1], goal[::-1]], [np.zeros(7)] * 2)
    for _ in range(50):
        sim.step()
    # Cubic with zero end velocities: halfway in time is halfway in position.
    np.testing.assert_allclose(sim.q, HOME + 0.1, atol=1e-9)
    _run(sim)
    np.testing.assert_allclose(sim.q, goal, atol=GOAL_TOLERANCE)


def test_first_point_after_zero_starts_from_current_state() -> None:
    sim = JointIntegrator(LIMITS, rate_hz=100.0, q0=HOME)
    sim.set_reference(ARM_JOINTS, [1.0], [HOME + 0.1])
    for _ in range(50):
        sim.step()
    np.testing.assert_allclose(sim.q, HOME + 0.05, atol=1e-9)


def test_beyond_limit_reference_is_clamped() -> None:
    sim = JointIntegrator(LIMITS, q0=HOME)
    goal = HOME.copy()
    goal[1] = 6.0  # above the 5.462881 rad limit of joint 2
    assert sim.set_point(ARM_JOINTS, goal) is True
    states = _run(sim)
    assert states[-1][1] == pytest.approx(LIMITS.upper[1], abs=GOAL_TOLERANCE)
    assert max(s[1] for s in states) <= LIMITS.upper[1]


@pytest.mark.parametrize(
    ('names', 'times', 'points', 'match'),
    [
        (ARM_JOINTS[:6], [0.0], [HOME[:6]], 'joint names'),
        ((*ARM_JOINTS[:6], 'j2s7s300_joint_finger_1'), [0.0], [HOME], 'joint names'),
        ((*ARM_JOINTS[:6], ARM_JOINTS[0]), [0.0], [HOME], 'joint names'),
        (ARM_JOINTS, [0.0], [HOME[:6]], 'positions: shape'),
        (ARM_JOINTS, [0.0, 1.0], [HOME], 'positions: shape'),
        (ARM_JOINTS, [0.0], [[math.nan] * 7], 'non-finite'),
        (ARM_JOINTS, [math.inf], [HOME], 'non-finite'),
        (ARM_JOINTS, [1.0, 1.0], [HOME, HOME], 'strictly increasing'),
        (ARM_JOINTS, [-1.0], [HOME], 'strictly increasing'),
        (ARM_JOINTS, [], [], 'no points'),
        (ARM_JOINTS, [0.0], [['a'] * 7], 'not numeric'),
    ],
)
def test_bad_references_rejected_and_old_one_kept(names, times, points, match) -> None:
    sim = JointIntegrator(LIMITS, q0=HOME)
    sim.set_point(ARM_JOINTS, HOME + 0.1)
    with pytest.raises(TrajectoryError, match=match):
        sim.set_reference(names, times, points)
    assert sim.active
    _run(sim)
    np.testing.assert_allclose(sim.q, HOME + 0.1, atol=GOAL_TOLERANCE)


def test_bad_construction_and_reset() -> None:
    with pytest.raises(TrajectoryError, match='rate_hz'):
        JointIntegrator(LIMITS, rate_hz=0.0)
    sim = JointIntegrator(LIMITS)
    np.testing.assert_allclose(sim.q, 0.5 * (LIMITS.lower + LIMITS.upper))
    with pytest.raises(TrajectoryError, match='outside the joint limits'):
        sim.reset(np.zeros(7))
    with pytest.raises(ValueError):
        sim.q[0] = 1.0  # read-only view


@settings(max_examples=30, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(
    deltas=st.lists(
        st.lists(st.floats(-1.0, 1.0), min_size=7, max_size=7), min_size=1, max_size=4
    ),
    durations=st.lists(st.floats(0.05, 1.0), min_size=4, max_size=4),
)
def test_any_reference_respects_limits_and_finishes(deltas, durations) -> None:
    sim = JointIntegrator(LIMITS, rate_hz=100.0, q0=HOME)
    points = [HOME + np.array(d) for d in deltas]
    times = np.cumsum(durations[: len(points)])
    sim.set_reference(ARM_JOINTS, times, points)
    states = np.array(_run(sim, max_steps=2000))
    speeds = np.abs(np.diff(states, axis=0)) / sim.period
    assert np.all(speeds <= LIMITS.velocity * (1 + 1e-9))
    assert np.all(states >= LIMITS.lower) and np.all(states <= LIMITS.upper)
    np.testing.assert_allclose(
        states[-1], np.clip(points[-1], LIMITS.lower, LIMITS.upper), atol=GOAL_TOLERANCE
    )
