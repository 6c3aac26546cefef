"""Issue #28: the STPIK step without its per-step overhead gives the same bits (no ROS import).

Each test compares a changed function with the straightforward computation it replaced (copied
here as it was), with ``np.array_equal`` / ``==`` (bit for bit, not a tolerance), at random
configurations near obstacles, with and without a carried object, and checks that the cases
that make the comparison meaningful (pairs found and bounding the step) really occurred.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.stpik import LOOKAHEAD_M, Stpik, solve_hierarchy


def _reference_body_reach(stpik: Stpik, k) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`Stpik.body_reach` before #28 (np.r_ per call, np.linalg.norm)."""
    frames = stpik._frames[1:8]
    origins = frames[:, :3, 3]
    axes = frames[:, :3, 2]
    joints, radii = stpik._body_joint, stpik._body_radius
    centres = stpik.bodies.centres[: len(joints)]
    if stpik.bodies.attached is not None:
        centres = stpik.bodies.centres
        joints = np.r_[joints, 7]
        radii = np.r_[radii, stpik.bodies.attached_radius]
    offset = centres[None] - origins[:, None]
    along = np.einsum('jgk,jk->jg', offset, axes)
    to_axis = np.linalg.norm(offset - along[..., None] * axes[:, None], axis=2)
    distance = to_axis + radii[None]
    moved = joints[None] >= np.arange(1, 8)[:, None]
    return np.where(moved, distance, 0.0), joints


def _reference_step_scale(stpik: Stpik, k, dq: np.ndarray) -> float:
    """:meth:`Stpik.step_scale` before #28 (closure ``limit``, float() of numpy scalars)."""
    c = stpik.config
    reach, joints = _reference_body_reach(stpik, k)
    step = np.abs(dq)
    body_motion = step @ reach
    scale = 1.0

    def limit(motion: float, allowed: float) -> None:
        nonlocal scale
        if motion > 1e-12:
            scale = min(scale, max(allowed, 1e-4) / motion)

    limit(
        float(np.max(body_motion)),
        LOOKAHEAD_M
        + min(
            c.obstacle_activation_m - c.obstacle_min_distance_m,
            c.self_activation_m - c.self_min_distance_m,
        ),
    )
    index = stpik._body_index
    for p in k.scene_pairs:
        if p.distance >= c.obstacle_activation_m:
            limit(float(body_motion[index[p.name_a]]), p.distance - c.obstacle_min_distance_m)
    for p in k.self_pairs:
        if p.distance >= c.self_activation_m:
            a, b = index[p.name_a], index[p.name_b]
            if joints[a] > joints[b]:
                a, b = b, a
            relative = float(step[joints[a] :] @ reach[joints[a] :, b])
            limit(relative, p.distance - c.self_min_distance_m)
    return scale


@pytest.fixture
def setup(robot, make_scenario, make_cylinder):
    scenario = make_scenario(make_cylinder('a', 0.45, 0.0), make_cylinder('b', 0.35, 0.2))
    stpik = Stpik(robot, PlannerConfig())
    stpik.posture.reference = np.asarray(scenario.home, dtype=float)
    return stpik, SceneWorld(scenario.objects), scenario


def _configurations(scenario, count: int, seed: int):
    rng = np.random.default_rng(seed)
    home = np.asarray(scenario.home, dtype=float)
    return [home + rng.normal(0.0, 0.8, 7) for _ in range(count)]


@pytest.mark.parametrize('carried', [False, True])
def test_step_bound_is_bit_identical_to_the_closure_version(setup, carried):
    stpik, scene, scenario = setup
    if carried:
        held = scenario.objects[0]
        stpik.bodies.attach(held, pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.08])))
    rng = np.random.default_rng(5)
    bounded = {'scene': 0, 'self': 0, 'below_one': 0}
    c = stpik.config
    for q in _configurations(scenario, 250, 7 + carried):
        k = stpik.kinematics(q, scene)
        reach, joints = stpik.body_reach(k)
        expected_reach, expected_joints = _reference_body_reach(stpik, k)
        assert reach.shape == (7, 15 if carried else 14)
        assert np.array_equal(reach, expected_reach)
        assert np.array_equal(joints, expected_joints) and joints.dtype == expected_joints.dtype
        dq = rng.normal(0.0, 0.05, 7)
        scale = stpik.step_scale(k, dq)
        assert scale == _reference_step_scale(stpik, k, dq)
        bounded['scene'] += any(p.distance >= c.obstacle_activation_m for p in k.scene_pairs)
        bounded['self'] += any(p.distance >= c.self_activation_m for p in k.self_pairs)
        bounded['below_one'] += scale < 1.0
    assert all(v > 10 for v in bounded.values()), bounded  # the pair bounds were exercised


def test_base_solve_is_solve_hierarchy_of_ee_and_posture(setup, robot):
    stpik, scene, scenario = setup
    c = stpik.config
    rng = np.random.default_rng(9)
    for q in _configurations(scenario, 100, 3):
        stpik.ee.target = pin.SE3(robot.ee_pose(q + rng.normal(0.0, 0.2, 7)))
        k = stpik.kinematics(q, scene)
        ee, posture = stpik.ee.compute(k), stpik.posture.compute(k)
        dq = stpik._solve_base(ee, posture)
        expected = solve_hierarchy([ee, posture], 7, c.damping, c.singular_threshold)
        assert np.array_equal(dq, expected)
        assert np.any(dq != 0.0)


def test_joint_limit_test_is_the_np_any_test(setup):
    stpik, scene, scenario = setup
    task = stpik.joint_limits
    answers = []
    for q in _configurations(scenario, 200, 4):
        k = stpik.kinematics(q, scene)
        expected = bool(np.any(k.q < task._low) or np.any(k.q > task._high))
        answers.append(task.may_activate(k))
        assert answers[-1] == expected
    assert any(answers) and not all(answers)  # both answers occurred
