"""End-effector position and orientation task (Sect. 4, task 4): an equality task."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from stpik_motion_planner.tasks.task import Kinematics, Task, TaskRows


def pose_error(world_target: pin.SE3, world_ee: pin.SE3) -> np.ndarray:
    """σ̃ = [p_d − p; log3(R_d Rᵀ)] in world axes, shape (6,) ([m], [rad])."""
    position = world_target.translation - world_ee.translation
    rotation = pin.log3(world_target.rotation @ world_ee.rotation.T)
    return np.concatenate([position, rotation])


class EePoseTask(Task):
    """Track ``target`` (EE pose in the world frame) with the LOCAL_WORLD_ALIGNED Jacobian."""

    name = 'ee_pose'

    def __init__(self, target: pin.SE3 | None = None, gain: float = 1.0) -> None:
        super().__init__(gain)
        self.target = target if target is not None else pin.SE3.Identity()

    def compute(self, k: Kinematics) -> TaskRows:
        """Rows (J_ee (6, 7), K σ̃ (6,))."""
        jacobian = pin.getFrameJacobian(k.model, k.data, k.ee_frame, pin.LOCAL_WORLD_ALIGNED)
        error = pose_error(self.target, k.world_ee)
        return TaskRows(jacobian, self.gain * error, ('x', 'y', 'z', 'rx', 'ry', 'rz'))
