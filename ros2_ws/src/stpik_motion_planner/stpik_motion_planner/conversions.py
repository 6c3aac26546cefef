"""Message ↔ core conversions of the motion-planner node (ROS message types, no rclpy node)."""

from __future__ import annotations

import math

import numpy as np
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Pose, PoseArray
from jaco2_sim.model import ARM_JOINTS, HOME
from jaco2_sim.scene import ObjectSpec, Scenario
from qtree_msgs.msg import ObjectState, Scene
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

ROLES = {
    ObjectState.ROLE_TARGET: 'target',
    ObjectState.ROLE_OBSTACLE: 'obstacle',
    ObjectState.ROLE_STATIC: 'static',
}
SHAPES = {ObjectState.SHAPE_CYLINDER: 'cylinder', ObjectState.SHAPE_BOX: 'box'}


def _yaw(pose: Pose) -> float:
    q = pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def scenario_from_msg(
    msg: Scene,
    home: tuple[float, ...] = tuple(HOME),
    original: dict[str, tuple[float, float, float]] | None = None,
) -> Scenario:
    """Scene message → :class:`Scenario` (objects not IN_CLUTTER keep their ``original`` pose).

    Raises:
        ValueError: unknown role or shape code.
    """
    objects = []
    for o in msg.objects:
        if o.role not in ROLES or o.shape not in SHAPES:
            raise ValueError(f'object {o.id!r}: unknown role {o.role} or shape {o.shape}')
        p = o.pose.position
        position = (p.x, p.y, p.z)
        if o.status != ObjectState.STATUS_IN_CLUTTER and original and o.id in original:
            position = original[o.id]
        size = (o.box_size.x, o.box_size.y, o.box_size.z)
        objects.append(
            ObjectSpec(
                o.id,
                ROLES[o.role],
                SHAPES[o.shape],
                position,
                _yaw(o.pose),
                o.radius,
                o.height,
                size,
            )
        )
    c = msg.drop_zone.position
    s = msg.drop_zone_size
    return Scenario(msg.scenario_name, tuple(objects), (c.x, c.y, c.z), (s.x, s.y, s.z), home)


def trajectory_msg(times: np.ndarray, q: np.ndarray) -> JointTrajectory:
    """Arrays (N,) [s] and (N, 7) [rad] → JointTrajectory of the arm joints."""
    msg = JointTrajectory()
    msg.joint_names = list(ARM_JOINTS)
    for t, row in zip(times, q, strict=True):
        point = JointTrajectoryPoint()
        point.positions = [float(v) for v in row]
        sec = math.floor(t)
        point.time_from_start = Duration(sec=int(sec), nanosec=int((t - sec) * 1e9))
        msg.points.append(point)
    return msg


def pose_array_msg(path: np.ndarray, frame_id: str) -> PoseArray:
    """(M, 7) xyz + quaternion xyzw → PoseArray."""
    msg = PoseArray()
    msg.header.frame_id = frame_id
    for row in path:
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = (float(v) for v in row[:3])
        o = pose.orientation
        o.x, o.y, o.z, o.w = (float(v) for v in row[3:])
        msg.poses.append(pose)
    return msg
