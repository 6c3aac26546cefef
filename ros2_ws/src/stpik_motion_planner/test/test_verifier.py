"""TrajectoryVerifier: catches collisions between samples, limit violations and self-hits."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from jaco2_description.model import ARM_JOINTS, HOME
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.verifier import RESOLUTION_M, Carried, TrajectoryVerifier

# Layouts before #31 re-laid S1-S3: the regressions below were measured on them.
SCENES = pathlib.Path(__file__).parent / 'scenes'

HOME_Q = np.asarray(HOME)
TABLE = ObjectSpec('table', 'static', 'box', (0.35, 0.0, -0.025), size=(1.2, 1.4, 0.05))


@pytest.fixture(scope='module')
def verifier(robot) -> TrajectoryVerifier:
    return TrajectoryVerifier(robot)


def test_collision_between_two_clear_samples_is_found(verifier, robot):
    q_a = HOME_Q.copy()
    q_b = HOME_Q.copy()
    q_b[0] += 1.2  # joint 1 swings the hand on an arc
    mid = robot.ee_pose((q_a + q_b) / 2).translation
    post = ObjectSpec('post', 'obstacle', 'cylinder', tuple(mid), radius=0.02, height=0.05)
    ends = verifier.verify(np.array([q_a, q_a, q_b, q_b]), [post, TABLE])
    # Both samples clear the post, the motion between them does not.
    for q in (q_a, q_b):
        assert verifier.verify(q[None], [post, TABLE]).ok
    assert not ends.ok
    hit = ends.scene_collisions[0]
    assert hit.name_b == 'post' and 1.0 < hit.index < 2.0 and hit.value < 0.0
    assert ends.max_gap_m <= RESOLUTION_M + 1e-12


def test_joint_limit_violation_is_reported(verifier):
    q = np.array([HOME_Q, HOME_Q])
    q[1, 1] = 0.75  # joint 2 below its 0.820 rad limit
    report = verifier.verify(q, [])
    assert [(v.name_a, v.name_b) for v in report.limit_violations] == [(ARM_JOINTS[1], 'lower')]
    assert report.limit_violations[0].value == pytest.approx(0.820305 - 0.75, abs=1e-6)


def test_continuous_joints_are_unbounded(verifier):
    q = np.array([HOME_Q, HOME_Q])
    q[1, [0, 2, 4, 6]] += 3 * np.pi  # beyond ±2π on joints 1, 3, 5, 7
    report = verifier.verify(q, [])
    assert not report.limit_violations


def test_self_hit_is_found_on_every_model_pair(verifier, robot):
    rng = np.random.default_rng(3)
    lower, upper = robot.limits.lower, robot.limits.upper
    for _ in range(5000):
        q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi + 2))
        distances = robot.self_collision_distances(q)
        if np.min(distances) < -0.005:
            break
    else:
        pytest.fail('no self-colliding configuration sampled')
    i, j = robot.self_collision_pairs[int(np.argmin(distances))]
    report = verifier.verify(q[None], [])
    names = {(v.name_a, v.name_b) for v in report.self_collisions}
    links = robot.collision_links
    assert (links[i], links[j]) in names or (links[j], links[i]) in names


def test_carried_object_moves_with_the_hand_and_is_checked(verifier, robot):
    q_a = HOME_Q.copy()
    q_b = HOME_Q.copy()
    q_b[0] += 0.8
    ee_a, ee_b = robot.ee_pose(q_a), robot.ee_pose(q_b)
    hanging = ee_a.translation + np.array([0.0, 0.0, -0.25])  # 25 cm below the hand
    obj = ObjectSpec('C', 'obstacle', 'cylinder', tuple(hanging), radius=0.02, height=0.08)
    carried_at_b = (ee_b * ee_a.inverse()).act(hanging)
    post = ObjectSpec(
        'post', 'obstacle', 'cylinder', tuple(carried_at_b), radius=0.02, height=0.05
    )
    traj = np.array([q_a, q_b])
    assert verifier.verify(traj, [post]).ok  # the arm alone clears the post
    held = verifier.verify(traj, [post], Carried(obj, 0, 1))
    assert [(v.name_a, v.name_b) for v in held.scene_collisions] == [('carried', 'post')]
    assert held.scene_collisions[0].index == pytest.approx(1.0, abs=0.2)
    # Released at once: the object stays where it was and nothing touches the post.
    assert verifier.verify(traj, [post], Carried(obj, 0, 0)).ok


def test_bad_trajectory_shapes_are_refused(verifier):
    with pytest.raises(ValueError, match='shape'):
        verifier.verify(np.zeros((3, 6)), [])
    with pytest.raises(ValueError, match='non-finite'):
        verifier.verify(np.full((2, 7), np.nan), [])
    with pytest.raises(ValueError, match='outside the trajectory'):
        obj = ObjectSpec('C', 'obstacle', 'cylinder', (0.5, 0, 0.05), radius=0.03, height=0.1)
        verifier.verify(np.zeros((2, 7)), [], Carried(obj, 1, 5))


def test_a_motion_far_from_everything_is_proven_free_without_densifying(verifier):
    """Conservative advancement: distances at the two samples bound every pair's distance on the
    segment, so a clear swing needs no configuration between them (uniform 1 cm densification
    checked dozens), while the same swing through a post is still caught (test above)."""
    q_a = HOME_Q.copy()
    q_b = HOME_Q.copy()
    q_b[0] += 0.3
    far = ObjectSpec('far', 'obstacle', 'cylinder', (-0.6, -0.6, 0.05), radius=0.02, height=0.1)
    report = verifier.verify(np.array([q_a, q_b]), [far])
    assert report.ok and report.checked == 2


def _carried_over(robot, post_top_below_bottom_m: float, role: str = 'obstacle'):
    """A carried cylinder 25 cm below the hand, swung 0.8 rad by joint 1, and a box whose top is
    ``post_top_below_bottom_m`` [m] below the carried object's bottom where it ends (< 0: the box
    reaches that far into the object's bottom slice)."""
    q_a, q_b = HOME_Q.copy(), HOME_Q.copy()
    q_b[0] += 0.8
    ee_a, ee_b = robot.ee_pose(q_a), robot.ee_pose(q_b)
    hanging = ee_a.translation + np.array([0.0, 0.0, -0.25])
    obj = ObjectSpec('C', 'obstacle', 'cylinder', tuple(hanging), radius=0.02, height=0.08)
    end = (ee_b * ee_a.inverse()).act(hanging)
    top = end[2] - 0.04 - post_top_below_bottom_m
    post = ObjectSpec(role, role, 'box', (end[0], end[1], top - 0.05), size=(0.2, 0.2, 0.1))
    return np.array([q_a, q_b]), post, Carried(obj, 0, 1)


def test_the_whole_carried_object_is_checked_against_other_objects(robot):
    """#29 point 1: the bottom 12 mm of the carried object were unchecked against everything,
    so an object reaching 6 mm into it passed; only its support surfaces keep that slice."""
    verifier = TrajectoryVerifier(robot)
    traj, post, carried = _carried_over(robot, -0.006)
    report = verifier.verify(traj, [post], carried)
    assert [(v.name_a, v.name_b) for v in report.scene_collisions] == [('carried', 'obstacle')]
    assert report.scene_collisions[0].value == pytest.approx(-0.006, abs=1e-3)
    traj, table, carried = _carried_over(robot, -0.006, role='static')
    assert verifier.verify(traj, [table], carried).ok  # set down on a support: tolerated


def test_the_planner_proves_the_executors_stop_distance(robot):
    """A pair 2 mm apart is contact-free but inside the executor's stop distance (3 mm)."""
    from stpik_motion_planner.config import PlannerConfig
    from stpik_motion_planner.execution_config import ExecutionConfig
    from stpik_motion_planner.verifier import STOP_CLEARANCE_M

    assert (
        pytest.approx(
            PlannerConfig().obstacle_min_distance_m - ExecutionConfig().margin_tolerance_m
        )
        == STOP_CLEARANCE_M
    )
    from qtree_scene.scenario import load_scenario
    from stpik_motion_planner.planner import MotionPlanner

    # The planner's own verifier (it checked at clearance_m=0 before #29).
    assert MotionPlanner(load_scenario('s1'), model=robot).verifier.clearance_m == STOP_CLEARANCE_M
    traj, post, carried = _carried_over(robot, 0.002)
    assert TrajectoryVerifier(robot).verify(traj, [post], carried).ok
    strict = TrajectoryVerifier(robot, clearance_m=STOP_CLEARANCE_M).verify(traj, [post], carried)
    assert not strict.ok and strict.scene_collisions[0].value == pytest.approx(0.002, abs=1e-3)
    clear = TrajectoryVerifier(robot, clearance_m=STOP_CLEARANCE_M)
    traj, post, carried = _carried_over(robot, 0.02)
    report = clear.verify(traj, [post], carried)
    # The smallest pair distance (a self pair of the arm here) is reported, above 3 mm.
    assert report.ok and STOP_CLEARANCE_M < report.min_distance_m < 0.021


def test_the_smallest_distance_is_exact_and_the_motion_bounds_are_sound(robot) -> None:
    """#28: the smallest distance the verifier reports is the exact one over every pair it
    checks at every sample (it was a bounding-sphere bound: 7.8 mm reported where the exact
    minimum is 12 mm on a trajectory of s1 over the table alone), and no pair gets closer along
    a segment than its motion bound (what conservative advancement relies on)."""
    import pinocchio as pin
    from qtree_scene.scenario import load_scenario
    from stpik_motion_planner.planner import MotionPlanner
    from stpik_motion_planner.verifier import STOP_CLEARANCE_M

    planner = MotionPlanner(load_scenario(str(SCENES / 's1_before_31.yaml')), model=robot)
    result = planner.check('O4', [])
    assert result.feasible, result.message
    q = np.asarray(result.joint_trajectory)
    obj = next(o for o in planner.scenario.objects if o.id == 'O4')
    standing = list(planner.scenario.statics)  # as a blocker sweep checks it: the table
    carried = Carried(obj, result.grasp_index, result.release_index)
    checker = TrajectoryVerifier(robot, clearance_m=STOP_CLEARANCE_M)
    report = checker.verify(q, standing, carried)
    gm, _names, reach, _kinds, masks = checker._build(
        standing, carried, q[carried.grasp_index], q[carried.release_index]
    )
    gd = pin.GeometryData(gm)
    exact = []
    for i in range(len(q)):
        pin.updateGeometryPlacements(checker.model, checker.data, gm, gd, q[i])
        exact.append(
            [pin.computeDistance(gm, gd, k).min_distance for k in range(len(masks['before']))]
        )
    exact = np.array(exact)
    # no pair's distance changes between samples by more than its motion bound
    assert np.all(np.abs(np.diff(exact, axis=0)) <= checker.motion_bounds(q, reach) + 1e-5)

    def phase(i: int) -> str:
        return (
            'before'
            if i < carried.grasp_index
            else 'carry'
            if i <= carried.release_index
            else 'after'
        )

    smallest = min(
        float(np.min(np.where(masks[phase(i)], exact[i], np.inf))) for i in range(len(q))
    )
    assert report.ok and report.min_distance_m == pytest.approx(smallest, abs=1e-9)
