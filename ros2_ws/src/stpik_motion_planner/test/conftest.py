"""Shared fixtures of the motion-planner unit tests (no ROS import)."""

from __future__ import annotations

import pytest
from jaco2_description.model import Jaco2Model
from qtree_scene.scene import ObjectSpec, Scenario

TABLE = ObjectSpec('table', 'static', 'box', (0.35, 0.0, -0.025), size=(1.2, 1.4, 0.05))
HOME = (4.71, 2.84, 0.0, 0.75, 4.62, 4.48, 4.88)


def cylinder(name: str, x: float, y: float, role: str = 'obstacle', h: float = 0.14):
    """A cylinder of radius 3 cm standing on the table at (x, y) [m]."""
    return ObjectSpec(name, role, 'cylinder', (x, y, h / 2), radius=0.03, height=h)


def scenario(*objects: ObjectSpec) -> Scenario:
    """A scene with the table, the given objects and the usual drop zone."""
    return Scenario('test', (*objects, TABLE), (0.0, 0.5, 0.15), (0.3, 0.3, 0.3), HOME)


@pytest.fixture(scope='session')
def make_cylinder():
    """Factory fixture: :func:`cylinder`."""
    return cylinder


@pytest.fixture(scope='session')
def make_scenario():
    """Factory fixture: :func:`scenario`."""
    return scenario


@pytest.fixture(scope='session')
def robot() -> Jaco2Model:
    """One shared robot model (building it takes a few ms)."""
    return Jaco2Model()


@pytest.fixture(scope='session')
def free_scene() -> Scenario:
    """The target alone, 0.65 m in front of the robot."""
    return scenario(cylinder('T', 0.65, 0.0, 'target'))


@pytest.fixture(scope='session')
def boxed_scene() -> Scenario:
    """The target boxed in on every side by six obstacles 8 cm away."""
    import math

    ring = [
        cylinder(f'O{i}', 0.65 + 0.08 * math.cos(a), 0.08 * math.sin(a))
        for i, a in enumerate(math.radians(d) for d in range(0, 360, 60))
    ]
    return scenario(cylinder('T', 0.65, 0.0, 'target'), *ring)
