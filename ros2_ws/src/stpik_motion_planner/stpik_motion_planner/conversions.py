"""Message ↔ core conversions of the motion-planner node (ROS message types, no rclpy node).

Also builds the /relocate_object answer, the ``/motion_planner/events`` message and the
parameter descriptors the node declares.
"""

from __future__ import annotations

import math

import numpy as np
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import Pose, PoseArray
from jaco2_description.model import ARM_JOINTS
from qtree_msgs.msg import PlanningEvent
from qtree_msgs.srv import RelocateObject
from qtree_node_support.text import clip
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from stpik_motion_planner.result import PlanResult
from stpik_motion_planner.scene_checks import MAX_ID_CHARS, MAX_RELOCATED_IDS

EE_FRAME = 'j2s7s300_link_base'  # frame of the answered end-effector path


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


def fill_relocate_response(
    response: RelocateObject.Response, result: PlanResult, message: str
) -> RelocateObject.Response:
    """Copy ``result`` into ``response``, with ``message`` (already clipped) as its message.

    Args:
        response: the /relocate_object response to fill.
        result: the answer (times [s], joint trajectory [rad], end-effector path [m]).
        message: the answer's message, cut to the node's limit.

    Returns:
        ``response``, filled; its end-effector path is in the arm base frame.
    """
    response.feasible, response.reason = result.feasible, int(result.reason)
    response.message, response.planning_time = message, result.planning_time
    response.from_cache = result.from_cache
    response.trajectory = trajectory_msg(result.times, result.joint_trajectory)
    response.ee_path = pose_array_msg(result.ee_path, EE_FRAME)
    response.blocking_ids = list(result.blocking_ids)
    response.blocked_by_immovable = result.blocked_by_immovable
    response.approach_blocking_ids = [i for ids in result.approach_blockers for i in ids]
    response.approach_blocker_counts = [len(ids) for ids in result.approach_blockers]
    response.grasp_family = result.grasp_family
    return response


def planning_event_msg(
    stamp: Time,
    request: RelocateObject.Request,
    response: RelocateObject.Response,
    result: PlanResult,
) -> PlanningEvent:
    """The ``/motion_planner/events`` message of one answered request.

    Ids are cut to :data:`MAX_ID_CHARS` characters, at most :data:`MAX_RELOCATED_IDS` of them;
    the message and end-effector path are those of ``response``.

    Args:
        stamp: time of the answer.
        request: the /relocate_object request.
        response: its answer, filled by :func:`fill_relocate_response`.
        result: the answer as a :class:`PlanResult`.
    """
    relocated = list(request.relocated_ids)
    return PlanningEvent(
        stamp=stamp,
        object_id=clip(request.object_id, MAX_ID_CHARS),
        relocated_ids=[clip(r, MAX_ID_CHARS) for r in relocated[:MAX_RELOCATED_IDS]],
        execute=request.execute,
        feasible=result.feasible,
        reason=int(result.reason),
        message=response.message,
        planning_time=result.planning_time,
        from_cache=result.from_cache,
        ee_path=response.ee_path,
    )


def command_msg(q: np.ndarray) -> JointState:
    """sensor_msgs/JointState reference of the 7 arm joints [rad]."""
    return JointState(name=list(ARM_JOINTS), position=[float(v) for v in q])


def xyzquat_pose_msg(xyzquat: np.ndarray) -> Pose:
    """Xyz [m] + quaternion xyzw (7,) → Pose."""
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in xyzquat[:3])
    o = pose.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in xyzquat[3:])
    return pose
