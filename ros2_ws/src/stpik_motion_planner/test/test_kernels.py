"""Issue #28: each compiled kernel gives what the numpy / Pinocchio code it replaced gave."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from hypothesis import given, settings
from hypothesis import strategies as st
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.kernels import (
    chain_placements,
    replay_candidates,
    scene_candidates,
    self_candidates,
    solve_levels,
)
from stpik_motion_planner.stpik import RANK_TOLERANCE, Stpik, damped_pinv, pinv_pair

SEEDS = st.integers(0, 2**32 - 1)


def _numpy_hierarchy(levels, n, damping, threshold):
    """Eq. (6) as the planner computed it before #28 (numpy, two pseudo-inverses per level)."""
    dq, N = np.zeros(n), np.eye(n)
    used = [(J, e) for J, e in levels if len(e)]
    for index, (J, e) in enumerate(used):
        JN = J @ N
        if index == len(used) - 1:
            return dq + damped_pinv(JN, damping, threshold) @ (e - J @ dq)
        damped, truncated = pinv_pair(JN, damping, threshold)
        dq = dq + damped @ (e - J @ dq)
        N = N - truncated @ JN
    return dq


@settings(max_examples=40, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(SEEDS)
def test_chain_placements_equal_pinocchio(robot, seed):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, 7)
    stpik = Stpik(robot, PlannerConfig())
    joints, placements = chain_placements(q, *stpik._chain)
    data, gdata = stpik.model.createData(), pin.GeometryData(stpik.geometry_model)
    pin.forwardKinematics(stpik.model, data, q)
    pin.updateGeometryPlacements(stpik.model, data, stpik.geometry_model, gdata)
    for j in range(stpik.model.njoints):
        assert np.allclose(joints[j], data.oMi[j].homogeneous, atol=1e-12)
    for g, placement in enumerate(gdata.oMg):
        assert np.allclose(placements[g], placement.homogeneous, atol=1e-12)
    # The EE pose the carried object moves with: the EE frame's Pinocchio placement.
    pin.updateFramePlacements(stpik.model, data)
    ee = joints[stpik._ee_joint] @ stpik._ee_in_joint
    assert np.allclose(ee, data.oMf[stpik.ee_frame].homogeneous, atol=1e-12)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(SEEDS, st.floats(-0.05, 0.3), st.booleans())
def test_self_candidates_are_the_pairs_the_sphere_bound_keeps(seed, threshold, inclusive):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-0.5, 0.5, (9, 3))
    radii = rng.uniform(0.0, 0.15, 9)
    a, b = np.triu_indices(9, 1)
    a, b = a.astype(np.int64), b.astype(np.int64)
    gap = np.linalg.norm(centres[a] - centres[b], axis=1) - (radii[a] + radii[b])
    expected = np.flatnonzero(gap <= threshold if inclusive else gap < threshold)
    got = self_candidates(centres, radii, a, b, threshold, inclusive)
    assert np.array_equal(got, expected)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(SEEDS, st.floats(-0.05, 0.3), st.booleans())
def test_scene_candidates_are_the_pairs_the_box_bound_keeps(seed, threshold, inclusive):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-0.6, 0.6, (8, 3))
    radii = rng.uniform(0.0, 0.12, 8)
    bodies = np.array([2, 3, 5, 7], dtype=np.int64)
    objects = rng.uniform(-0.6, 0.6, (6, 3))
    yaw = rng.uniform(-np.pi, np.pi, 6)
    half = rng.uniform(0.01, 0.1, (6, 3))
    cos, sin = np.cos(yaw), np.sin(yaw)
    # The numpy bound before #28 (RobotBodies._scene_bounds).
    delta = centres[bodies][:, None, :] - objects[None]
    x = delta[..., 0] * cos + delta[..., 1] * sin
    y = delta[..., 1] * cos - delta[..., 0] * sin
    local = np.stack([x, y, delta[..., 2]], axis=-1)
    bound = np.linalg.norm(np.maximum(np.abs(local) - half[None], 0.0), axis=-1)
    bound -= radii[bodies][:, None]
    expected = np.nonzero(bound <= threshold if inclusive else bound < threshold)
    rows, objs = scene_candidates(
        centres, radii, bodies, objects, cos, sin, half, threshold, inclusive
    )
    # Bit-level rounding may differ: every pair further than 1e-12 from the threshold agrees.
    clear = np.abs(bound - threshold) > 1e-12
    got = {(int(r), int(o)) for r, o in zip(rows, objs, strict=True) if clear[r, o]}
    assert got == {(int(r), int(o)) for r, o in zip(*expected, strict=True) if clear[r, o]}
    assert list(zip(rows, objs, strict=True)) == sorted(zip(rows, objs, strict=True))  # body-major


@settings(max_examples=60, deadline=None, derandomize=True)
@given(SEEDS, st.lists(st.integers(0, 7), min_size=1, max_size=4), st.sampled_from([1e-3, 0.05]))
def test_solve_levels_equals_the_numpy_hierarchy(seed, dims, damping):
    rng = np.random.default_rng(seed)
    levels = [(rng.normal(size=(m, 7)), rng.normal(size=m)) for m in dims]
    if rng.random() < 0.3 and dims[0]:  # a rank-deficient first level (damping acts)
        levels[0] = (np.repeat(levels[0][0][:1], dims[0], axis=0), levels[0][1])
    expected = _numpy_hierarchy(levels, 7, damping, 0.05)
    starts = np.r_[0, np.cumsum(dims)].astype(np.int64)
    jacobian = np.ascontiguousarray(np.vstack([J for J, _ in levels]))
    error = np.ascontiguousarray(np.concatenate([e for _, e in levels]))
    got = solve_levels(jacobian, error, starts, damping, 0.05, RANK_TOLERANCE)
    assert np.allclose(got, expected, atol=1e-9, rtol=1e-9)


def test_bodies_placed_by_the_kernel_find_the_pinocchio_distances(
    robot, make_scenario, make_cylinder
):
    """The collision bodies placed from the kernel's placements report, at random
    configurations, the distances of bodies placed from Pinocchio's, to 10 µm: fcl's GJK on
    cylinders iterates to about 1e-6 m, so a rounding-level move can shift its answer so much."""
    from stpik_motion_planner.collision import RobotBodies

    stpik = Stpik(robot, PlannerConfig())
    scenario = make_scenario(make_cylinder('a', 0.45, 0.0), make_cylinder('b', 0.35, 0.2))
    scene = SceneWorld(scenario.objects)
    reference = RobotBodies(
        stpik.geometry_model, robot.collision_links, robot.self_collision_pairs
    )
    data, gdata = stpik.model.createData(), pin.GeometryData(stpik.geometry_model)
    rng = np.random.default_rng(5)
    compared = 0
    for _ in range(50):
        q = np.asarray(scenario.home) + rng.normal(0.0, 0.8, 7)
        stpik.place_bodies(q)
        pin.forwardKinematics(stpik.model, data, q)
        pin.updateFramePlacements(stpik.model, data)
        pin.updateGeometryPlacements(stpik.model, data, stpik.geometry_model, gdata)
        reference.place(
            np.array([m.homogeneous for m in gdata.oMg]), data.oMf[stpik.ee_frame].homogeneous
        )
        for ours, theirs in (
            (stpik.bodies.self_proximities(0.1), reference.self_proximities(0.1)),
            (stpik.bodies.scene_proximities(scene, 0.2), reference.scene_proximities(scene, 0.2)),
        ):
            assert [(p.name_a, p.name_b) for p in ours] == [(p.name_a, p.name_b) for p in theirs]
            for p, r in zip(ours, theirs, strict=True):
                assert abs(p.distance - r.distance) < 1e-5  # GJK tolerance of cylinders
                compared += 1
    assert compared > 50  # close pairs were really compared


def test_may_activate_is_false_only_where_a_task_gives_no_row(robot, make_scenario, make_cylinder):
    """The STPIK step skips a set-based task when ``may_activate`` is False (#28): at random
    configurations near the scene, that happens only where ``compute`` gives no row, and
    each task does give rows somewhere (so the comparison is not vacuous)."""
    stpik = Stpik(robot, PlannerConfig())
    scenario = make_scenario(make_cylinder('a', 0.45, 0.0), make_cylinder('b', 0.35, 0.2))
    scene = SceneWorld(scenario.objects)
    rng = np.random.default_rng(11)
    activated = dict.fromkeys(('joint_limits', 'self_hit', 'obstacles'), 0)
    for _ in range(300):
        q = np.asarray(scenario.home) + rng.normal(0.0, 1.2, 7)
        k = stpik.kinematics(q, scene)
        for task in (stpik.joint_limits, stpik.self_hit, stpik.obstacles):
            rows = task.compute(k).dim
            assert task.may_activate(k) or rows == 0
            activated[task.name] += bool(rows)
    assert all(activated.values()), activated


@settings(max_examples=40, deadline=None, derandomize=True)
@given(SEEDS)
def test_replay_candidates_are_each_querys_scene_candidates(seed):
    """#28 replay memo: the batched cull gives, per logged query, the pairs of its own cull."""
    rng = np.random.default_rng(seed)
    n, k = 5, 4
    centres = rng.uniform(-0.6, 0.6, (n, k, 3))
    radii = rng.uniform(0.0, 0.12, (n, k))
    thresholds = rng.uniform(-0.05, 0.3, n)
    inclusive = rng.uniform(size=n) < 0.5
    objects = rng.uniform(-0.6, 0.6, (6, 3))
    yaw = rng.uniform(-np.pi, np.pi, 6)
    half = rng.uniform(0.01, 0.1, (6, 3))
    cos, sin = np.cos(yaw), np.sin(yaw)
    query, rows, objs = replay_candidates(
        centres, radii, thresholds, inclusive, objects, cos, sin, half
    )
    for i in range(n):
        r, o = scene_candidates(
            centres[i], radii[i], np.arange(k), objects, cos, sin, half, thresholds[i],
            bool(inclusive[i]),
        )  # fmt: skip
        assert np.array_equal(rows[query == i], r) and np.array_equal(objs[query == i], o)
