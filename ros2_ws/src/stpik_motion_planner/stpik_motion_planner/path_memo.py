"""Memo of sampled Cartesian paths, reused where their probes replay (#28). No ROS import.

A path sampled for one approach depends on the scene only through the probes its sampler
makes (corridor, palm ball) and the height of the tallest movable object, which is part of
the key. A path sampled before is therefore reused in another scene when each of its probes'
culls lets through the same objects there (:class:`~.collision.QueryLog`), as the STPIK
results are (:meth:`.robust_stpik.RobustStpik._remembered`).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence

from stpik_motion_planner.cartesian_path import CartesianPath
from stpik_motion_planner.collision import QueryList, QueryLog, SceneWorld
from stpik_motion_planner.exceptions import MotionPlannerError, copy_error

SAMPLED_PER_KEY = 8  # sampled paths kept per approach (different scenes) [-]
SAMPLED_KEYS = 50_000  # approaches remembered before the memo starts afresh [-]

# What one sampling gives: the path (None: none found) after appending its failures.
SamplePath = Callable[[list[MotionPlannerError]], CartesianPath | None]


class SampledPaths:
    """Sampled paths by key, each with its probes' logs in the worlds it probed."""

    def __init__(self) -> None:
        """An empty memo."""
        # key -> [(scene objects, logs per world, path, failures)], newest last.
        self._entries: dict[Hashable, list[tuple]] = {}

    def __len__(self) -> int:
        """Number of keys remembered."""
        return len(self._entries)

    def path(
        self,
        key: Hashable,
        worlds: Sequence[SceneWorld],
        objects: tuple,
        sample: SamplePath,
        failures: list[MotionPlannerError],
    ) -> CartesianPath | None:
        """The path of ``key``: remembered if its probes replay in ``worlds``, else sampled.

        Either way the failures of the sampling are appended to ``failures`` (copies, for a
        remembered one) and the probes' queries reach every recorder of ``worlds`` (an
        enclosing answer's footprint sees a remembered path's probes as its own).

        Args:
            key: what the path depends on besides the probed scene.
            worlds: the worlds the sampler probes, in a fixed order.
            objects: the scene's objects (a scene equal to a remembered one replays at once).
            sample: samples the path, appending its failures to the list it is given.
            failures: where the failures go.
        """
        if len(self._entries) > SAMPLED_KEYS:
            self._entries.clear()
        entries = self._entries.setdefault(key, [])
        for seen, seen_logs, seen_path, seen_found in entries:
            if seen == objects or all(
                log.replays_in(world) for log, world in zip(seen_logs, worlds, strict=True)
            ):
                failures.extend(copy_error(err) for err in seen_found)
                for log, world in zip(seen_logs, worlds, strict=True):
                    for recorder in world.recorders:
                        recorder.extend(log.queries)
                return seen_path
        logs = tuple(QueryList() for _ in worlds)
        for log, world in zip(logs, worlds, strict=True):
            world.recorders.append(log)
        found: list[MotionPlannerError] = []
        try:
            path = sample(found)
        finally:
            for world in worlds:
                world.recorders.pop()
        failures.extend(found)
        replay = tuple(QueryLog(log) for log in logs)
        entries.append((objects, replay, path, tuple(copy_error(err) for err in found)))
        del entries[:-SAMPLED_PER_KEY]
        return path
