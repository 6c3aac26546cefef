"""Scene types → ``qtree_msgs/msg/Scene`` messages (message types only, no rclpy node).

The inverse of :mod:`qtree_scene.message`: the simulator publishes its world with it, and tests
and clients build SetScene requests from a scenario (YAML file, generator or a dict in the
scenario schema).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from geometry_msgs.msg import Pose, Vector3
from jaco2_description.model import BASE_LINK
from qtree_msgs.msg import ObjectState, Scene
from shape_msgs.msg import SolidPrimitive

from qtree_scene.message import ROLE_CODES, STATUS_CODES, primitive_of, yaw_quaternion
from qtree_scene.scene import Scenario, Status

PoseTuple = tuple[Sequence[float], Sequence[float]]  # position (3,) [m], quaternion xyzw (4,)


def pose_msg(position: Sequence[float], quaternion: Sequence[float] = (0, 0, 0, 1)) -> Pose:
    """geometry_msgs/Pose of a position [m] and a quaternion (x, y, z, w)."""
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
) -> Scene:
    """The Scene message of ``scenario`` (header stamp left at zero for the caller).

    Args:
        scenario: objects (the table a STATIC box), drop zone.
        poses: current pose of some objects by id; the others are at their scenario pose.
        statuses: status of some objects by id; the others are ``'in_clutter'``.
        attached_id: id of the object held by the hand, '' when none.
    """
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
