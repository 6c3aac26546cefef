"""Scene objects as ``visualization_msgs/msg/MarkerArray`` and ``/tf`` frames (no ROS import).

The input is a decoded ``qtree_msgs/msg/Scene`` (an rclpy message, a rosbags message or any object
with the same attributes). Output messages are plain dicts for
:class:`qtree_recorder.encoding.DynamicEncoder`, so Foxglove (and any MarkerArray viewer) shows the
table, target and obstacles, coloured by role and status, moving while carried:

* target green, obstacles red, relocated objects grey, static bodies (table) brown, the object
  held by the gripper yellow; the drop zone a translucent blue box;
* one ``/tf`` frame ``world`` → ``object/<id>`` per object (its pose in the scene frame).

The array starts with a DELETEALL marker so objects that left the scene disappear.
"""

from __future__ import annotations

from typing import Any

from qtree_recorder.tf_frames import WORLD_FRAME, FrameTransform

ROLE_TARGET, ROLE_OBSTACLE, ROLE_STATIC = 0, 1, 2  # qtree_msgs/ObjectState.ROLE_*
PRIMITIVE_BOX, PRIMITIVE_CYLINDER = 1, 3  # shape_msgs/SolidPrimitive.BOX, .CYLINDER
LEGACY_CYLINDER = 0  # ObjectState.SHAPE_CYLINDER of logs recorded before SolidPrimitive shapes
STATUS_IN_CLUTTER, STATUS_GRASPED, STATUS_RELOCATED = 0, 1, 2  # ObjectState.STATUS_*
MARKER_CUBE, MARKER_CYLINDER, MARKER_TEXT = 1, 3, 9  # visualization_msgs/Marker types
ACTION_ADD, ACTION_DELETEALL = 0, 3  # visualization_msgs/Marker actions
OBJECT_FRAME_PREFIX = 'object/'

Rgba = tuple[float, float, float, float]
COLOR_TARGET: Rgba = (0.10, 0.75, 0.20, 1.0)
COLOR_OBSTACLE: Rgba = (0.85, 0.15, 0.10, 1.0)
COLOR_RELOCATED: Rgba = (0.60, 0.60, 0.60, 1.0)
COLOR_STATIC: Rgba = (0.55, 0.35, 0.17, 1.0)
COLOR_GRASPED: Rgba = (0.95, 0.80, 0.10, 1.0)
COLOR_DROP_ZONE: Rgba = (0.20, 0.40, 0.90, 0.25)
COLOR_LABEL: Rgba = (1.0, 1.0, 1.0, 1.0)
LABEL_HEIGHT_M = 0.03  # [m] text size
LABEL_OFFSET_M = 0.04  # [m] above the object's top


def object_color(role: int, status: int, attached: bool = False) -> Rgba:
    """Colour of an object by role and status (the held object wins, then relocated)."""
    if attached or status == STATUS_GRASPED:
        return COLOR_GRASPED
    if status == STATUS_RELOCATED:
        return COLOR_RELOCATED
    return {ROLE_TARGET: COLOR_TARGET, ROLE_OBSTACLE: COLOR_OBSTACLE}.get(role, COLOR_STATIC)


def _xyz(v: Any) -> dict[str, float]:
    return {'x': float(v.x), 'y': float(v.y), 'z': float(v.z)}


def _pose(pose: Any) -> dict[str, dict[str, float]]:
    q = pose.orientation
    quat = {'x': float(q.x), 'y': float(q.y), 'z': float(q.z), 'w': float(q.w)}
    if all(v == 0.0 for v in quat.values()):  # an unset quaternion means identity
        quat['w'] = 1.0
    return {'position': _xyz(pose.position), 'orientation': quat}


def _marker(stamp: dict, ns: str, marker_id: int, kind: int, pose: dict, scale: dict,
            color: Rgba, text: str = '', action: int = ACTION_ADD) -> dict:  # fmt: skip
    return {
        'header': {'stamp': stamp, 'frame_id': WORLD_FRAME},
        'ns': ns,
        'id': marker_id,
        'type': kind,
        'action': action,
        'pose': pose,
        'scale': scale,
        'color': dict(zip(('r', 'g', 'b', 'a'), color, strict=True)),
        'lifetime': {'sec': 0, 'nanosec': 0},
        'frame_locked': False,
        'text': text,
    }


def object_geometry(obj: Any) -> tuple[str, float, float, tuple[float, float, float]]:
    """``(shape, radius, height, box size)`` of a decoded ObjectState [m].

    ``obj.shape`` is a ``shape_msgs/SolidPrimitive`` (CYLINDER dimensions [height, radius], BOX
    [x, y, z]); older logs, with ``shape`` a code and ``radius``/``height``/``box_size`` fields,
    are read too. An unknown primitive is drawn as a box of its (padded) dimensions.
    """
    shape = obj.shape
    if not hasattr(shape, 'type'):  # a log recorded before SolidPrimitive shapes
        size = obj.box_size
        if int(shape) == LEGACY_CYLINDER:
            return 'cylinder', float(obj.radius), float(obj.height), (0.0, 0.0, 0.0)
        return 'box', 0.0, 0.0, (float(size.x), float(size.y), float(size.z))
    dims = [float(v) for v in shape.dimensions]
    if int(shape.type) == PRIMITIVE_CYLINDER and len(dims) == 2:
        return 'cylinder', dims[1], dims[0], (0.0, 0.0, 0.0)
    dims = [*dims, 0.0, 0.0, 0.0][:3]
    return 'box', 0.0, 0.0, (dims[0], dims[1], dims[2])


def object_scale(obj: Any) -> dict[str, float]:
    """Marker scale of an object: cylinder (2r, 2r, h), box its full edge lengths [m]."""
    shape, radius, height, size = object_geometry(obj)
    if shape == 'cylinder':
        return {'x': 2.0 * radius, 'y': 2.0 * radius, 'z': height}
    return dict(zip('xyz', size, strict=True))


def scene_markers(scene: Any, stamp_ns: int) -> dict:
    """A ``visualization_msgs/msg/MarkerArray`` dict of a ``qtree_msgs/msg/Scene``.

    Args:
        scene: decoded Scene (attributes ``objects``, ``attached_id``, ``drop_zone``,
            ``drop_zone_size``).
        stamp_ns: header stamp [ns since epoch].
    """
    stamp = {'sec': stamp_ns // 1_000_000_000, 'nanosec': stamp_ns % 1_000_000_000}
    identity = {'position': {'x': 0.0, 'y': 0.0, 'z': 0.0},
                'orientation': {'x': 0.0, 'y': 0.0, 'z': 0.0, 'w': 1.0}}  # fmt: skip
    zero = {'x': 0.0, 'y': 0.0, 'z': 0.0}
    markers = [_marker(stamp, '', 0, MARKER_CUBE, identity, zero, (0, 0, 0, 0),
                       action=ACTION_DELETEALL)]  # fmt: skip
    attached = str(getattr(scene, 'attached_id', ''))
    for index, obj in enumerate(scene.objects):
        pose = _pose(obj.pose)
        scale = object_scale(obj)
        kind = MARKER_CYLINDER if object_geometry(obj)[0] == 'cylinder' else MARKER_CUBE
        color = object_color(int(obj.role), int(obj.status), bool(attached) and obj.id == attached)
        markers.append(_marker(stamp, 'objects', index, kind, pose, scale, color))
        if int(obj.role) != ROLE_STATIC:
            label = {'position': dict(pose['position']), 'orientation': identity['orientation']}
            label['position']['z'] += scale['z'] / 2 + LABEL_OFFSET_M
            text_scale = {'x': 0.0, 'y': 0.0, 'z': LABEL_HEIGHT_M}
            markers.append(_marker(stamp, 'labels', index, MARKER_TEXT, label, text_scale,
                                   COLOR_LABEL, text=str(obj.id)))  # fmt: skip
    size = getattr(scene, 'drop_zone_size', None)
    if size is not None and float(size.x) * float(size.y) > 0.0:
        markers.append(_marker(stamp, 'drop_zone', 0, MARKER_CUBE, _pose(scene.drop_zone),
                               _xyz(size), COLOR_DROP_ZONE))  # fmt: skip
    return {'markers': markers}


def object_transforms(scene: Any) -> list[FrameTransform]:
    """One ``world`` → ``object/<id>`` transform per object of a decoded Scene."""
    out = []
    for obj in scene.objects:
        pose = _pose(obj.pose)
        p, q = pose['position'], pose['orientation']
        out.append(
            FrameTransform(
                WORLD_FRAME,
                OBJECT_FRAME_PREFIX + str(obj.id),
                (p['x'], p['y'], p['z']),
                (q['x'], q['y'], q['z'], q['w']),
            )
        )
    return out
