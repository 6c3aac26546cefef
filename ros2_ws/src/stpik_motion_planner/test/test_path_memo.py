"""The memo of sampled Cartesian paths (#28): reused only where its probes replay."""

from __future__ import annotations

import dataclasses

import fcl
import numpy as np
from qtree_scene.scene import ObjectSpec
from stpik_motion_planner.collision import QueryList, SceneWorld
from stpik_motion_planner.exceptions import NoCartesianPath
from stpik_motion_planner.path_memo import SampledPaths

NEAR = ObjectSpec('N', 'obstacle', 'cylinder', (0.0, 0.0, 0.1), radius=0.03, height=0.2)
FAR = ObjectSpec('F', 'obstacle', 'cylinder', (0.5, 0.5, 0.1), radius=0.03, height=0.2)
PROBE_AT = np.array([0.07, 0.0, 0.1])  # a 5 cm ball 4 cm from N's surface [m]


class _Sampler:
    """Probes a ball in each world and 'finds' a path (a string) unless N is within 5 cm."""

    def __init__(self) -> None:
        self.calls = 0

    def __call__(self, worlds: tuple[SceneWorld, ...], found: list) -> str | None:
        self.calls += 1
        sphere = fcl.Sphere(0.05)
        probe = fcl.CollisionObject(sphere, fcl.Transform(PROBE_AT))
        hits = [h for w in worlds for h in w.probe_hits(probe, PROBE_AT, 0.05, 0.05, sphere)]
        if hits:
            found.append(NoCartesianPath('T', f'blocked by {hits}'))
            return None
        return f'path {self.calls}'


def _ask(memo: SampledPaths, sampler: _Sampler, objects: list[ObjectSpec], failures: list):
    worlds = (SceneWorld(objects), SceneWorld([]))
    return memo.path(
        'key', worlds, tuple(objects), lambda found: sampler(worlds, found), failures
    ), worlds


def test_a_path_is_reused_where_its_probes_cull_alike_and_resampled_elsewhere() -> None:
    memo, sampler = SampledPaths(), _Sampler()
    failures: list = []
    first, _ = _ask(memo, sampler, [NEAR], failures)
    assert first is None and sampler.calls == 1 and len(failures) == 1
    # Another scene where the probe culls as before (F far away, only N near): the answer is
    # reused, with a copy of its failure.
    again: list = []
    reused, _ = _ask(memo, sampler, [NEAR, FAR], again)
    assert reused is None and sampler.calls == 1
    assert len(again) == 1 and again[0] is not failures[0]
    assert str(again[0]) == str(failures[0])
    # N moved out of the probe's reach: the cull differs, the path is sampled again.
    moved = dataclasses.replace(NEAR, position=(-0.2, 0.0, 0.1))
    path, _ = _ask(memo, sampler, [moved], [])
    assert path == 'path 2' and sampler.calls == 2


def test_a_reused_path_gives_its_probes_to_the_enclosing_recorders() -> None:
    memo, sampler = SampledPaths(), _Sampler()
    _ask(memo, sampler, [NEAR], [])
    worlds = (SceneWorld([NEAR]), SceneWorld([]))
    outer = (QueryList(), QueryList())
    for log, world in zip(outer, worlds, strict=True):
        world.recorders.append(log)
    memo.path('key', worlds, (NEAR,), lambda found: sampler(worlds, found), [])
    assert sampler.calls == 1  # reused
    assert len(outer[0]) == 1 and outer[0][0].hits == (NEAR,)  # the probe of the first call
    assert len(outer[1]) == 1 and outer[1][0].hits == ()
    assert all(not w.recorders[1:] for w in worlds)  # the memo's own logs were taken off
