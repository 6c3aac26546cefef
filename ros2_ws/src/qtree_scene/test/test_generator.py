"""generate_clutter guarantees: seeded, household sizes, target in the workspace, densities."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jaco2_description.model import HAND_OPENING_M
from qtree_scene.exceptions import ScenarioError
from qtree_scene.footprint import footprint_of, overlap
from qtree_scene.generator import X_MIN_M, footprint_area, generate_clutter, region_size
from qtree_scene.hand_access import free_yaws
from qtree_scene.layouts import CARRY_MIN_REACH_M, CLEARING_APPROACHES, in_side_grasp_workspace
from qtree_scene.scene import ObjectSpec, Scenario


def _across(o: ObjectSpec) -> float:
    return 2 * o.radius if o.shape == 'cylinder' else min(o.size[:2])


def clearing_order(scenario: Scenario) -> list[str] | None:
    """Greedy 2-D closure: remove any carryable object with a free approach until the target
    has one; the removed ids (target last), or None when it gets stuck. Exact for the 2-D model
    (removing an object never blocks an approach)."""
    standing = {o.id: o for o in [*scenario.obstacles, scenario.target]}
    order: list[str] = []
    while True:
        for oid, o in sorted(standing.items(), key=lambda kv: kv[0] != 'T'):
            carryable = (
                _across(o) <= HAND_OPENING_M
                and in_side_grasp_workspace(o.position)
                and math.hypot(*o.position[:2]) >= CARRY_MIN_REACH_M
            )
            others = [footprint_of(v) for k, v in standing.items() if k != oid]
            if carryable and free_yaws(o.position[:2], others, CLEARING_APPROACHES):
                order.append(oid)
                del standing[oid]
                if oid == 'T':
                    return order
                break
        else:
            return None


SCENES = st.tuples(
    st.integers(min_value=4, max_value=30),
    st.floats(min_value=0.1, max_value=0.35),
    st.integers(min_value=0, max_value=2**31),
)


@settings(max_examples=40, deadline=None, derandomize=True)  # the same examples every run (CI)
@given(scene=SCENES)
def test_sizes_density_and_target_placement(scene) -> None:
    n, density, seed = scene
    scenario = generate_clutter(n, density, seed)
    movable = [*scenario.obstacles, scenario.target]
    assert len(movable) == n + 1
    for o in movable:
        if o.shape == 'cylinder':
            assert 0.02 <= o.radius <= 0.05 and 0.08 <= o.height <= 0.25
        else:
            assert all(0.04 <= v <= 0.10 for v in o.size[:2]) and 0.08 <= o.size[2] <= 0.25
        assert o.position[2] == pytest.approx((o.height or o.size[2]) / 2)  # on the table
    # The footprints fill the clutter region at the requested density.
    area = sum(footprint_area(o) for o in movable)
    depth, width = region_size(area, density)
    assert area / (depth * width) == pytest.approx(density)
    for o in movable:
        x_min = X_MIN_M['accessible']
        assert x_min <= o.position[0] <= x_min + depth and abs(o.position[1]) <= width / 2
    # Target inside the side-grasp workspace, never the farthest object.
    target = scenario.target
    assert in_side_grasp_workspace(target.position)
    across = 2 * target.radius if target.shape == 'cylinder' else min(target.size[:2])
    assert across <= HAND_OPENING_M  # the open hand can close on it
    reach = [math.hypot(*o.position[:2]) for o in movable]
    assert math.hypot(*target.position[:2]) < max(reach)
    footprints = [footprint_of(o) for o in movable]
    for i, a in enumerate(footprints):
        assert not any(overlap(a, b, 0.0099) for b in footprints[i + 1 :])


@settings(max_examples=25, deadline=None, derandomize=True)
@given(scene=SCENES)
def test_accessible_layout_is_clearable_by_the_2d_hand(scene) -> None:
    n, density, seed = scene
    order = clearing_order(generate_clutter(n, density, seed))
    assert order is not None and order[-1] == 'T'


def test_target_is_blocked_for_every_planner_approach() -> None:
    """Every one of the planner's approaches to the target is blocked in the 2-D model (the
    cautious side of the planner's corridor test). A layout is redrawn at most LAYOUT_RESTARTS
    times, so a few sparse scenes keep a free one."""
    free = [
        (n, density, seed)
        for n, density in ((10, 0.15), (20, 0.3), (30, 0.15))
        for seed in range(8)
        if free_yaws(
            (s := generate_clutter(n, density, seed)).target.position[:2],
            [footprint_of(o) for o in s.obstacles],
        )
    ]
    assert len(free) <= 1, free  # at most one scene kept its last layout (30, 0.15, 6 today)


def test_uniform_layout_is_often_not_clearable() -> None:
    """The plain layout (before the accessibility rule) gets stuck in most dense scenes: the
    accessible layout's guarantee is not a property of every random scene."""
    stuck = sum(
        clearing_order(generate_clutter(20, 0.3, seed, layout='uniform')) is None
        for seed in range(6)
    )
    assert stuck >= 3
    assert all(clearing_order(generate_clutter(20, 0.3, seed)) for seed in range(6))


def test_boxes_corner_to_corner_keep_the_gap() -> None:
    """Found by hypothesis: two boxes whose bounding circles were just over the gap apart were
    never compared, although their corners came within the gap."""
    movable = [*generate_clutter(15, 0.1, 71115).obstacles]
    footprints = [footprint_of(o) for o in movable]
    for i, a in enumerate(footprints):
        assert not any(overlap(a, b, 0.0099) for b in footprints[i + 1 :])


def test_seeded_and_reproducible() -> None:
    a = generate_clutter(20, 0.25, 7)
    assert a == generate_clutter(20, 0.25, 7)
    assert a != generate_clutter(20, 0.25, 8)


def test_boxes_and_cylinders_both_appear() -> None:
    shapes = {o.shape for s in range(5) for o in generate_clutter(20, 0.2, s).obstacles}
    assert shapes == {'cylinder', 'box'}
    only_cylinders = generate_clutter(20, 0.2, 0, box_share=0.0)
    assert {o.shape for o in only_cylinders.obstacles} == {'cylinder'}


def test_target_among_the_clutter_in_most_scenes() -> None:
    """Some object stands between the base and the target (in its corridor) in most scenes."""
    covered = 0
    for seed in range(20):
        s = generate_clutter(15, 0.25, seed)
        t = s.target.position
        reach = math.hypot(t[0], t[1])
        ax, ay = t[0] / reach, t[1] / reach
        for o in s.obstacles:
            along = o.position[0] * ax + o.position[1] * ay
            lateral = abs(o.position[0] * ay - o.position[1] * ax)
            if along < reach and lateral < 0.1:
                covered += 1
                break
    assert covered >= 18


@pytest.mark.parametrize(
    ('kwargs', 'field'),
    [
        ({'n_objects': -1}, 'n_objects'),
        ({'n_objects': 2.5}, 'n_objects'),
        ({'density': 0.0}, 'density'),
        ({'density': 0.5}, 'density'),
        ({'density': math.nan}, 'density'),
        ({'seed': -3}, 'seed'),
        ({'radius_range': (0.05, 0.02)}, 'radius_range'),
        ({'radius_range': (0.0, 0.02)}, 'radius_range'),
        ({'radius_range': (0.045, 0.06)}, 'radius_range'),  # nothing the hand can close on
        ({'height_range': (0.08, 2.0)}, 'height_range'),
        ({'box_share': 1.5}, 'box_share'),
        ({'gap': 0.0}, 'gap'),
        ({'layout': 'grid'}, 'layout'),
        ({'x_min': math.inf}, 'x_min'),
    ],
)
def test_bad_arguments_name_the_field(kwargs: dict, field: str) -> None:
    args = {'n_objects': 10, 'density': 0.2, 'seed': 0, **kwargs}
    with pytest.raises(ScenarioError) as err:
        generate_clutter(**args)
    assert err.value.field == field


@pytest.mark.parametrize('layout', ['accessible', 'uniform'])
def test_unpackable_density_is_a_clear_error_not_a_hang(layout: str) -> None:
    with pytest.raises(ScenarioError, match='cannot pack') as err:
        generate_clutter(40, 0.4, 0, radius_range=(0.03, 0.08), attempts=20, layout=layout)
    assert err.value.field == 'density'
