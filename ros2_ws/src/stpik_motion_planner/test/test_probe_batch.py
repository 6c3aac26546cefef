"""The sampler's batched hand probes (#28) answer and log as one probe query per part and world.

:meth:`CartesianSampler._hits` culls all the hand's parts in one call per world and runs the
narrow phase per part; the reference here is the per-part loop it replaced: per part, a fresh
fcl object, :meth:`SceneWorld.probe_hits` against the scene, then against the movable bodies
with the wider margin. Both must give the same ids and the same :class:`SceneQuery` logs, in
the same order, bit for bit (the memos and footprints replay those logs).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import fcl
import numpy as np
import pinocchio as pin
import pytest
from qtree_scene.scenario import load_scenario
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.cartesian_path import CartesianSampler, grasp_rotation
from stpik_motion_planner.collision import (
    PROBE_SLACK_M,
    ProbeSet,
    SceneQuery,
    SceneWorld,
    probe_distance,
)
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.hand_model import HandModel
from stpik_motion_planner.kernels import scene_candidates

CONFIG = PlannerConfig()
WIDER_M = CONFIG.obstacle_activation_m - CONFIG.position_tolerance_m  # the corridor's margin


@pytest.fixture(scope='module')
def hand(robot) -> HandModel:
    return HandModel(robot, CONFIG.pregrasp_standoff_m)


def _cluttered() -> list[ObjectSpec]:
    """Boxes (turned) and cylinders 6-10 cm apart around x = 0.55 m, on a table."""
    table = ObjectSpec('table', 'static', 'box', (0.5, 0.0, -0.02), yaw=0.0, size=(1, 1.2, 0.04))
    objects = [table]
    for i, (x, y) in enumerate([(0.55, 0.0), (0.62, 0.08), (0.48, -0.09), (0.6, -0.1)]):
        objects.append(ObjectSpec(f'C{i}', 'obstacle', 'cylinder', (x, y, 0.07), 0.0, 0.03, 0.14))
    for i, (x, y, yaw) in enumerate([(0.5, 0.1, 0.4), (0.68, -0.02, -0.7)]):
        objects.append(
            ObjectSpec(f'B{i}', 'obstacle', 'box', (x, y, 0.05), yaw=yaw, size=(0.05, 0.07, 0.1))
        )
    return objects


def _scenes() -> dict[str, list[ObjectSpec]]:
    scenes = {name: list(load_scenario(name).objects) for name in ('s1', 's2', 's3')}
    scenes['cluttered'] = _cluttered()
    return scenes


def _poses(objects: list[ObjectSpec], rng: np.random.Generator) -> list[pin.SE3]:
    """Side grasps at every movable object (several yaws and heights), and random poses."""
    poses = []
    for obj in objects:
        if obj.role == 'static':
            continue
        for _ in range(3):
            yaw = math.atan2(obj.position[1], obj.position[0]) + rng.uniform(-0.6, 0.6)
            z = obj.position[2] + rng.uniform(-0.03, 0.05)
            poses.append(pin.SE3(grasp_rotation(yaw), np.array([*obj.position[:2], z])))
    for _ in range(10):
        rotation = pin.exp3(rng.uniform(-math.pi, math.pi, 3))
        poses.append(pin.SE3(rotation, rng.uniform([0.3, -0.3, 0.0], [0.8, 0.3, 0.3])))
    return poses


def _per_part(
    sampler: CartesianSampler, parts: dict, spheres: dict, pose: pin.SE3, wider: float | None
) -> list[str]:
    """The committed per-part loop: one probe_hits per part and world."""
    rotation, translation = pose.rotation, pose.translation
    transform = fcl.Transform(rotation, translation)
    margin = sampler.config.obstacle_min_distance_m
    hit: list[str] = []
    for name, geometry in parts.items():
        body = fcl.CollisionObject(geometry, transform)
        centre, radius = spheres[name]
        world_centre = rotation @ centre + translation
        hit += sampler.scene.probe_hits(body, world_centre, radius, margin, geometry)
        if wider is not None and wider > margin:
            hit += sampler.movable.probe_hits(body, world_centre, radius, wider, geometry)
    return sorted(set(hit))


def _logged(
    sampler: CartesianSampler, run: Callable[..., list[str]], *args: Any
) -> tuple[list[str], list[SceneQuery], tuple]:
    """``run(*args)``'s result, the queries of both worlds in one log (their interleaving),
    and each world's own log.
    """
    both: list[SceneQuery] = []
    own: tuple[list[SceneQuery], list[SceneQuery]] = ([], [])
    sampler.scene.recorders[:] = [both, own[0]]
    sampler.movable.recorders[:] = [both, own[1]]
    try:
        hits = run(*args)
    finally:
        sampler.scene.recorders.clear()
        sampler.movable.recorders.clear()
    return hits, both, own


def _assert_same_query(a: SceneQuery, b: SceneQuery) -> None:
    for field in ('centres', 'radii', 'rows'):
        x, y = getattr(a, field), getattr(b, field)
        assert (x.dtype, x.shape, x.tobytes()) == (y.dtype, y.shape, y.tobytes()), field
    assert (a.threshold, a.inclusive) == (b.threshold, b.inclusive)
    assert a.objects == b.objects and a.hits == b.hits
    assert a.probe is not None and b.probe is not None
    assert a.probe[0] is b.probe[0]
    pose_a, pose_b = a.probe[1], b.probe[1]
    assert pose_a.getRotation().tobytes() == pose_b.getRotation().tobytes()
    assert pose_a.getTranslation().tobytes() == pose_b.getTranslation().tobytes()


def _assert_query_is_its_own_cull(world: SceneWorld, query: SceneQuery) -> None:
    """The query's objects are the single-probe cull's; its hits, every object within reach."""
    rows, objects = scene_candidates(
        np.ascontiguousarray(query.centres),
        np.ascontiguousarray(query.radii),
        np.zeros(1, dtype=np.int64),
        world.centres,
        world.cos,
        world.sin,
        world.half,
        query.threshold,
        False,
    )
    assert query.objects == tuple(world.specs[o] for o in objects)
    assert np.array_equal(query.rows, rows)
    assert query.probe is not None
    geometry, pose = query.probe
    near = tuple(s for s in world.specs if probe_distance(s, geometry, pose) < query.threshold)
    assert query.hits == near


@pytest.mark.parametrize('scene_name', ['s1', 's2', 's3', 'cluttered'])
def test_batched_hand_probes_give_the_per_part_hits_and_logs(hand, scene_name) -> None:
    objects = _scenes()[scene_name]
    sampler = CartesianSampler(SceneWorld(objects), CONFIG, hand)
    rng = np.random.default_rng(28)
    cases = [
        (sampler.swept_probes, hand.swept, hand.swept_spheres, WIDER_M),
        (sampler.at_pose_probes, hand.at_pose, hand.at_pose_spheres, None),
    ]
    seen = {'hits': 0, 'queries': 0, 'several_candidates': 0, 'no_candidate': 0}
    for pose in _poses(objects, rng):
        for probes, parts, spheres, wider in cases:
            new = _logged(sampler, sampler._hits, probes, pose, wider)
            old = _logged(sampler, _per_part, sampler, parts, spheres, pose, wider)
            assert new[0] == old[0]
            worlds = 2 if wider is not None else 1
            assert len(new[1]) == len(old[1]) == worlds * len(parts)
            for a, b in zip(new[1], old[1], strict=True):
                _assert_same_query(a, b)
            for world, log_new, log_old in zip(
                (sampler.scene, sampler.movable), new[2], old[2], strict=True
            ):
                mine = {id(q) for q in log_new}
                assert [id(q) for q in log_new] == [id(q) for q in new[1] if id(q) in mine]
                assert len(log_new) == len(log_old)
                for query in log_new:
                    _assert_query_is_its_own_cull(world, query)
            seen['hits'] += len(new[0])
            seen['queries'] += len(new[1])
            seen['several_candidates'] += sum(len(q.objects) > 1 for q in new[1])
            seen['no_candidate'] += sum(not q.objects for q in new[1])
    # The poses exercise the cull's split: hits, parts with several candidates, parts with none.
    assert all(seen.values()), seen


def test_batched_hits_need_no_recorder(hand) -> None:
    """Without recorders the batched and per-part probes give the same ids and log nothing."""
    objects = _cluttered()
    sampler = CartesianSampler(SceneWorld(objects), CONFIG, hand)
    for pose in _poses(objects, np.random.default_rng(7)):
        batched = sampler._hits(sampler.swept_probes, pose, WIDER_M)
        assert batched == _per_part(sampler, hand.swept, hand.swept_spheres, pose, WIDER_M)


def test_probe_set_radii_hold_the_slack(hand) -> None:
    probes = ProbeSet(hand.swept, hand.swept_spheres)
    assert probes.names == list(hand.swept)
    expected = [hand.swept_spheres[n][1] + PROBE_SLACK_M for n in probes.names]
    assert probes.radii.tolist() == expected
