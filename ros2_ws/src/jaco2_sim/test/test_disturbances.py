"""Tests of jaco2_sim.disturbances and the integrator's disturbance hooks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from jaco2_description.model import ARM_JOINTS, HOME, arm_limits
from jaco2_sim.disturbances import (
    CommandDelay,
    Disturbances,
    DisturbedDrive,
    MeasurementNoise,
    from_parameters,
)
from jaco2_sim.exceptions import DisturbanceError, TrajectoryError
from jaco2_sim.integrator import JointIntegrator

LIMITS = arm_limits()


def test_defaults_are_off():
    d = Disturbances()
    assert not d.active
    assert d.joint_offset_rad == (0.0,) * 7 and d.latency_s == 0.0
    assert d.velocity_limit_scale == 1.0 and d.noise_rad == 0.0
    assert Disturbances(latency_s=0.05).active


@pytest.mark.parametrize(
    'parameters, match',
    [
        ({'command_latency_s': -0.01}, 'command_latency_s'),
        ({'command_latency_s': math.nan}, 'command_latency_s'),
        ({'measurement_noise_rad': -1e-3}, 'measurement_noise_rad'),
        ({'velocity_limit_scale': 0.0}, 'velocity_limit_scale'),
        ({'velocity_limit_scale': 1.5}, 'velocity_limit_scale'),
        ({'joint_offset_rad': [0.0, math.nan, 0, 0, 0, 0, 0]}, 'joint_offset_rad'),
        ({'joint_offset_rad': [0.1]}, 'joint_offset_rad'),
        ({'joint_offset_rad': [1.0] * 7}, 'joint_offset_rad'),
        ({'noise_seed': -1}, 'noise_seed'),
        ({'command_latency_s': 'soon'}, 'command_latency_s'),
    ],
)
def test_bad_values_name_the_parameter(parameters, match):
    with pytest.raises(DisturbanceError, match=match):
        from_parameters(parameters)


def test_delay_releases_commands_in_order_after_the_latency():
    delay = CommandDelay(0.05)
    delay.push(0.0, 'a')
    delay.push(0.01, 'b')
    assert delay.due(0.04) == []
    assert delay.due(0.05) == ['a']
    assert delay.due(0.1) == ['b'] and len(delay) == 0


def test_noise_is_seeded_and_zero_by_default():
    q = np.array(HOME)
    assert MeasurementNoise().measure(q) is not None
    np.testing.assert_array_equal(MeasurementNoise().measure(q), q)
    a, b = MeasurementNoise(0.001, 3), MeasurementNoise(0.001, 3)
    np.testing.assert_array_equal(a.measure(q), b.measure(q))
    samples = np.array([a.measure(q) - q for _ in range(2000)])
    assert 0.0009 < samples.std() < 0.0011 and abs(samples.mean()) < 1e-4


def test_offset_shifts_where_the_servo_settles():
    sim = JointIntegrator(LIMITS, 100.0, HOME)
    offset = np.array([0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0])
    sim.disturb(offset, 1.0)
    sim.set_point(ARM_JOINTS, HOME)
    for _ in range(100):
        sim.step()
    np.testing.assert_allclose(sim.q, HOME + offset, atol=1e-9)


def test_velocity_scale_slows_the_arm():
    sim = JointIntegrator(LIMITS, 100.0, HOME)
    sim.disturb(np.zeros(7), 0.5)
    goal = HOME + np.array([0.3, 0, 0, 0, 0, 0, 0])
    sim.set_point(ARM_JOINTS, goal)
    steps = 0
    while not sim.step():
        steps += 1
        assert np.all(np.abs(sim.velocity) <= 0.5 * LIMITS.velocity + 1e-9)
    assert steps + 1 == math.ceil(0.3 / (0.5 * LIMITS.velocity[0] * 0.01))


def test_drive_delays_streamed_points_and_reports_bad_ones():
    sim = JointIntegrator(LIMITS, 100.0, HOME)
    drive = DisturbedDrive(sim, Disturbances(latency_s=0.05))
    goal = HOME + 0.01
    drive.command('point', ARM_JOINTS, goal)
    for _ in range(4):
        assert drive.apply_due() == []
        sim.step()
        np.testing.assert_array_equal(sim.q, HOME)  # not applied yet
    for _ in range(3):
        drive.apply_due()
        sim.step()
    np.testing.assert_allclose(sim.q, goal)
    drive.command('point', ARM_JOINTS[:6], goal[:6])
    for _ in range(6):
        errors = drive.apply_due()
        sim.step()
        if errors:
            break
    assert errors and 'joint names' in errors[0]
    drive.configure(Disturbances())  # no latency: applied (or refused) at once
    with pytest.raises(TrajectoryError):
        drive.command('point', ARM_JOINTS, [math.nan] * 7)
