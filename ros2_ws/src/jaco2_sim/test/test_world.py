"""Tests of jaco2_sim.world: attach keeps the EE offset, update moves, detach leaves in place."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from jaco2_description.model import HOME, Jaco2Model
from jaco2_sim.exceptions import WorldError
from jaco2_sim.world import World
from qtree_scene.scenario import load_scenario


@pytest.fixture
def world() -> World:
    return World(load_scenario('s1'))


def test_initial_state(world: World) -> None:
    assert world.attached_id is None
    target = world.state('T')
    assert target.status == 'in_clutter'
    np.testing.assert_allclose(target.pose.translation, target.spec.position)
    assert set(world.objects) == {'T', 'O1', 'O2', 'O3', 'O4', 'O5', 'table'}


def test_attach_follows_ee_then_detach_leaves_object(world: World) -> None:
    robot = Jaco2Model()
    ee0 = robot.ee_pose(HOME)
    start = world.state('O1').pose.copy()
    distance = world.attach('O1', ee0)
    assert distance == pytest.approx(np.linalg.norm(start.translation - ee0.translation))
    assert world.state('O1').status == 'grasped'
    ee1 = robot.ee_pose(HOME + np.array([0.3, 0.1, 0.0, -0.2, 0.0, 0.1, 0.4]))
    version = world.version
    assert world.update(ee1)
    assert world.version == version + 1
    moved = world.state('O1').pose
    # The offset object-to-EE is the one at attach time.
    np.testing.assert_allclose(
        ee1.actInv(moved).homogeneous, ee0.actInv(start).homogeneous, atol=1e-12
    )
    assert not world.update(ee1)  # no motion, no change
    world.detach('O1')
    assert world.state('O1').status == 'relocated' and world.attached_id is None
    world.update(ee0)
    np.testing.assert_allclose(world.state('O1').pose.homogeneous, moved.homogeneous)


def test_pure_translation_of_ee_translates_object(world: World) -> None:
    ee = pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.3]))
    world.attach('T', ee)
    world.update(pin.SE3(np.eye(3), np.array([0.5, 0.2, 0.4])))
    start = np.array(world.state('T').spec.position)
    np.testing.assert_allclose(
        world.state('T').pose.translation, start + np.array([0.0, 0.2, 0.1]), atol=1e-12
    )


def test_errors(world: World) -> None:
    ee = pin.SE3.Identity()
    with pytest.raises(WorldError, match='unknown object'):
        world.attach('nope', ee)
    with pytest.raises(WorldError, match='static'):
        world.attach('table', ee)
    with pytest.raises(WorldError, match='not attached'):
        world.detach('O2')
    world.attach('O2', ee)
    with pytest.raises(WorldError, match="'O2' is attached"):
        world.attach('O3', ee)
    with pytest.raises(WorldError, match='release status'):
        world.detach('O2', status='grasped')
    world.detach('O2', status='in_clutter')
    assert world.state('O2').status == 'in_clutter'


def test_reset(world: World) -> None:
    start = np.array(world.state('O3').spec.position)
    world.attach('O3', pin.SE3.Identity())
    world.update(pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.0])))
    world.reset()
    assert world.attached_id is None
    assert world.state('O3').status == 'in_clutter'
    np.testing.assert_allclose(world.state('O3').pose.translation, start)


def test_relocated_object_released_near_its_slot_stands_upright_on_it(world: World) -> None:
    from qtree_scene.placement import slot_position

    obj = world.state('O2').spec
    slot = slot_position(world.scenario, 0, obj)
    tilted = pin.SE3(pin.rpy.rpyToMatrix(0.05, -0.03, 0.4), slot + np.array([0.01, 0.02, 0.01]))
    world.attach('O2', tilted)  # EE at the object's pose: offset identity after the move
    world.update(tilted * world._object_to_ee.inverse() * world._object_to_ee)
    world.objects['O2'].pose = tilted
    world.detach('O2')
    pose = world.state('O2').pose
    np.testing.assert_allclose(pose.translation, slot, atol=1e-12)
    np.testing.assert_allclose(pose.rotation[:, 2], [0.0, 0.0, 1.0], atol=1e-12)


def test_huge_ids_are_quoted_short(world: World) -> None:
    with pytest.raises(WorldError, match=r"unknown object 'xxxx.*…' \(10000 characters\)") as err:
        world.attach('x' * 10_000, pin.SE3.Identity())  # was echoed in full (#18)
    assert len(str(err.value)) < 300
