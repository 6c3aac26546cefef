"""Message ↔ core conversions for the simulator node (the only module besides the node that imports
ROS message types)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Pose, Vector3
from qtree_msgs.msg import ObjectState, Scene
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from jaco2_sim.exceptions import TrajectoryError
from jaco2_sim.model import ARM_JOINTS, BASE_LINK, FINGER_JOINTS
from jaco2_sim.world import World

ROLES = {
    'target': ObjectState.ROLE_TARGET,
    'obstacle': ObjectState.ROLE_OBSTACLE,
    'static': ObjectState.ROLE_STATIC,
}
SHAPES = {'cylinder': ObjectState.SHAPE_CYLINDER, 'box': ObjectState.SHAPE_BOX}
STATUSES = {
    'in_clutter': ObjectState.STATUS_IN_CLUTTER,
    'grasped': ObjectState.STATUS_GRASPED,
    'relocated': ObjectState.STATUS_RELOCATED,
}
STATUS_NAMES = {code: name for name, code in STATUSES.items()}


def pose_msg(placement: pin.SE3) -> Pose:
    """geometry_msgs/Pose of a transform (quaternion x, y, z, w)."""
    msg = Pose()
    t = placement.translation
    msg.position.x, msg.position.y, msg.position.z = (float(v) for v in t)
    q = pin.Quaternion(placement.rotation)
    msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = (
        float(q.x),
        float(q.y),
        float(q.z),
        float(q.w),
    )
    return msg


def _vector3(values: Sequence[float]) -> Vector3:
    return Vector3(x=float(values[0]), y=float(values[1]), z=float(values[2]))


def scene_msg(world: World, stamp: Time) -> Scene:
    """qtree_msgs/Scene of the world: objects (table = STATIC box), drop zone, attached id."""
    msg = Scene()
    msg.header.stamp = stamp
    msg.header.frame_id = BASE_LINK
    msg.scenario_name = world.scenario.name
    for object_id, state in world.objects.items():
        spec = state.spec
        obj = ObjectState(id=object_id, role=ROLES[spec.role], shape=SHAPES[spec.shape])
        obj.radius, obj.height = float(spec.radius), float(spec.height)
        obj.box_size = _vector3(spec.size)
        obj.pose = pose_msg(state.pose)
        obj.status = STATUSES[state.status]
        msg.objects.append(obj)
    msg.attached_id = world.attached_id or ''
    center = np.array(world.scenario.drop_zone_center, dtype=float)
    msg.drop_zone = pose_msg(pin.SE3(np.eye(3), center))
    msg.drop_zone_size = _vector3(world.scenario.drop_zone_size)
    msg.robot_base = pose_msg(pin.SE3.Identity())
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
) -> tuple[list[str], list[float], list[list[float]], list[list[float]] | None]:
    """(joint_names, times [s], positions (N, 7), velocities (N, 7) or None) of a trajectory.

    Raises:
        TrajectoryError: velocities given on some points only.
    """
    times = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in msg.points]
    positions = [list(p.positions) for p in msg.points]
    with_velocities = [len(p.velocities) > 0 for p in msg.points]
    if any(with_velocities) and not all(with_velocities):
        raise TrajectoryError('velocities must be given on every point or on none')
    velocities = [list(p.velocities) for p in msg.points] if any(with_velocities) else None
    return list(msg.joint_names), times, positions, velocities
