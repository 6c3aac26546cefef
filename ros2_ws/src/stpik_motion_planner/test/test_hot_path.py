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


def test_results_are_reused_only_where_the_scene_queries_replay(setup, robot, make_cylinder):
    """#28 replay memo: a far object added keeps the remembered solve (bit for bit the one
    computed afresh); an object in the arm's way is a new computation."""
    stpik, scene, scenario = setup
    home = np.asarray(scenario.home, dtype=float)
    target = pin.SE3(robot.ee_pose(home))
    target.translation = target.translation + np.r_[0.05, 0.0, -0.05]
    first = stpik.converge(home, target, scene)
    hits = stpik.memo_hits
    far = SceneWorld([*scenario.objects, make_cylinder('far', -0.6, -0.6)])
    again = stpik.converge(home, target, far)
    assert stpik.memo_hits == hits + 1
    fresh = RobustStpik(robot, PlannerConfig()).converge(home, target, far)
    assert np.array_equal(again, first) and np.array_equal(fresh, first)
    near_point = robot.ee_pose(first).translation
    near = SceneWorld([*scenario.objects, make_cylinder('near', *near_point[:2], h=0.8)])

    def solve(planner: RobustStpik):
        try:
            return planner.converge(home, target, near)
        except MotionPlannerError as err:
            return str(err)

    in_the_way = solve(stpik)
    assert stpik.memo_hits == hits + 1  # computed again
    expected = solve(RobustStpik(robot, PlannerConfig()))
    assert type(in_the_way) is type(expected)
    assert (
        (in_the_way == expected)
        if isinstance(expected, str)
        else np.array_equal(in_the_way, expected)
    )
