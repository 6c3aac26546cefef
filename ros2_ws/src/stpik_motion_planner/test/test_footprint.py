"""The footprint of a computation (#32 item 4): what its scene queries found and could find."""

from __future__ import annotations

import dataclasses
import math

import fcl
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.collision import SceneQuery, SceneWorld, cull_half_extents
from stpik_motion_planner.footprint import Footprint

coord = st.floats(-0.6, 0.6, allow_nan=False)


def _box(x: float, y: float, yaw: float = 0.0, size=(0.06, 0.1, 0.2)) -> ObjectSpec:
    return ObjectSpec('B', 'obstacle', 'box', (x, y, 0.1), yaw=yaw, size=size)


def _ball_query(centre, radius: float, threshold: float) -> SceneQuery:
    empty = np.zeros(0, dtype=np.int64)
    return SceneQuery(np.array([centre], float), np.array([radius]), threshold, False, empty, ())


def _cull_bound(centre: np.ndarray, obj: ObjectSpec) -> float:
    """The cull's lower bound (:func:`.kernels.scene_candidates`) without its radius [m]."""
    d = centre - np.asarray(obj.position)
    c, s = math.cos(obj.yaw), math.sin(obj.yaw)
    hx, hy, hz = cull_half_extents(obj)
    x = max(abs(d[0] * c + d[1] * s) - hx, 0.0)
    y = max(abs(d[1] * c - d[0] * s) - hy, 0.0)
    z = max(abs(d[2]) - hz, 0.0)
    return math.sqrt(x * x + y * y + z * z)


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.tuples(coord, coord, st.floats(0.0, 0.5)), min_size=1, max_size=20),
    st.floats(0.01, 0.15),
    st.floats(0.0, 0.03),
    coord,
    coord,
    st.floats(-math.pi, math.pi),
)
def test_an_object_a_ball_reaches_is_never_missed(balls, radius, threshold, x, y, yaw) -> None:
    """Property: whenever some recorded ball's cull would let the object through, may_meet is
    True (the cells only widen the balls)."""
    footprint = Footprint()
    for bx, by, bz in balls:
        footprint.append(_ball_query((bx, by, bz), radius, threshold))
    region = footprint.region()
    obj = _box(x, y, yaw)
    reached = any(_cull_bound(np.array(b), obj) - radius < threshold for b in balls)
    if reached:
        assert region.may_meet(obj)


def test_far_objects_are_not_met_and_cells_are_few() -> None:
    footprint = Footprint()
    for t in np.linspace(0.0, 0.3, 301):  # a ball swept 30 cm along x at 1 mm steps
        footprint.append(_ball_query((t, 0.0, 0.2), 0.05, 0.02))  # at the box's top
    region = footprint.region()
    assert len(region.reach) <= 32  # 1 cm cells
    assert region.may_meet(_box(0.15, 0.0))  # under the sweep
    assert region.may_meet(_box(0.15, 0.12))  # its side 7 cm away: 7 cm reach + cell slack
    assert not region.may_meet(_box(0.15, 0.25))
    assert not region.may_meet(_box(0.6, 0.0))


def test_probe_queries_are_checked_exactly_and_only_hits_count_as_met() -> None:
    """A probe's answer depends on the objects it found; may_meet repeats its fcl call."""
    near = ObjectSpec('N', 'obstacle', 'cylinder', (0.0, 0.0, 0.1), radius=0.03, height=0.2)
    culled = dataclasses.replace(near, id='C', position=(0.16, 0.0, 0.1))  # in the cull only
    world = SceneWorld([near, culled])
    footprint = Footprint()
    world.recorders.append(footprint)
    sphere = fcl.Sphere(0.05)
    probe = fcl.CollisionObject(sphere, fcl.Transform(np.array([0.07, 0.0, 0.1])))
    hits = world.probe_hits(probe, np.array([0.07, 0.0, 0.1]), 0.05, 0.005, sphere)
    world.recorders.pop()
    assert hits == ['N']
    region = footprint.region()
    assert region.met == frozenset({near})  # C passed the cull, 4 cm away: not met
    assert len(region.probes) == 1 and len(region.reach) == 0
    for gap in (0.003, 0.0049, 0.0051, 0.02):  # N's surface `gap` from the probe's
        moved = dataclasses.replace(near, position=(0.07 - 0.05 - 0.03 - gap, 0.0, 0.1))
        again = SceneWorld([moved]).probe_hits(probe, np.array([0.07, 0.0, 0.1]), 0.05, 0.005)
        assert region.may_meet(moved) == bool(again) == (gap < 0.005)


def test_a_lost_part_makes_the_footprint_incomplete() -> None:
    footprint = Footprint()
    footprint.append(_ball_query((0.0, 0.0, 0.0), 0.05, 0.0))
    assert footprint.region().complete
    footprint.lose('a memo result without its queries')
    assert not footprint.region().complete
    assert footprint.why_incomplete == 'a memo result without its queries'
