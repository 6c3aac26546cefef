"""Closed-loop executor core (stpik_motion_planner.closed_loop) against a toy servo plant.

The plant: each tick the joints go to the streamed reference + a constant offset, within the
velocity limits (as jaco2_sim's integrator does; this package may not import jaco2_sim).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from jaco2_description.model import ARM_JOINTS
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.closed_loop import (
    SETTLE_M,
    ClosedLoopController,
    ExecutionStopped,
    PlannedMotion,
    measured_q,
    segments,
)
from stpik_motion_planner.collision import Proximity, SceneWorld
from stpik_motion_planner.exceptions import InvalidConfig
from stpik_motion_planner.execution_config import ExecutionConfig, check_mode
from stpik_motion_planner.planner import MotionPlanner

OFFSET = np.array([0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0])  # servo offset on joint 2 [rad]


@pytest.fixture(scope='module')
def plan(free_scene):
    planner = MotionPlanner(free_scene)
    result = planner.check('T', [])
    assert result.feasible, result.message
    return planner, result


def _servo(q, target, robot, dt):
    """q → target within the velocity limits (direction kept)."""
    v = (target - q) / dt
    ratio = float(np.max(np.abs(v) / robot.limits.velocity))
    return q + (v / max(ratio, 1.0)) * dt


def _closed_loop(
    planner, result, offset, on_tick=None, at_rest=False, lag=0, noise_rad=0.0, measure_lag=0
):
    """EE errors [m] at the end of the grasp and release segments (``at_rest``: once the
    servo has reached the last streamed reference, as the hand ends up on the arm).

    ``lag``: ticks a streamed reference takes to reach the servo; ``measure_lag``: ticks a
    measurement takes to reach the controller."""
    robot = planner.robot
    scene = SceneWorld(o for o in planner.scenario.objects if o.id != 'T')
    controller = ClosedLoopController(robot, scene, planner.config)
    motion = PlannedMotion(result.times, result.joint_trajectory, robot)
    q = np.array(result.joint_trajectory[0])
    q_ref = q.copy()
    ticks, end_errors = 0, []
    commands = [q.copy()] * lag  # streamed references in flight (latency of ``lag`` ticks)
    measurements = [q.copy()] * measure_lag  # joint states in flight
    rng = np.random.default_rng(7)  # measurement noise of ``noise_rad`` per joint
    for start, end, _ in segments(result)[:2]:
        controller.begin(motion, start, end, q_ref)
        while controller.phase != 'done':
            measurements.append(q + rng.normal(0.0, noise_rad, 7) if noise_rad else q.copy())
            tick = controller.step(measurements.pop(0))
            ticks += 1
            if on_tick is not None:
                on_tick(ticks, controller)
            commands.append(tick.q_ref.copy())
            q = _servo(q, commands.pop(0) + offset, robot, controller.config.period)
            assert ticks < 20_000
        q_ref = controller.q_ref
        for _ in range(2000 if at_rest else 0):  # the servo goes on to the last reference
            q = _servo(q, q_ref + offset, robot, controller.config.period)
        target = motion.ee_of(result.joint_trajectory[end]).translation
        end_errors.append(float(np.linalg.norm(motion.ee_of(q).translation - target)))
    return end_errors


def test_closed_loop_removes_a_joint_offset_that_open_loop_keeps(plan):
    planner, result = plan
    motion = PlannedMotion(result.times, result.joint_trajectory, planner.robot)
    # Open loop: the servo settles at the planned joints + offset.
    open_errors = []
    for _, end, _ in segments(result)[:2]:
        q_goal = result.joint_trajectory[end]
        reached = motion.ee_of(q_goal + OFFSET).translation
        open_errors.append(float(np.linalg.norm(reached - motion.ee_of(q_goal).translation)))
    closed_errors = _closed_loop(planner, result, OFFSET)
    assert min(open_errors) > 0.015  # 0.05 rad on the shoulder: centimetres at the hand
    assert max(closed_errors) < 0.003  # grasp and release reached within 3 mm


def test_the_hand_at_rest_after_a_segment_is_within_the_settle_tolerance(plan):
    """#26: a segment was "done" while the arm still moved on to the leading reference: the hand
    came to rest 5.07 mm from the plan (node test under load); with a 50 ms command latency
    here, 5.1 / 8.7 mm at rest (was done at the first tick of a smoothed error within 2 mm)."""
    planner, result = plan
    tolerance = ExecutionConfig().settle_tolerance_m
    assert tolerance <= 0.001
    for offset, lag in ((OFFSET, 0), (np.zeros(7), 0), (OFFSET, 5), (np.zeros(7), 5)):
        rest_errors = _closed_loop(planner, result, offset, at_rest=True, lag=lag)
        assert max(rest_errors) < 1.5 * tolerance, rest_errors


def test_closed_loop_without_disturbance_ends_on_the_plan(plan):
    planner, result = plan
    assert max(_closed_loop(planner, result, np.zeros(7))) < 0.003


def test_obstacle_moved_onto_the_path_stops_with_the_reason(plan):
    planner, result = plan
    motion = PlannedMotion(result.times, result.joint_trajectory, planner.robot)
    # A box put where the hand will be halfway through the approach to the grasp.
    g = result.grasp_index
    ahead = motion.ee_of(result.joint_trajectory[g - 2]).translation
    box = ObjectSpec('intruder', 'obstacle', 'box', tuple(ahead), size=(0.05, 0.05, 0.05))
    others = [o for o in planner.scenario.objects if o.id != 'T']

    def drop_box(ticks, controller):
        if ticks == 50:
            controller.set_scene(SceneWorld([*others, box]))

    with pytest.raises(ExecutionStopped) as stop:
        _closed_loop(planner, result, np.zeros(7), drop_box)
    assert stop.value.cause in ('obstacles', 'tracking')
    assert 'intruder' in str(stop.value)


def test_measured_state_checks():
    q = measured_q([*reversed(ARM_JOINTS), 'j2s7s300_joint_finger_1'], [*range(7), 0.2][::1])
    assert q[0] == 6.0 and q.shape == (7,)
    with pytest.raises(ExecutionStopped, match='misses arm joints'):
        measured_q(ARM_JOINTS[:6], [0.0] * 6)
    with pytest.raises(ExecutionStopped, match='unknown joints'):
        measured_q([*ARM_JOINTS, 'elbow'], [0.0] * 8)
    with pytest.raises(ExecutionStopped, match='non-finite'):
        measured_q(ARM_JOINTS, [math.nan] + [0.0] * 6)
    with pytest.raises(ExecutionStopped, match='names but'):
        measured_q(ARM_JOINTS, [0.0] * 6)


def test_step_refuses_a_bad_measurement(plan):
    planner, result = plan
    controller = ClosedLoopController(planner.robot, SceneWorld([]), planner.config)
    with pytest.raises(ExecutionStopped):
        controller.step(np.zeros(7))  # before begin()
    motion = PlannedMotion(result.times, result.joint_trajectory, planner.robot)
    controller.begin(motion, 0, result.grasp_index, result.joint_trajectory[0])
    with pytest.raises(ExecutionStopped, match='7 finite'):
        controller.step(np.full(7, math.nan))


@pytest.mark.parametrize(
    'field, value',
    [('control_rate_hz', 5.0), ('control_rate_hz', 5000.0), ('control_rate_hz', math.nan),
     ('tracking_gain', -0.1), ('max_tracking_error_m', math.inf)],
)  # fmt: skip
def test_bad_execution_settings_are_refused(field, value):
    with pytest.raises(InvalidConfig, match=field):
        ExecutionConfig(**{field: value})


def test_execution_mode_values():
    assert check_mode('open_loop') == 'open_loop'
    with pytest.raises(InvalidConfig, match='execution_mode'):
        check_mode('closed')


def test_planned_motion_interpolates_and_holds(plan):
    planner, result = plan
    motion = PlannedMotion(result.times, result.joint_trajectory, planner.robot)
    t = 0.5 * (result.times[1] + result.times[2])
    expected = 0.5 * (result.joint_trajectory[1] + result.joint_trajectory[2])
    np.testing.assert_allclose(motion.joints_at(t), expected)
    np.testing.assert_allclose(motion.joints_at(1e9), result.joint_trajectory[-1])
    assert motion.ee_at(-1.0).isApprox(pin.SE3(planner.robot.ee_pose(result.joint_trajectory[0])))


def test_a_reference_into_an_object_is_held_before_it_is_streamed(plan):
    """#29 point 5: the streamed reference leads the measured arm by up to max_lead_rad, and
    only the measured arm was checked: a reference inside an object (here a box standing where
    the hand will be a few samples on, 20 mm clear of the arm as measured) was streamed and
    drove the arm into it before the next measurement showed it. Now the tick stops first."""
    planner, result = plan
    q_plan = result.joint_trajectory
    controller = ClosedLoopController(planner.robot, SceneWorld([]), planner.config)
    lead = controller.config.max_lead_rad
    bodies = controller.stpik.bodies
    found = None
    for i in range(len(q_plan) - 1):
        for j in range(i + 1, len(q_plan)):
            if found or np.max(np.abs(q_plan[j] - q_plan[i])) > lead:
                break
            wrist = planner.robot.ee_pose(q_plan[j]).translation
            box = SceneWorld(
                [ObjectSpec('placed', 'obstacle', 'box', tuple(wrist), size=(0.1, 0.1, 0.1))]
            )
            controller.stpik.place_bodies(q_plan[j])
            inside = not bodies.scene_clear(box, 0.0)
            controller.stpik.place_bodies(q_plan[i])
            if inside and bodies.scene_clear(box, 0.02):
                found = i, j, box
    assert found is not None, 'no sample pair of the plan to test with'
    i, j, box = found
    controller.set_scene(box)
    motion = PlannedMotion(result.times, q_plan, planner.robot)
    controller.begin(motion, i, len(q_plan) - 1, q_plan[j])
    with pytest.raises(ExecutionStopped) as stop:
        controller.step(q_plan[i])
    assert stop.value.cause == 'obstacles'
    assert 'joint reference' in str(stop.value) and 'placed' in str(stop.value)
    # The same tick without the box streams a reference.
    controller.set_scene(SceneWorld([]))
    controller.begin(motion, i, len(q_plan) - 1, q_plan[j])
    assert controller.step(q_plan[i]).q_ref.shape == (7,)


def test_the_carried_object_is_checked_at_its_true_size_but_its_bottom_against_statics(plan):
    """#29: the closed loop carried the object 20 mm short at BOTH ends against everything, so a
    box 10 mm above the carried top, or an object 10 mm under its bottom (one standing on the
    drop slot), was 30 mm away for the controller. Now only the bottom against a static body
    (the table it is set down on) is short; the rest is exact."""
    planner, result = plan
    q = np.array(result.joint_trajectory[result.grasp_index])
    controller = ClosedLoopController(planner.robot, SceneWorld([]), planner.config)
    held = planner.scenario.object('T')
    world_obj = pin.SE3(
        pin.rpy.rpyToMatrix(0.0, 0.0, held.yaw), np.asarray(held.position, dtype=float)
    )
    controller.attach(held, world_obj, q)
    top, bottom = held.position[2] + held.height / 2, held.position[2] - held.height / 2
    x, y = held.position[0], held.position[1]

    def carried_distance(z_face: float, above: bool, role: str = 'obstacle') -> float:
        half = 0.02  # a 40 mm cube whose face is at z_face
        centre = (x, y, z_face + half if above else z_face - half)
        cube = SceneWorld([ObjectSpec('cube', role, 'box', centre, size=(0.04,) * 3)])
        controller.stpik.place_bodies(q)
        pairs = controller.stpik.bodies.scene_proximities(cube, 0.1)
        return min(p.distance for p in pairs if p.name_a == 'attached')

    assert carried_distance(top + 0.010, above=True) == pytest.approx(0.010, abs=1e-4)
    assert carried_distance(bottom - 0.010, above=False) == pytest.approx(0.010, abs=1e-4)
    assert carried_distance(bottom - 0.010, above=False, role='static') == pytest.approx(
        0.010 + SETTLE_M, abs=1e-4
    )
    assert carried_distance(top + 0.010, above=True, role='static') == pytest.approx(
        0.010, abs=1e-4
    )


def test_a_noisy_measurement_still_settles_on_the_plan(plan):
    """#26 settle rule, every tick of 0.2 s within 1 mm: with 1 mrad of measurement noise the
    measured error at rest is 0.6-1.2 mm, so no segment ever ended (the execution benchmark's
    noise_1mrad row: 0 of 15 done, all on settle_timeout_s). Averaged over the window: done,
    and the true hand is on the plan."""
    planner, result = plan
    errors = _closed_loop(planner, result, np.zeros(7), noise_rad=0.001)
    assert max(errors) < 0.0025  # true EE error at the end of each segment [m]


def test_a_lost_set_stops_with_the_task_the_pair_and_the_margin(plan) -> None:
    """#27: one check for both distance sets; the self-hit set is checked first."""
    planner, result = plan
    controller = ClosedLoopController(planner.robot, SceneWorld([]), planner.config)
    q = result.joint_trajectory[0]
    kin = controller.stpik.kinematics(q, SceneWorld([]))
    m, slack = controller.margins, controller.config.margin_tolerance_m
    inside = np.zeros(3)
    self_hit = Proximity('link_3', 'link_6', m.self_min_distance_m - slack - 1e-4, inside, inside)
    obstacle = Proximity('link_5', 'cup', m.obstacle_min_distance_m - slack, inside, inside)
    kept = Proximity('link_5', 'cup', m.obstacle_min_distance_m - slack + 1e-4, inside, inside)
    kin.self_pairs, kin.scene_pairs = [], [kept]
    controller._check_sets(kin)  # within the measurement tolerance: no stop
    kin.scene_pairs = [kept, obstacle]
    with pytest.raises(ExecutionStopped) as stop:
        controller._check_sets(kin)
    assert stop.value.cause == 'obstacles'
    margin_mm = m.obstacle_min_distance_m * 1e3
    assert str(stop.value).endswith(
        f"link_5 {obstacle.distance * 1e3:.1f} mm from 'cup' (margin {margin_mm:.1f} mm)"
    )
    kin.self_pairs = [self_hit]
    with pytest.raises(ExecutionStopped) as stop:
        controller._check_sets(kin)
    assert stop.value.cause == 'self_hit'
    assert 'link_3 and link_6' in str(stop.value) and 'apart' in str(stop.value)


def test_each_segment_reports_its_worst_tracking_error(plan) -> None:
    """#26: the node logs each segment's worst EE error (the figure behind the node tests'
    max_tracking_error_m); it grows within a segment and starts again with the next."""
    planner, result = plan
    seen: list[tuple[int, float, float]] = []

    def watch(_ticks, controller) -> None:
        seen.append((controller.ticks, controller.worst_error_m, controller.worst_error_rad))

    _closed_loop(planner, result, OFFSET, watch, lag=5)
    starts = [i for i, (ticks, _, _) in enumerate(seen) if ticks == 1]
    assert starts == [0, starts[1]] and starts[1] > 1  # two segments, each counted from 1
    segment_worst = []
    for lo, hi in ((0, starts[1]), (starts[1], len(seen))):
        worst = [m for _, m, _ in seen[lo:hi]]
        assert worst == sorted(worst)  # a running maximum
        segment_worst.append(worst[-1])
    # the 0.05 rad shoulder offset puts the hand centimetres off before the loop removes it; the
    # next segment starts with the offset known (#26: the observer's estimate), so it stays on
    assert 0.005 < segment_worst[0] < ExecutionConfig().max_tracking_error_m
    assert segment_worst[1] < 0.001
    assert all(rad >= 0.0 for _, _, rad in seen)


@pytest.mark.parametrize(
    ('lag', 'measure_lag', 'noise_rad'),
    [(5, 5, 0.0), (10, 10, 0.0), (20, 10, 0.0), (10, 10, 0.001)],
)
def test_a_slow_round_trip_is_not_taken_for_a_tracking_error(
    plan, lag, measure_lag, noise_rad
) -> None:
    """#26: corrected against the delayed measurement, the reference overshot and the loop
    oscillated once the round trip grew on a loaded machine. Before ArmObserver, on this plan:
    5 + 5 ticks, the segment never settled (27 mm); 10 + 10 and 20 + 10, stopped at 52.8 and
    52.0 mm "tracking error" (s1's O4 plan, 10 + 10: 87.6 mm, the hand 43 mm off its path, a
    finger 0.3 mm from the table). With its Smith predictor the hand stays on its path and the
    error checked is the deviation, not the round trip."""
    planner, result = plan
    worst: list[float] = []
    paths: list[float] = []
    motion = PlannedMotion(result.times, result.joint_trajectory, planner.robot)
    path = np.array(
        [
            motion.ee_of(motion.joints_at(t)).translation
            for t in np.linspace(0, result.times[-1], 2000)
        ]
    )

    def watch(_ticks, controller) -> None:
        worst.append(controller.worst_error_m)
        # the servo's arm is not visible here; the last streamed reference + the estimated
        # offset is where the controller sends it (the arm reaches it ``lag`` ticks later)
        sent = motion.ee_of(controller.observer.predicted(controller.q_ref)).translation
        paths.append(float(np.min(np.linalg.norm(path - sent, axis=1))))

    ends = _closed_loop(
        planner, result, np.zeros(7), watch, lag=lag, measure_lag=measure_lag, noise_rad=noise_rad
    )
    assert max(ends) < 0.003  # grasp and release reached
    assert max(worst) < 0.005  # was 25-88 mm: the round trip, counted as an error
    assert max(paths) < 0.003  # the hand is sent along the planned path
