"""Message ↔ core conversions for the simulator node (the only module besides the node that imports
ROS message types).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np
import pinocchio as pin
import rclpy.serialization
from builtin_interfaces.msg import Time
from jaco2_description.model import ARM_JOINTS, FINGER_JOINTS
from qtree_msgs.msg import Scene
from qtree_scene import message as scene_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from jaco2_sim.exceptions import TrajectoryError
from jaco2_sim.world import World

MAX_SCANNED_NAMES = 256  # trajectory_size() stops counting points after this many joint names


def scene_msg(world: World, stamp: Time) -> Scene:
    """qtree_msgs/Scene of the world: objects (table = STATIC box), drop zone, attached id."""
    poses = {}
    for object_id, state in world.objects.items():
        q = pin.Quaternion(state.pose.rotation)
        poses[object_id] = (state.pose.translation, (q.x, q.y, q.z, q.w))
    statuses = {object_id: state.status for object_id, state in world.objects.items()}
    msg = scene_message.scene_msg(world.scenario, poses, statuses, world.attached_id or '')
    msg.header.stamp = stamp
    return msg


def joint_state_msg(
    stamp: Time, q: np.ndarray, velocity: np.ndarray, fingers: np.ndarray
) -> JointState:
    """sensor_msgs/JointState of the arm (7) then the fingers (6) [rad], [rad/s]."""
    msg = JointState()
    msg.header.stamp = stamp
    msg.name = [*ARM_JOINTS, *FINGER_JOINTS]
    msg.position = [float(v) for v in (*q, *fingers)]
    msg.velocity = [float(v) for v in (*velocity, *np.zeros(len(FINGER_JOINTS)))]
    return msg


def trajectory_arrays(
    msg: JointTrajectory,
) -> tuple[list[str], np.ndarray, list[Sequence[float]], list[Sequence[float]] | None]:
    """(joint_names, times [s] (N,), positions (N rows), velocities (N rows) or None).

    One pass of C-level iteration per field (numpy ``fromiter`` over the points, the rows are the
    messages' own ``array.array`` buffers, no copy): about 5 ms for 10 000 points. The shapes and
    values are checked by :meth:`JointIntegrator.set_reference`, which stacks the rows with numpy.

    Raises:
        TrajectoryError: velocities given on some points only.
    """
    points = msg.points
    n = len(points)
    times = np.fromiter(
        (p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in points),
        dtype=float,
        count=n,
    )
    positions = [p.positions for p in points]
    with_velocities = np.fromiter((len(p.velocities) > 0 for p in points), dtype=bool, count=n)
    if with_velocities.any() and not with_velocities.all():
        raise TrajectoryError('velocities must be given on every point or on none')
    velocities = [p.velocities for p in points] if with_velocities.any() else None
    return list(msg.joint_names), times, positions, velocities


def trajectory_size(raw: bytes) -> tuple[int, int | None] | None:
    """(number of joint names, number of points) of a serialised trajectory_msgs/JointTrajectory.

    Reads only the lengths at the start of the CDR data (header, joint names, then the points'
    sequence length), so the cost does not grow with the number of points: the node can reject an
    oversized trajectory before rclpy deserialises it (about 0.8 s for 100 000 points).

    Args:
        raw: the message as a raw subscription receives it (4-byte encapsulation, then CDR).

    Returns:
        ``(names, points)``; ``points`` is None when there are more than
        :data:`MAX_SCANNED_NAMES` joint names (not scanned further). None if ``raw`` is not plain
        CDR or is truncated (then deserialise it and let that fail or succeed).
    """
    if len(raw) < 4 or raw[0] != 0 or raw[1] not in (0, 1):  # CDR_BE = 00 00, CDR_LE = 00 01
        return None
    u32 = struct.Struct('<I' if raw[1] == 1 else '>I')
    body = memoryview(raw)[4:]  # CDR alignment counts from here

    def length_at(pos: int) -> tuple[int, int]:  # (uint32 at pos aligned to 4, next position)
        pos += -pos % 4
        return u32.unpack_from(body, pos)[0], pos + 4

    try:
        frame_id, pos = length_at(8)  # after header.stamp (int32 sec, uint32 nanosec)
        names, pos = length_at(pos + frame_id)
        if names > MAX_SCANNED_NAMES:
            return names, None
        for _ in range(names):
            size, pos = length_at(pos)
            pos += size
        points, pos = length_at(pos)
    except struct.error:
        return None
    return names, points


def too_long_message(points: int, limit: int) -> str | None:
    """Why a trajectory of ``points`` points exceeds ``limit`` (max_trajectory_points), or None."""
    if points > limit:
        return (
            f'{points} points, more than max_trajectory_points = {limit}'
            ' (split it or raise the parameter)'
        )
    return None


def decode_trajectory(raw: bytes, max_points: int) -> JointTrajectory:
    """Deserialise a raw /joint_trajectory message, rejecting an oversized one unread.

    The lengths are read first (:func:`trajectory_size`): more than ``max_points`` points, or more
    joint names than :data:`MAX_SCANNED_NAMES`, is rejected without deserialising.

    Args:
        raw: the message as a raw subscription receives it.
        max_points: the ``max_trajectory_points`` parameter [-].

    Raises:
        TrajectoryError: why the trajectory is rejected (the node logs it).
    """
    size = trajectory_size(raw)
    if size is not None:
        names, points = size
        if points is None:
            raise TrajectoryError(f'{names} joint names, the arm has {len(ARM_JOINTS)}')
        if why := too_long_message(points, max_points):
            raise TrajectoryError(why)
    try:
        msg = rclpy.serialization.deserialize_message(raw, JointTrajectory)
    except Exception as err:  # garbage bytes must not kill the node
        raise TrajectoryError(f'cannot deserialise: {err}') from err
    if why := too_long_message(len(msg.points), max_points):
        raise TrajectoryError(why)
    return msg
