"""The planner's fallbacks (robust_stpik): RRTConnect transits, seeded IK restarts."""

from __future__ import annotations

import numpy as np
from jaco2_description.model import HOME
from qtree_benchmarks.motion.reference import REFERENCE_CONFIG
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.robust_stpik import RobustStpik


def test_rrt_transit_with_continuous_joints(robot) -> None:
    """Continuous joints have infinite limits; OMPL needs finite bounds (raised before)."""
    config = PlannerConfig(**REFERENCE_CONFIG)
    stpik = RobustStpik(robot, config)
    assert not np.all(np.isfinite(stpik.lower))  # joints 1, 3, 5, 7 are continuous
    q_a = np.asarray(HOME, dtype=float)
    q_b = q_a + np.array([0.6, -0.2, 0.4, 0.3, -0.5, 0.2, 0.8])
    path = stpik.rrt(q_a, q_b, SceneWorld([]))
    assert path is not None
    assert np.allclose(path[-1], q_b, atol=1e-6)
    steps = np.abs(np.diff(np.vstack([q_a, path]), axis=0)).max(axis=1)
    assert np.all(steps <= config.step_rad + 1e-9)


def test_ik_restarts_are_seeded_by_the_question(robot, free_scene) -> None:
    """The same target gets the same restart seeds whatever was solved before (cache by set)."""
    import pinocchio as pin
    from stpik_motion_planner.robust_stpik import _pose_seed

    pose = pin.SE3(np.eye(3), np.array([0.5, -0.1, 0.2]))
    other = pin.SE3(np.eye(3), np.array([0.5, -0.1, 0.21]))
    assert _pose_seed(0, pose) == _pose_seed(0, pin.SE3(pose))
    assert _pose_seed(0, pose) != _pose_seed(0, other) != _pose_seed(1, other)
    assert min(_pose_seed(0, pin.SE3(-np.eye(3), -pose.translation))) >= 0


def test_rrt_refuses_an_invalid_end_before_searching(robot, monkeypatch) -> None:
    """An end past a joint limit is refused without a search."""
    from stpik_motion_planner import robust_stpik

    def no_search(*_args, **_kwargs):
        raise AssertionError('RRTConnect started for an invalid end')

    monkeypatch.setattr(robust_stpik, 'RrtConnect', no_search)
    stpik = RobustStpik(robot, PlannerConfig())
    q_a = np.asarray(HOME, dtype=float)
    beyond = q_a.copy()
    beyond[1] = stpik.upper[1] + 0.1  # joint 2 past its limit
    assert stpik.rrt(q_a, beyond, SceneWorld([])) is None
