"""Where the carried object is along an answer: its world pose at every sample between the
grasp and the release, its tilt from upright and where the hand released it (no ROS import).

Used by the planner's tests (the carried object stays upright, #29 point 10) and by the
benchmark's verification (:mod:`qtree_benchmarks.motion.verification`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
from qtree_scene.scene import ObjectSpec

from stpik_motion_planner.result import PlanResult


def _object_pose(obj: ObjectSpec) -> pin.SE3:
    return pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, obj.yaw), np.asarray(obj.position, dtype=float))


def carried_poses(obj: ObjectSpec, result: PlanResult, robot) -> list[pin.SE3]:
    """World poses of the carried object at every sample from the grasp to the release."""
    q = result.joint_trajectory
    in_hand = robot.ee_pose(q[result.grasp_index]).actInv(_object_pose(obj))
    return [
        robot.ee_pose(q[i]) * in_hand for i in range(result.grasp_index, result.release_index + 1)
    ]


def tilt_deg(pose: pin.SE3) -> float:
    """Angle of the object's axis from the world vertical [deg]."""
    return float(np.degrees(np.arccos(np.clip(pose.rotation[2, 2], -1.0, 1.0))))


def released(obj: ObjectSpec, result: PlanResult, robot) -> ObjectSpec:
    """``obj`` where ``result``'s hand released it (position, yaw about z)."""
    pose = carried_poses(obj, result, robot)[-1]
    yaw = float(np.arctan2(pose.rotation[1, 0], pose.rotation[0, 0]))
    return dataclasses.replace(obj, position=tuple(pose.translation), yaw=yaw)
