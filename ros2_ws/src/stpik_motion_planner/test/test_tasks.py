"""Finite-difference checks of every STPIK task Jacobian (pink's test_jacobians shape)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.stpik import Stpik
from stpik_motion_planner.tasks import JointLimitTask

Q0 = np.array([5.5, 1.6, -2.0, 1.2, 2.7, 4.4, 5.0])
H = 1e-6  # finite-difference step [rad]


def numeric(f, q: np.ndarray) -> np.ndarray:
    """Central differences of f: (7,) → (m,), shape (m, 7)."""
    cols = []
    for i in range(7):
        dq = np.zeros(7)
        dq[i] = H
        cols.append((f(q + dq) - f(q - dq)) / (2 * H))
    return np.array(cols).T


def test_ee_pose_position_rows_match_finite_differences(robot):
    stpik = Stpik(robot, PlannerConfig())
    k = stpik.kinematics(Q0, SceneWorld([]))
    J = pin.getFrameJacobian(k.model, k.data, k.ee_frame, pin.LOCAL_WORLD_ALIGNED)
    stpik.ee.target = k.world_ee
    rows = stpik.ee.compute(k)
    assert np.allclose(rows.jacobian, J)

    def position(q):
        return stpik.kinematics(q, SceneWorld([])).world_ee.translation.copy()

    assert np.allclose(rows.jacobian[:3], numeric(position, Q0), atol=1e-5)


def test_obstacle_row_matches_finite_difference_of_distance(robot):
    box = ObjectSpec('B', 'obstacle', 'box', (0.5, 0.0, 0.1), size=(0.1, 0.1, 0.1))
    world = SceneWorld([box])
    config = PlannerConfig(obstacle_activation_m=0.2)
    stpik = Stpik(robot, config)
    q = np.array([5.5, 1.45, -2.0, 1.1, 2.7, 4.5, 5.0])
    k = stpik.kinematics(q, world)
    assert k.scene_pairs, 'the arm should be within 20 cm of the box'
    _sigma, J, lower, upper, labels = stpik.obstacles.evaluate(k)
    pair = labels[0]

    def distance(qq):
        kk = stpik.kinematics(qq, world)
        return np.array([p.distance for p in kk.scene_pairs if f'{p.name_a}/{p.name_b}' == pair])

    assert np.allclose(J[0], numeric(distance, q)[0], atol=2e-3)
    assert lower[0] == pytest.approx(0.2) and upper[0] == np.inf


def test_self_collision_row_matches_finite_difference(robot):
    config = PlannerConfig(self_activation_m=0.2)
    stpik = Stpik(robot, config)
    q = np.array([4.71, 2.84, 0.0, 0.75, 4.62, 4.48, 4.88])
    k = stpik.kinematics(q, SceneWorld([]))
    sigma, J, _, _, labels = stpik.self_hit.evaluate(k)
    assert len(sigma) > 0
    i = int(np.argmin(sigma))

    def distance(qq):
        kk = stpik.kinematics(qq, SceneWorld([]))
        return np.array(
            [p.distance for p in kk.self_pairs if f'{p.name_a}/{p.name_b}' == labels[i]]
        )

    assert np.allclose(J[i], numeric(distance, q)[0], atol=2e-3)


def test_joint_limit_task_activates_only_outside_the_margins(robot):
    task = JointLimitTask(robot.limits.lower, robot.limits.upper, margin=0.1, gain=1.0)

    class K:
        q = np.array([0.0, robot.limits.lower[1] + 0.05, 0, 3.0, 0, robot.limits.upper[5], 0])

    rows = task.compute(K)
    assert rows.labels == ('joint_2', 'joint_6')
    assert rows.error == pytest.approx([0.05, -0.1])
    assert np.array_equal(rows.jacobian, np.eye(7)[[1, 5]])
