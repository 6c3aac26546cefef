"""Issue #28: the faster hot path gives the answers of the slower one (no ROS import)."""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
import pytest
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import MotionPlannerError, PlanningTimeout
from stpik_motion_planner.robust_stpik import RobustStpik


def _kinematic_valid(stpik: RobustStpik, q: np.ndarray, scene: SceneWorld) -> bool:
    """The validity check before #28: every pair :meth:`kinematics` finds (those within the
    activation distances) beyond its activation distance (#29: the RRT keeps those)."""
    if np.any(q < stpik.lower) or np.any(q > stpik.upper):
        return False
    k = stpik.kinematics(q, scene)
    c = stpik.config
    return all(p.distance > c.self_activation_m for p in k.self_pairs) and all(
        p.distance > c.obstacle_activation_m for p in k.scene_pairs
    )


@pytest.fixture
def setup(robot, make_scenario, make_cylinder):
    scenario = make_scenario(make_cylinder('a', 0.45, 0.0), make_cylinder('b', 0.35, 0.2))
    return RobustStpik(robot, PlannerConfig()), SceneWorld(scenario.objects), scenario


def test_collision_only_validity_equals_the_kinematic_one(setup):
    stpik, scene, scenario = setup
    rng = np.random.default_rng(3)
    home = np.asarray(scenario.home, dtype=float)
    answers = []
    for _ in range(300):
        q = home + rng.normal(0.0, 1.0, 7)
        answers.append(stpik.valid(q, scene))
        assert answers[-1] == _kinematic_valid(stpik, q, scene)
    assert any(answers) and not all(answers)  # both kinds of configuration were asked


def test_rrt_past_the_deadline_is_a_timeout(setup):
    stpik, scene, scenario = setup
    home = np.asarray(scenario.home, dtype=float)
    with pytest.raises(PlanningTimeout):
        stpik.rrt(home, home + 0.1, scene, deadline=time.perf_counter() - 1.0)


def test_fallback_pass_reuses_the_plain_pass_answer(setup, robot):
    stpik, scene, scenario = setup
    home = np.asarray(scenario.home, dtype=float)
    target = pin.SE3(robot.ee_pose(home))
    target.translation = target.translation + np.r_[0.0, 0.0, 5.0]  # out of reach
    calls = []
    original = type(stpik).__mro__[1].converge

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    type(stpik).__mro__[1].converge = counted
    try:
        with stpik.plain(), pytest.raises(MotionPlannerError) as first:
            stpik.converge(home, target, scene)
        assert len(calls) == 1
        with pytest.raises(MotionPlannerError) as again:
            stpik.converge(home, target, scene)  # fallbacks on: the plain solve is not re-run
        assert len(calls) == 1 + stpik.config.ik_restarts
        assert str(again.value) == str(first.value)  # restarts fail too: the first error
        stpik.forget()
        with stpik.plain(), pytest.raises(MotionPlannerError):
            stpik.converge(home, target, scene)
        assert len(calls) == 2 + stpik.config.ik_restarts
    finally:
        type(stpik).__mro__[1].converge = original
