"""The benchmark-only reference planner's joint-space RRTConnect transit."""

from __future__ import annotations

import numpy as np
from jaco2_description.model import HOME
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.reference import REFERENCE_CONFIG, ThoroughStpik


def test_rrt_transit_with_continuous_joints(robot) -> None:
    """Continuous joints have infinite limits; OMPL needs finite bounds (raised before)."""
    config = PlannerConfig(**REFERENCE_CONFIG)
    stpik = ThoroughStpik(robot, config)
    assert not np.all(np.isfinite(stpik.lower))  # joints 1, 3, 5, 7 are continuous
    q_a = np.asarray(HOME, dtype=float)
    q_b = q_a + np.array([0.6, -0.2, 0.4, 0.3, -0.5, 0.2, 0.8])
    path = stpik._rrt(q_a, q_b, SceneWorld([]))
    assert path is not None
    assert np.allclose(path[-1], q_b, atol=1e-6)
    steps = np.abs(np.diff(np.vstack([q_a, path]), axis=0)).max(axis=1)
    assert np.all(steps <= config.step_rad + 1e-9)
