"""RRTConnect of the planner (#29): deterministic per question, activation clearance."""

from __future__ import annotations

import itertools
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jaco2_description.model import HOME
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.robust_stpik import RobustStpik
from stpik_motion_planner.rrt_connect import RrtConnect, question_seed


def _wall(q: np.ndarray) -> bool:
    """A 2-D wall at |x| < 0.2 with a gap at y < -0.8."""
    return not (abs(q[0]) < 0.2 and q[1] > -0.8)


def _search(seed: int) -> RrtConnect:
    low, high = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    return RrtConnect(_wall, low, high, np.random.default_rng(seed), 0.3, 0.01)


def test_the_same_seed_gives_the_same_path_whatever_ran_before() -> None:
    start, goal = np.array([-0.5, 0.0]), np.array([0.5, 0.0])
    first = _search(5).solve(start, goal, 2000)
    _search(7).solve(start, goal, 2000)  # another question in between
    again = _search(5).solve(start, goal, 2000)
    assert first is not None and again is not None
    assert np.array_equal(np.array(first), np.array(again))
    assert not np.array_equal(np.array(first), np.array(_search(8).solve(start, goal, 2000)))


@settings(max_examples=25, deadline=None, derandomize=True)
@given(st.integers(0, 2**32), st.floats(-0.9, -0.3), st.floats(0.3, 0.9))
def test_every_edge_of_a_found_path_is_valid(seed: int, x_a: float, x_b: float) -> None:
    search = _search(seed)
    path = search.solve(np.array([x_a, 0.5]), np.array([x_b, 0.5]), 3000)
    assert path is not None
    path = search.shortcut(path, 30)
    assert np.allclose(path[0], [x_a, 0.5]) and np.allclose(path[-1], [x_b, 0.5])
    for a, b in itertools.pairwise(path):
        for t in np.linspace(0.0, 1.0, 200):
            assert _wall(a + (b - a) * t)


def test_no_path_after_the_iteration_bound_and_a_deadline_raises() -> None:
    walled = RrtConnect(
        lambda q: abs(q[0]) >= 0.2, np.array([-1.0, -1]), np.array([1.0, 1]),
        np.random.default_rng(0), 0.3, 0.01,
    )  # fmt: skip
    assert walled.solve(np.array([-0.5, 0.0]), np.array([0.5, 0.0]), 200) is None
    late = RrtConnect(
        lambda q: abs(q[0]) >= 0.2, np.array([-1.0, -1]), np.array([1.0, 1]),
        np.random.default_rng(0), 0.3, 0.01, deadline=0.0, on_deadline=lambda: ValueError('late'),
    )  # fmt: skip
    with pytest.raises(ValueError, match='late'):
        late.solve(np.array([-0.5, 0.0]), np.array([0.5, 0.0]), 200)


def test_question_seed_is_stable_across_processes() -> None:
    code = (
        'from stpik_motion_planner.rrt_connect import question_seed; import numpy as np; '
        'print(question_seed(3, np.arange(7.0).tobytes(), "s1"))'
    )
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True)
    assert int(out.stdout) == question_seed(3, np.arange(7.0).tobytes(), 's1')


def test_the_joint_rrt_keeps_the_activation_distance(robot) -> None:
    """#29 point 2: the fallback's validity was the 5 mm safety margin while STPIK's obstacle
    task acts at 25 mm; a configuration 10 mm from an obstacle was a valid RRT state."""
    from qtree_scene.scene import ObjectSpec

    config = PlannerConfig()
    stpik = RobustStpik(robot, config)
    q = np.asarray(HOME, dtype=float)
    hand = robot.ee_pose(q).translation

    def scene_at(z: float) -> SceneWorld:
        box = ObjectSpec('B', 'obstacle', 'box', (hand[0], hand[1], z), size=(0.04, 0.04, 0.04))
        return SceneWorld([box])

    def nearest(scene: SceneWorld) -> float:
        stpik.place_bodies(q)
        return min(p.distance for p in stpik.bodies.scene_proximities(scene, 1.0))

    def lowered_to(gap_m: float) -> SceneWorld:
        """The box above the hand, lowered until its nearest arm body is ``gap_m`` away."""
        z = hand[2] + 0.3
        for _ in range(30):
            z -= nearest(scene_at(z)) - gap_m
        return scene_at(z)

    near, far = lowered_to(0.010), lowered_to(0.035)
    assert config.obstacle_min_distance_m < nearest(near) < config.obstacle_activation_m
    assert nearest(far) > config.obstacle_activation_m
    assert not stpik.valid(q, near)
    assert stpik.valid(q, far)


@given(st.integers(1, 400))
def test_bisection_order_checks_every_configuration_once(n: int) -> None:
    from stpik_motion_planner.rrt_connect import _bisection_order

    order = _bisection_order(n)
    assert sorted(order) == list(range(1, n + 1)) and order[0] == n
