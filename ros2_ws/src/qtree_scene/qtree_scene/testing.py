"""Small scenes for tests: cylinders on the table, the usual drop zone (no ROS import).

Shared by the unit tests of the motion planner and of the benchmarks, so every test that says
"the target boxed in by six obstacles" means the same scene.
"""

from __future__ import annotations

import math

from jaco2_description.model import HOME as JACO2_HOME

from qtree_scene.scene import ObjectSpec, Role, Scenario

TABLE = ObjectSpec('table', 'static', 'box', (0.35, 0.0, -0.025), size=(1.2, 1.4, 0.05))
HOME = tuple(float(q) for q in JACO2_HOME)  # the Jaco2's home posture [rad]


def cylinder(
    name: str, x: float, y: float, role: Role = 'obstacle', h: float = 0.14
) -> ObjectSpec:
    """A cylinder of radius 3 cm and height ``h`` [m] standing on the table at (x, y) [m]."""
    return ObjectSpec(name, role, 'cylinder', (x, y, h / 2), radius=0.03, height=h)


def scenario(*objects: ObjectSpec) -> Scenario:
    """A scene with the table, the given objects and the usual drop zone."""
    return Scenario('test', (*objects, TABLE), (0.0, 0.5, 0.15), (0.3, 0.3, 0.3), HOME)


def free_scenario() -> Scenario:
    """The target alone, 0.65 m in front of the robot."""
    return scenario(cylinder('T', 0.65, 0.0, 'target'))


def boxed_scenario() -> Scenario:
    """The target boxed in on every side by six obstacles 8 cm away."""
    ring = [
        cylinder(f'O{i}', 0.65 + 0.08 * math.cos(a), 0.08 * math.sin(a))
        for i, a in enumerate(math.radians(d) for d in range(0, 360, 60))
    ]
    return scenario(cylinder('T', 0.65, 0.0, 'target'), *ring)
