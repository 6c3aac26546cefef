"""STPIK tasks in the pink shape: one module per task, all on the :class:`Task` base."""

from stpik_motion_planner.tasks.ee_pose_task import EePoseTask
from stpik_motion_planner.tasks.joint_limit_task import JointLimitTask
from stpik_motion_planner.tasks.obstacle_task import ObstacleTask
from stpik_motion_planner.tasks.posture_task import PostureTask
from stpik_motion_planner.tasks.self_collision_task import SelfCollisionTask
from stpik_motion_planner.tasks.task import Kinematics, SetBasedTask, Task, TaskRows

__all__ = [
    'EePoseTask',
    'JointLimitTask',
    'Kinematics',
    'ObstacleTask',
    'PostureTask',
    'SelfCollisionTask',
    'SetBasedTask',
    'Task',
    'TaskRows',
]
