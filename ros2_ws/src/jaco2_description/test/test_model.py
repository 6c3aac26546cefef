"""Tests of jaco2_description.model: URDF, Pinocchio FK/Jacobian, FCL geometry, full model."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import fcl
import numpy as np
import pinocchio as pin
import pytest
from jaco2_description.exceptions import ModelError
from jaco2_description.model import (
    ARM_JOINTS,
    CANDLE,
    EE_FRAME,
    FINGER_JOINTS,
    HOME,
    Jaco2Model,
    full_model,
    link_parents,
    link_placements,
    planning_urdf,
    urdf_path,
    urdf_text,
)

PI = math.pi
# KINOVA_FACTS.md table (1): (origin xyz [m], origin rpy [rad]) of joint_1..7, then the EE frame.
JOINT_TABLE = [
    ((0, 0, 0.15675), (0, PI, 0)),
    ((0, 0.0016, -0.11875), (-PI / 2, 0, PI)),
    ((0, -0.205, 0), (-PI / 2, 0, 0)),
    ((0, 0, -0.205), (PI / 2, 0, PI)),
    ((0, 0.2073, -0.0114), (-PI / 2, 0, PI)),
    ((0, 0, -0.10375), (PI / 2, 0, PI)),
    ((0, 0.10375, 0), (-PI / 2, 0, PI)),
]
EE_ORIGIN = ((0, 0, -0.16), (PI, 0, PI / 2))
GAZEBO_SPAWN = np.array([0, 2.9, 0, 1.3, -2.07, 1.4, 0])


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def _homogeneous(xyz: tuple, rpy: tuple) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rot(2, rpy[2]) @ _rot(1, rpy[1]) @ _rot(0, rpy[0])
    T[:3, 3] = xyz
    return T


def numpy_fk(q: np.ndarray) -> np.ndarray:
    """Independent FK of the KINOVA_FACTS joint table: transform_ee_to_base, shape (4, 4)."""
    T = np.eye(4)
    for (xyz, rpy), angle in zip(JOINT_TABLE, q, strict=True):
        Rq = np.eye(4)
        Rq[:3, :3] = _rot(2, angle)
        T = T @ _homogeneous(xyz, rpy) @ Rq
    return T @ _homogeneous(*EE_ORIGIN)


@pytest.fixture(scope='module')
def robot() -> Jaco2Model:
    return Jaco2Model()


def test_model_dimensions_and_names(robot: Jaco2Model) -> None:
    assert robot.model.nq == robot.model.nv == 7
    assert tuple(robot.model.names)[1:] == ARM_JOINTS
    assert robot.model.existFrame(EE_FRAME)
    assert full_model().nq == full_model().nv == 13
    assert len(FINGER_JOINTS) == 6


def test_urdf_keeps_continuous_joints_and_planning_copy_converts_them() -> None:
    root = ET.fromstring(urdf_text())
    types = {j.get('name'): j.get('type') for j in root.iter('joint')}
    assert [types[n] for n in ARM_JOINTS] == ['continuous', 'revolute'] * 3 + ['continuous']
    assert types['j2s7s300_joint_end_effector'] == 'fixed'
    planning = ET.fromstring(planning_urdf(urdf_text()))
    assert not [j for j in planning.iter('joint') if j.get('type') == 'continuous']
    assert urdf_path().name == 'j2s7s300.urdf'
    assert link_parents()['j2s7s300_link_1'] == 'j2s7s300_link_base'


def test_limits_from_urdf(robot: Jaco2Model) -> None:
    lim = robot.limits
    np.testing.assert_allclose(lim.lower[[1, 3, 5]], [0.820305, 0.523599, 1.134464])
    np.testing.assert_allclose(lim.upper[[1, 3, 5]], [5.462881, 5.759587, 5.148721])
    np.testing.assert_allclose(lim.lower[[0, 2, 4, 6]], -4 * PI)  # continuous: far bounds
    np.testing.assert_allclose(lim.upper[[0, 2, 4, 6]], 4 * PI)
    np.testing.assert_allclose(lim.velocity, [0.6283] * 4 + [0.8378] * 3)
    assert np.all((lim.lower <= HOME) & (lim.upper >= HOME))


@pytest.mark.parametrize(
    ('q', 'expected'),
    [
        (CANDLE, (0.0, -0.013, 1.2603)),
        (HOME, (0.266, -0.212, 0.503)),
        (GAZEBO_SPAWN, (-0.164, 0.218, 0.541)),
        (np.zeros(7), (0.0, -0.0098, -0.0872)),
    ],
)
def test_fk_sanity_values(robot: Jaco2Model, q: np.ndarray, expected: tuple) -> None:
    np.testing.assert_allclose(robot.ee_pose(q).translation, expected, atol=1.5e-3)


def test_candle_joint_heights(robot: Jaco2Model) -> None:
    robot.forward(CANDLE)
    heights = [robot.data.oMi[i].translation[2] for i in range(1, 8)]
    np.testing.assert_allclose(
        heights, [0.15675, 0.2755, 0.4805, 0.6855, 0.8928, 0.9966, 1.1003], atol=2e-4
    )


def test_fk_matches_numpy_chain(robot: Jaco2Model) -> None:
    rng = np.random.default_rng(4)
    for _ in range(20):
        q = rng.uniform(robot.limits.lower, robot.limits.upper)
        T = numpy_fk(q)
        pose = robot.ee_pose(q)
        np.testing.assert_allclose(pose.translation, T[:3, 3], atol=1e-9)
        np.testing.assert_allclose(pose.rotation, T[:3, :3], atol=1e-9)


def test_jacobian_matches_finite_differences(robot: Jaco2Model) -> None:
    rng = np.random.default_rng(7)
    eps = 1e-6  # [rad]
    for _ in range(10):
        q = rng.uniform(robot.limits.lower + 0.1, robot.limits.upper - 0.1)
        J = robot.frame_jacobian(q)
        assert J.shape == (6, 7)
        pose = robot.ee_pose(q)
        J_fd = np.zeros((6, 7))
        for k in range(7):
            dq = np.zeros(7)
            dq[k] = eps
            moved = robot.ee_pose(q + dq)
            J_fd[:3, k] = (moved.translation - pose.translation) / eps
            J_fd[3:, k] = pin.log3(moved.rotation @ pose.rotation.T) / eps
        np.testing.assert_allclose(J, J_fd, atol=1e-5)


def test_home_and_candle_free_of_self_collision(robot: Jaco2Model) -> None:
    assert len(robot.self_collision_pairs) > 40
    for q in (HOME, CANDLE, GAZEBO_SPAWN):
        assert robot.self_collision_distances(q).min() > 0.03


def test_folded_arm_is_in_self_collision(robot: Jaco2Model) -> None:
    # Elbow and wrist folded back (q4 and q6 near their limits): the hand hits the upper arm.
    q = np.array([PI, PI, PI, 0.6, PI, 1.2, PI])
    assert robot.self_collision_distances(q).min() <= 0.0


def test_fcl_objects_follow_geometry_placements(robot: Jaco2Model) -> None:
    objects = robot.fcl_objects()
    assert [name for name, _ in objects] == robot.collision_links
    assert 'j2s7s300_link_7' in robot.collision_links
    assert objects[0][1].getNodeType() == fcl.Cylinder(1.0, 1.0).getNodeType()
    robot.update_fcl(HOME)
    for (_, obj), placement in zip(objects, robot.geometry_data.oMg, strict=True):
        np.testing.assert_allclose(obj.getTranslation(), placement.translation, atol=1e-12)
    hand = objects[robot.collision_links.index('j2s7s300_link_7')][1]
    assert hand.getNodeType() == fcl.Box(1.0, 1.0, 1.0).getNodeType()
    # The hand box is centred 6.05 cm from joint 7 towards the EE (KINOVA_FACTS table 3), i.e.
    # 0.16 - 0.0605 m behind the EE frame along its approach axis z.
    ee = robot.ee_pose(HOME)
    np.testing.assert_allclose(
        ee.actInv(hand.getTranslation()), [0.0018, 0.0, -(0.16 - 0.0605)], atol=1e-9
    )


def test_bad_inputs_raise(robot: Jaco2Model) -> None:
    with pytest.raises(ModelError, match='shape'):
        robot.forward(np.zeros(6))
    with pytest.raises(ModelError, match='non-finite'):
        robot.forward(np.array([np.nan] + [0.0] * 6))
    with pytest.raises(ModelError, match='finger_angle'):
        Jaco2Model(finger_angle=2.0)
    with pytest.raises(ModelError, match='unknown frame'):
        robot.frame_id('nope')


def test_link_placements_match_full_fk() -> None:
    q_all = dict(zip(ARM_JOINTS, HOME, strict=True)) | {n: 0.5 for n in FINGER_JOINTS}
    placements = link_placements(q_all)
    assert set(placements) == set(link_parents())
    # Chain the relative placements up to the base and compare with the planning model's FK.
    robot = Jaco2Model(finger_angle=0.5)
    world = pin.SE3.Identity()
    chain = []
    link = EE_FRAME
    while link in placements:
        chain.append(placements[link])
        link = link_parents()[link]
    for placement in reversed(chain):
        world = world * placement
    np.testing.assert_allclose(world.homogeneous, robot.ee_pose(HOME).homogeneous, atol=1e-9)
    # Joint 1 rotates link_1 about its own z, 0.15675 m above the base.
    p1 = placements['j2s7s300_link_1']
    np.testing.assert_allclose(p1.translation, [0, 0, 0.15675], atol=1e-12)
    with pytest.raises(ModelError, match='not finite'):
        link_placements({ARM_JOINTS[0]: math.inf})


def test_convention_cross_check_with_example_robot_data() -> None:
    """j2s6s200 of example-robot-data shares base, shoulder and joint-2 frames with j2s7s300."""
    erd = pytest.importorskip('example_robot_data')
    kinova = erd.load('kinova').model
    ours = full_model()
    for k in (1, 2):
        np.testing.assert_allclose(
            ours.jointPlacements[k].translation, kinova.jointPlacements[k].translation, atol=1e-9
        )
    np.testing.assert_allclose(
        ours.jointPlacements[2].rotation, kinova.jointPlacements[2].rotation, atol=1e-9
    )
    assert kinova.velocityLimit[0] == pytest.approx(0.6283, abs=1e-4)
    assert kinova.upperPositionLimit[kinova.joints[2].idx_q] == pytest.approx(5.4629, abs=1e-4)
