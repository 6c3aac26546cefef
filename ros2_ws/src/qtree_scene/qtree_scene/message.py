"""``qtree_msgs/msg/Scene`` ↔ scene types: the one home of both directions.

Reading is duck-typed (attribute access, no ROS import); writing (:func:`scene_msg`, the
simulator's ``/scene`` and the SetScene requests of tests and clients) imports the message types
when it is called.

One converter for every node that reads a scene message: the simulator's ``SetScene`` (strict,
:func:`parse_scene_msg`: as strict as a scenario YAML file, the same validator and messages) and
the motion planner's ``/scene`` subscription (:func:`scenario_from_msg`: the per-field checks
only, since a published scene may hold relocated objects in the drop zone).

Object shapes are ``shape_msgs/SolidPrimitive``: CYLINDER with dimensions ``[height, radius]``,
BOX with ``[x, y, z]`` full edge lengths [m]. Poses are the shape's centre in the robot base frame
(``j2s7s300_link_base``, z up); objects are upright, so an orientation is a yaw about z.

Every error is a :class:`~qtree_scene.exceptions.ScenarioError` whose field is the message field
(``objects[3].shape.dimensions[1]``) and whose problem names the object id.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, NoReturn

from jaco2_description.model import BASE_LINK, HOME

from qtree_scene.exceptions import ScenarioError
from qtree_scene.fields import Fail, brief, failer, number
from qtree_scene.scenario import (
    MAX_OBJECTS,
    TABLE_ID,
    check_object_count,
    validate_scenario,
)
from qtree_scene.scene import ObjectSpec, Role, Scenario, Shape, Status, vec3

# qtree_msgs/msg/ObjectState and shape_msgs/msg/SolidPrimitive constants (test_message.py checks
# them against the generated message classes).
ROLE_CODES: dict[Role, int] = {'target': 0, 'obstacle': 1, 'static': 2}
STATUS_CODES = {'in_clutter': 0, 'grasped': 1, 'relocated': 2}
PRIMITIVE_BOX, PRIMITIVE_CYLINDER = 1, 3  # SolidPrimitive.BOX, .CYLINDER
PRIMITIVE_NAMES: dict[int, Shape] = {PRIMITIVE_BOX: 'box', PRIMITIVE_CYLINDER: 'cylinder'}
DIMENSION_NAMES = {'box': ('x', 'y', 'z'), 'cylinder': ('height', 'radius')}
MAX_ID_CHARS = 256  # longest object id [characters]
UPRIGHT_TOLERANCE = 0.01  # largest tilt of an object's z axis from the world z [rad]
UNIT_TOLERANCE = 1e-3  # largest | |q| - 1 | of an orientation quaternion [-]
STANDING_TOLERANCE_M = 0.01  # largest gap between an object's bottom and the table top [m]
SOURCE = 'SetScene'  # prefix of the strict parser's error messages

_ROLE_NAMES = {code: name for name, code in ROLE_CODES.items()}
_STATUS_NAMES = {code: name for name, code in STATUS_CODES.items()}


def primitive_of(obj: ObjectSpec) -> tuple[int, list[float]]:
    """``(SolidPrimitive type, dimensions)`` of a scene object (dimensions in metres)."""
    if obj.shape == 'cylinder':
        return PRIMITIVE_CYLINDER, [float(obj.height), float(obj.radius)]
    return PRIMITIVE_BOX, [float(v) for v in obj.size]


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation of ``yaw`` [rad] about z."""
    return 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)


def scenario_from_msg(
    msg: Any,
    original: Mapping[str, ObjectSpec] | None = None,
    home: tuple[float, ...] = tuple(HOME),
    source: str = '',
) -> Scenario:
    """A Scene message → :class:`Scenario`, with the per-field checks (no geometry rules).

    Args:
        msg: a decoded ``qtree_msgs/msg/Scene``.
        original: objects as they were while IN_CLUTTER, by id; an object of ``msg`` that is
            GRASPED or RELOCATED and is in ``original`` is taken from it (the contract of
            Scene.msg: relocation does not change the scene planned against).
        home: arm home configuration of the scenario, 7 angles [rad].
        source: prefix of the error messages.

    Raises:
        ScenarioError: bad frame, more than :data:`MAX_OBJECTS` objects, or a bad object field
            (id, role, status, primitive type, dimensions, non-finite or non-unit pose, ...).
    """
    fail = failer(source)
    frame = getattr(msg.header, 'frame_id', '')
    if frame not in ('', BASE_LINK):
        fail(
            'header.frame_id', f'must be {BASE_LINK!r} (the robot base frame), got {brief(frame)}'
        )
    check_object_count(len(msg.objects), fail)
    objects = []
    for i, obj in enumerate(msg.objects):
        spec = _object(obj, f'objects[{i}]', fail)
        if original and spec.id in original and _status(obj, f'objects[{i}]', fail) != 0:
            spec = original[spec.id]
        objects.append(spec)
    zone = _point(msg.drop_zone.position, 'drop_zone.position', fail)
    size = _positive_xyz(msg.drop_zone_size, 'drop_zone_size', fail)
    name = msg.scenario_name if isinstance(msg.scenario_name, str) else ''
    return Scenario(name, tuple(objects), zone, size, tuple(home))


def parse_scene_msg(msg: Any, home: tuple[float, ...] = tuple(HOME)) -> Scenario:
    """A Scene message → :class:`Scenario`, validated as strictly as a scenario YAML file.

    On top of :func:`scenario_from_msg`: a non-empty name, every status IN_CLUTTER, nothing
    attached, the robot base and the drop zone not rotated, objects upright and standing on the
    table top (z = 0, within :data:`STANDING_TOLERANCE_M`), then
    :func:`~qtree_scene.scenario.validate_scenario` (one target, unique ids, the table, no
    overlaps, keep-out radius, ...).

    Raises:
        ScenarioError: the first problem, prefixed ``SetScene:``, naming the field and object.
    """
    fail = failer(SOURCE)
    if not isinstance(msg.scenario_name, str) or not msg.scenario_name.strip():
        fail('scenario_name', f'must be a non-empty string, got {brief(msg.scenario_name)}')
    if msg.attached_id:
        fail('attached_id', f'must be empty in a new scene, got {brief(msg.attached_id)}')
    scenario = scenario_from_msg(msg, home=home, source=SOURCE)
    _identity(msg.robot_base, 'robot_base', 'the scene frame is the robot base frame', fail)
    _identity(msg.drop_zone, 'drop_zone', 'the drop zone is an axis-aligned box', fail)
    for i, (obj, spec) in enumerate(zip(msg.objects, scenario.objects, strict=True)):
        field = f'objects[{i}]'
        status = _status(obj, field, fail)
        if status != STATUS_CODES['in_clutter']:
            problem = f'must be STATUS_IN_CLUTTER (0) in a new scene, got {status}'
            fail(f'{field}.status', f'{spec.id!r}: {problem}')
        _upright(obj.pose.orientation, f'{field}.pose.orientation', spec.id, fail)
        bottom = 2 * spec.position[2] - spec.top_z  # centre z - half height [m]
        if spec.role != 'static' and abs(bottom) > STANDING_TOLERANCE_M:
            problem = f'must stand on the table top (z = 0), its bottom is at {bottom:.3f} m'
            fail(f'{field}.pose.position.z', f'{spec.id!r}: {problem}')
    table = [i for i, o in enumerate(scenario.objects) if o.id == TABLE_ID]
    if not table:
        fail('objects', f'no object {TABLE_ID!r} (the STATIC box the objects stand on)')
    spec = scenario.objects[table[0]]
    if spec.shape != 'box' or spec.role != 'static':
        fail(f'objects[{table[0]}]', f'{TABLE_ID!r} must be a STATIC BOX')
    validate_scenario(scenario, source=SOURCE, position_field='pose.position')
    return scenario


def _object(obj: Any, field: str, fail: Fail) -> ObjectSpec:
    object_id = obj.id
    if not isinstance(object_id, str) or not object_id.strip():
        fail(f'{field}.id', f'must be a non-empty string, got {brief(object_id)}')
    if len(object_id) > MAX_ID_CHARS:
        fail(f'{field}.id', f'{len(object_id)} characters, at most {MAX_ID_CHARS}')
    name = repr(object_id)
    role = _ROLE_NAMES.get(obj.role)
    if role is None:
        fail(
            f'{field}.role',
            f'{name}: unknown role {obj.role} (ROLE_TARGET 0, OBSTACLE 1, STATIC 2)',
        )
    _status(obj, field, fail)
    shape = _shape(obj.shape, f'{field}.shape', name, fail)
    dims = list(obj.shape.dimensions)
    sizes = [
        number(v, f'{field}.shape.dimensions[{k}]', _named(name, axis, fail), positive=True)
        for k, (v, axis) in enumerate(zip(dims, DIMENSION_NAMES[shape], strict=True))
    ]
    position = _point(obj.pose.position, f'{field}.pose.position', _named(name, '', fail))
    yaw = _yaw(obj.pose.orientation, f'{field}.pose.orientation', name, fail)
    if shape == 'cylinder':
        height, radius = sizes
        return ObjectSpec(object_id, role, shape, position, yaw, radius=radius, height=height)
    return ObjectSpec(object_id, role, shape, position, yaw, size=vec3(sizes))


def _shape(primitive: Any, field: str, name: str, fail: Fail) -> Shape:
    shape = PRIMITIVE_NAMES.get(primitive.type)
    if shape is None:
        fail(
            f'{field}.type',
            f'{name}: unknown primitive type {primitive.type} (BOX {PRIMITIVE_BOX} or '
            f'CYLINDER {PRIMITIVE_CYLINDER})',
        )
    wanted = DIMENSION_NAMES[shape]
    if len(primitive.dimensions) != len(wanted):
        fail(
            f'{field}.dimensions',
            f'{name}: a {shape.upper()} needs {len(wanted)} dimensions [{", ".join(wanted)}], '
            f'got {len(primitive.dimensions)}',
        )
    return shape


def _status(obj: Any, field: str, fail: Fail) -> int:
    if obj.status not in _STATUS_NAMES:
        problem = f'unknown status {obj.status} (IN_CLUTTER 0, GRASPED 1, RELOCATED 2)'
        fail(f'{field}.status', f'{obj.id!r}: {problem}')
    return obj.status


def _named(name: str, what: str, fail: Fail) -> Fail:
    """``fail`` with the object (and the dimension) named in front of the problem."""
    label = f'{name} {what}'.strip()

    def named(field: str, problem: str) -> NoReturn:
        fail(field, f'{label}: {problem}')

    return named


def _point(p: Any, field: str, fail: Fail) -> tuple[float, float, float]:
    return vec3(number(getattr(p, a), f'{field}.{a}', fail) for a in 'xyz')


def _positive_xyz(v: Any, field: str, fail: Fail) -> tuple[float, float, float]:
    return vec3(number(getattr(v, a), f'{field}.{a}', fail, positive=True) for a in 'xyz')


def _quaternion(q: Any, field: str, name: str, fail: Fail) -> tuple[float, ...]:
    x, y, z, w = (number(getattr(q, a), f'{field}.{a}', _named(name, '', fail)) for a in 'xyzw')
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        fail(field, f'{name}: not a unit quaternion (norm {norm:.4g})')
    return x / norm, y / norm, z / norm, w / norm


def _yaw(q: Any, field: str, name: str, fail: Fail) -> float:
    x, y, z, w = _quaternion(q, field, name, fail)
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def _upright(q: Any, field: str, object_id: str, fail: Fail) -> None:
    x, y, _, _ = _quaternion(q, field, repr(object_id), fail)
    tilt = 2 * math.asin(min(1.0, math.hypot(x, y)))  # angle of the z axis from world z [rad]
    if tilt > UPRIGHT_TOLERANCE:
        fail(field, f'{object_id!r}: tilted {tilt:.3f} rad, objects stand upright (yaw only)')


def _identity(pose: Any, field: str, why: str, fail: Fail) -> None:
    position = _point(pose.position, f'{field}.position', fail)
    x, y, z, _ = _quaternion(pose.orientation, f'{field}.orientation', field, fail)
    if field == 'robot_base' and any(abs(v) > 1e-9 for v in position):
        fail(f'{field}.position', f'must be (0, 0, 0): {why}, got {position}')
    if max(abs(x), abs(y), abs(z)) > 1e-6:
        fail(f'{field}.orientation', f'must be the identity: {why}')


__all__ = [
    'MAX_OBJECTS',
    'ScenarioError',
    'parse_scene_msg',
    'primitive_of',
    'scenario_from_msg',
    'yaw_quaternion',
]


PoseTuple = tuple[Sequence[float], Sequence[float]]  # position (3,) [m], quaternion xyzw (4,)


def pose_msg(position: Sequence[float], quaternion: Sequence[float] = (0, 0, 0, 1)) -> Any:
    """geometry_msgs/Pose of a position [m] and a quaternion (x, y, z, w)."""
    from geometry_msgs.msg import Pose  # lazy: the readers above need no message package

    msg = Pose()
    msg.position.x, msg.position.y, msg.position.z = (float(v) for v in position)
    o = msg.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in quaternion)
    return msg


def scene_msg(
    scenario: Scenario,
    poses: Mapping[str, PoseTuple] | None = None,
    statuses: Mapping[str, Status] | None = None,
    attached_id: str = '',
) -> Any:
    """The Scene message of ``scenario`` (header stamp left at zero for the caller).

    Args:
        scenario: objects (the table a STATIC box), drop zone.
        poses: current pose of some objects by id; the others are at their scenario pose.
        statuses: status of some objects by id; the others are ``'in_clutter'``.
        attached_id: id of the object held by the hand, '' when none.
    """
    from geometry_msgs.msg import Vector3
    from qtree_msgs.msg import ObjectState, Scene
    from shape_msgs.msg import SolidPrimitive

    poses, statuses = poses or {}, statuses or {}
    msg = Scene(scenario_name=scenario.name, attached_id=attached_id)
    msg.header.frame_id = BASE_LINK
    for spec in scenario.objects:
        kind, dimensions = primitive_of(spec)
        position, quaternion = poses.get(spec.id, (spec.position, yaw_quaternion(spec.yaw)))
        msg.objects.append(
            ObjectState(
                id=spec.id,
                role=ROLE_CODES[spec.role],
                shape=SolidPrimitive(type=kind, dimensions=dimensions),
                pose=pose_msg(position, quaternion),
                status=STATUS_CODES[statuses.get(spec.id, 'in_clutter')],
            )
        )
    msg.drop_zone = pose_msg(scenario.drop_zone_center)
    x, y, z = (float(v) for v in scenario.drop_zone_size)
    msg.drop_zone_size = Vector3(x=x, y=y, z=z)
    msg.robot_base = pose_msg((0.0, 0.0, 0.0))
    return msg
