"""MotionPlanner: feasibility, reasons, trajectory validity (checked independently), cache."""

from __future__ import annotations

import dataclasses
import math
import time

import fcl
import numpy as np
import pytest
from qtree_scene.generator import generate_clutter
from qtree_scene.placement import drop_slots
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.carried import carried_poses, tilt_deg
from stpik_motion_planner.collision import object_geometry, object_transform
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import InvalidConfig, InvalidRequest
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason
from stpik_motion_planner.verifier import Carried, TrajectoryVerifier


@pytest.fixture(scope='module')
def free_result(free_scene, robot):
    planner = MotionPlanner(free_scene, model=robot)
    return planner, planner.check('T', [])


def test_free_unoccluded_object_is_feasible(free_result):
    _, result = free_result
    assert result.feasible and result.reason == Reason.SUCCESS
    assert result.joint_trajectory.shape[1] == 7
    assert len(result.times) == len(result.joint_trajectory) == len(result.ee_path)
    assert np.all(np.diff(result.times) > 0)
    assert 0 < result.grasp_index < result.release_index < len(result.times) - 1
    assert set(result.timings) == {'sampling', 'stpik', 'collision', 'verify'}


def test_trajectory_starts_and_ends_home_and_grasps_the_object(free_result, robot):
    planner, result = free_result
    assert np.allclose(result.joint_trajectory[0], planner.home_q)
    assert np.allclose(result.joint_trajectory[-1], planner.home_q)
    grasp = robot.ee_pose(result.joint_trajectory[result.grasp_index])
    # EE on the cylinder axis within 1 cm, approach axis horizontal.
    assert np.linalg.norm(grasp.translation[:2] - [0.65, 0.0]) < 0.012
    assert abs(grasp.rotation[2, 2]) < 0.06


def test_trajectory_respects_limits_and_clears_the_scene(free_result, robot, free_scene):
    _, result = free_result
    traj = result.joint_trajectory
    assert np.all(traj >= robot.limits.lower) and np.all(traj <= robot.limits.upper)
    # Independent check with the model's own fcl objects against every other object.
    others = [o for o in free_scene.objects if o.id != 'T']
    bodies = [fcl.CollisionObject(object_geometry(o), object_transform(o)) for o in others]
    request = fcl.DistanceRequest()
    for q in traj:
        robot.update_fcl(q)
        for link, obj in robot.fcl_objects():
            if link.endswith(('link_base', 'link_1')):
                continue
            for body in bodies:
                assert fcl.distance(obj, body, request, fcl.DistanceResult()) > 0.0, link
    assert np.all(np.min(robot.self_collision_distances(traj[0])) > 0)


def test_boxed_in_object_is_infeasible(boxed_scene, robot):
    result = MotionPlanner(boxed_scene, model=robot).check('T', [])
    assert not result.feasible
    assert result.reason in (Reason.NO_CARTESIAN_PATH, Reason.SCENE_COLLISION)
    assert len(result.joint_trajectory) == 0


def test_relocated_objects_are_removed_from_the_scene(boxed_scene, robot):
    planner = MotionPlanner(boxed_scene, model=robot)
    result = planner.check('T', [f'O{i}' for i in range(6)])
    assert result.feasible, result.message


def test_cache_hits_on_the_same_set_in_any_order(free_result, boxed_scene, robot):
    planner = MotionPlanner(boxed_scene, model=robot)
    first = planner.check('T', ['O1', 'O0'])
    assert (planner.cache.hits, planner.cache.misses) == (0, 1)
    second = planner.check('T', ['O0', 'O1'])
    assert (planner.cache.hits, planner.cache.misses) == (1, 1)
    assert second.from_cache and not first.from_cache
    assert second.reason == first.reason


@pytest.mark.parametrize(
    ('object_id', 'relocated', 'reason'),
    [
        ('X', [], Reason.UNKNOWN_OBJECT),
        ('T', ['X'], Reason.UNKNOWN_OBJECT),
        ('O1', ['O1'], Reason.ALREADY_RELOCATED),
        ('O1', ['T'], Reason.INVALID_REQUEST),
        ('', [], Reason.INVALID_REQUEST),
        ('T', ['O1', 'O1'], Reason.INVALID_REQUEST),
        ('T', [''], Reason.INVALID_REQUEST),
        ('table', [], Reason.INVALID_REQUEST),
    ],
)
def test_bad_requests_get_their_reason(boxed_scene, robot, object_id, relocated, reason):
    planner = MotionPlanner(boxed_scene, model=robot)
    result = planner.check(object_id, relocated)
    assert (result.feasible, result.reason) == (False, reason)
    assert result.message
    assert planner.cache.misses == 0


def test_nan_scene_is_rejected(robot, make_scenario, make_cylinder):
    bad = make_scenario(make_cylinder('T', math.nan, 0.0, 'target'))
    with pytest.raises(InvalidRequest, match='non-finite') as info:
        MotionPlanner(bad, model=robot)
    assert info.value.reason == Reason.INVALID_SCENE


def test_time_limit_gives_timeout(free_scene, robot):
    planner = MotionPlanner(free_scene, PlannerConfig(time_limit_s=0.001), model=robot)
    result = planner.check('T', [])
    assert result.reason == Reason.TIMEOUT and not result.feasible
    assert len(planner.cache) == 0  # timeouts are not cached


def test_deterministic_for_a_seed(free_scene, robot):
    a = MotionPlanner(free_scene, model=robot).check('T', [])
    b = MotionPlanner(free_scene, model=robot).check('T', [])
    assert np.array_equal(a.joint_trajectory, b.joint_trajectory)


def test_config_rejects_out_of_range_values():
    with pytest.raises(InvalidConfig, match='step_m'):
        PlannerConfig(step_m=-1.0)
    with pytest.raises(InvalidConfig, match='seed'):
        dataclasses.replace(PlannerConfig(), seed=1.5)
    with pytest.raises(InvalidConfig, match='obstacle_activation_m'):
        PlannerConfig(obstacle_activation_m=0.001, obstacle_min_distance_m=0.01)


def test_every_returned_trajectory_passes_the_independent_verifier(free_result, robot):
    planner, result = free_result
    obj = planner.scenario.object('T')
    report = TrajectoryVerifier(robot).verify(
        result.joint_trajectory,
        planner.planning_scene('T', []),
        Carried(obj, result.grasp_index, result.release_index),
    )
    assert report.ok, report.summary()
    assert report.max_gap_m <= 0.01 + 1e-12
    # Released where the simulator stands it: on drop slot 0.
    release = robot.ee_pose(result.joint_trajectory[result.release_index]).translation
    slot = planner.slot_position(0, obj)
    assert np.linalg.norm(release[:2] - slot[:2]) < 0.012


def test_placed_objects_stand_in_occupied_slots_as_obstacles(boxed_scene, robot):
    planner = MotionPlanner(boxed_scene, model=robot)
    scene = planner.planning_scene('T', ['O3', 'O1'])
    ids = {o.id for o in scene}
    assert {'slot_0', 'slot_1'} <= ids and 'slot_2' not in ids and not ids & {'O1', 'O3', 'T'}
    assert scene == planner.planning_scene('T', ['O1', 'O3'])  # the set, not the order


def test_object_too_big_for_the_open_hand_is_refused(make_scenario, robot):
    big = ObjectSpec('T', 'target', 'cylinder', (0.65, 0.0, 0.07), radius=0.05, height=0.14)
    result = MotionPlanner(make_scenario(big), model=robot).check('T', [])
    assert not result.feasible and result.reason == Reason.OBJECT_TOO_BIG
    assert '100 mm across' in result.message and len(result.joint_trajectory) == 0


def test_no_free_slot_left_is_no_placement(make_scenario, make_cylinder, robot):
    dummies = [
        make_cylinder(f'D{i}', 0.85 + 0.07 * (i % 2), -0.4 + 0.07 * (i // 2)) for i in range(24)
    ]
    scene = make_scenario(make_cylinder('T', 0.6, 0.0, 'target'), *dummies)
    slots = drop_slots(scene)
    assert len(slots) < len(dummies)
    relocated = [d.id for d in dummies[: len(slots)]]
    result = MotionPlanner(scene, model=robot).check('T', relocated)
    assert not result.feasible and result.reason == Reason.NO_PLACEMENT
    assert f'room for {len(slots)}' in result.message


def test_a_scene_of_500_objects_is_answered_within_the_time_limit(robot, make_scenario):
    """#28 bad input: the largest scene SetScene accepts (500 objects) gets an answer, with its
    reason, within the time limit; a feasible one passes the verifier."""

    def pin_at(i: int) -> ObjectSpec:  # 16 mm pegs 25 mm apart, 24 per row
        xy = (0.35 + 0.025 * (i % 24), -0.3 + 0.025 * (i // 24))
        return ObjectSpec(f'O{i}', 'obstacle', 'cylinder', (*xy, 0.04), radius=0.008, height=0.08)

    pins = [pin_at(i) for i in range(499)]
    target = ObjectSpec('T', 'target', 'cylinder', (0.9, 0.35, 0.07), radius=0.03, height=0.14)
    scene = make_scenario(*pins, target)
    assert len(scene.objects) == 501  # the table is the 501st
    planner = MotionPlanner(scene, PlannerConfig(time_limit_s=3.0), model=robot)
    for object_id in ('O0', 'T', 'O250'):
        start = time.perf_counter()
        result = planner.check(object_id, [])
        assert time.perf_counter() - start < 3.0 + 1.0  # the limit, and the blocker annotation
        assert result.message and (result.feasible == (result.reason == Reason.SUCCESS))
        if result.feasible:
            report = planner.verifier.verify(
                result.joint_trajectory,
                planner.planning_scene(object_id, []),
                Carried(scene.object(object_id), result.grasp_index, result.release_index),
            )
            assert report.ok, report.summary()


def test_the_carried_object_stays_upright_within_the_tilt_limit(robot):
    """#29 point 10: the joint-line carry of O8 on this generated scene tilted the object 15.0°
    (19.6° on the benchmark's questions); the carry now holds it within the 10° limit (an
    STPIK-tracked Cartesian carry where the joint line tilts more), and the answer stays
    feasible and verified."""
    scene = generate_clutter(8, 0.2, 0, layout='uniform')
    planner = MotionPlanner(scene, model=robot)
    planner.blockers.enabled = False
    result = planner.check('O8', [])
    assert result.feasible, result.message
    tilts = [tilt_deg(p) for p in carried_poses(scene.object('O8'), result, robot)]
    assert max(tilts) <= math.degrees(planner.config.carry_tilt_limit_rad) + 1e-6
    poses = carried_poses(scene.object('O8'), result, robot)
    assert np.linalg.norm(poses[-1].translation - poses[0].translation) > 0.2  # carried away


def test_the_tilt_limit_refuses_a_carry_it_cannot_hold_upright(robot):
    """With a limit below the tracking tolerance no carry can hold it: the same question the
    default limit answers feasible (test above) is infeasible, never a tilted trajectory."""
    scene = generate_clutter(8, 0.2, 0, layout='uniform')
    planner = MotionPlanner(scene, config=PlannerConfig(carry_tilt_limit_rad=0.0), model=robot)
    planner.blockers.enabled = False
    result = planner.check('O8', [])
    assert not result.feasible
    assert result.joint_trajectory.size == 0


def test_configured_plans_with_the_config_in_the_planner_and_its_stpik(free_scene, robot):
    """The recheck's more effort (#30) reaches the STPIK solver, and is undone on an error."""
    planner = MotionPlanner(free_scene, model=robot)
    base = planner.config
    effort = base.replace(ik_restarts=20, time_limit_s=20.0)
    seen = []
    with planner.configured(effort):
        seen.append((planner.config, planner.stpik.config, planner.geometry.config))
    assert all(c is effort for c in seen[0])
    assert planner.config is base and planner.stpik.config is base
    with pytest.raises(RuntimeError), planner.configured(effort):
        raise RuntimeError('a plan that fails')
    assert planner.config is base and planner.stpik.config is base
