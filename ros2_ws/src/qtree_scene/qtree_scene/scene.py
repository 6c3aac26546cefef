"""Plain data types of a scene: objects on a table in front of the arm (no ROS import).

The world frame is the robot base frame (``j2s7s300_link_base`` at the origin, z up). Every
length is in metres and every angle in radians.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Literal

Role = Literal['target', 'obstacle', 'static']
Shape = Literal['cylinder', 'box']
Status = Literal['in_clutter', 'grasped', 'relocated']

Vec3 = tuple[float, float, float]
ROLES: tuple[Role, ...] = ('target', 'obstacle', 'static')


def vec3(values: Iterable[float]) -> Vec3:
    """Three floats as a :data:`Vec3` (positions [m], box sizes [m]).

    Raises:
        ValueError: not exactly three values.
    """
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def role(value: str) -> Role:
    """``value`` as a :data:`Role`.

    Raises:
        ValueError: not one of :data:`ROLES`.
    """
    for known in ROLES:
        if value == known:
            return known
    raise ValueError(f'role must be one of {ROLES}, got {value!r}')


@dataclass(frozen=True)
class ObjectSpec:
    """One object of a scenario.

    Attributes:
        id: unique name, e.g. ``'T'`` or ``'O3'``.
        role: ``'target'``, ``'obstacle'`` (may be relocated) or ``'static'`` (table, walls).
        shape: ``'cylinder'`` (axis along world z) or ``'box'``.
        position: centre of the object in the world frame [m], shape (3,).
        yaw: rotation about world z [rad].
        radius: cylinder radius [m] (0 for boxes).
        height: cylinder height [m] (0 for boxes).
        size: full box edge lengths x, y, z [m] ((0, 0, 0) for cylinders).
    """

    id: str
    role: Role
    shape: Shape
    position: Vec3
    yaw: float = 0.0
    radius: float = 0.0
    height: float = 0.0
    size: Vec3 = (0.0, 0.0, 0.0)

    @property
    def top_z(self) -> float:
        """Height of the object's top face [m]."""
        half = self.height / 2 if self.shape == 'cylinder' else self.size[2] / 2
        return self.position[2] + half


@dataclass(frozen=True)
class Scenario:
    """A cluttered table: the target, the obstacles, static bodies and the drop zone.

    Attributes:
        name: scenario name, e.g. ``'s1'``.
        objects: every object; exactly one has role ``'target'``.
        drop_zone_center: centre of the drop-zone box where relocated objects go [m].
        drop_zone_size: full size of the drop zone [m].
        home: arm home configuration, 7 joint angles [rad] (Kinova convention).
        description: free text.
        source: file the scenario was loaded from ('' if built in code).
        robot_keepout_radius: no object footprint within this distance of the base axis [m].
    """

    name: str
    objects: tuple[ObjectSpec, ...]
    drop_zone_center: Vec3
    drop_zone_size: Vec3
    home: tuple[float, ...]
    description: str = ''
    source: str = field(default='', compare=False)
    robot_keepout_radius: float = 0.2

    @property
    def target(self) -> ObjectSpec:
        """The one object with role ``'target'``."""
        return next(o for o in self.objects if o.role == 'target')

    @property
    def obstacles(self) -> tuple[ObjectSpec, ...]:
        """Objects with role ``'obstacle'``, in file order."""
        return tuple(o for o in self.objects if o.role == 'obstacle')

    @property
    def statics(self) -> tuple[ObjectSpec, ...]:
        """Objects with role ``'static'`` (never relocated)."""
        return tuple(o for o in self.objects if o.role == 'static')

    @property
    def movable_ids(self) -> tuple[str, ...]:
        """Ids of the obstacles then the target: the paper's action set a_1..a_No, a_T."""
        return (*(o.id for o in self.obstacles), self.target.id)

    def object(self, object_id: str) -> ObjectSpec:
        """The object named ``object_id``.

        Raises:
            KeyError: no such object.
        """
        for obj in self.objects:
            if obj.id == object_id:
                return obj
        raise KeyError(object_id)
