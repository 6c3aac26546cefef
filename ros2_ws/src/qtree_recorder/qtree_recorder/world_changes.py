"""The changing world of a run as timeline lines: scene events and re-plans (#32; no ROS import).

Used by the Rerun view (:mod:`.rerun_view`, entity ``/events/world``) and ``replay.py
--summary`` (section "changing world"). Three sources, all recorded in the MCAP:

* ``/scene``: an object IN_CLUTTER that moved, appeared or disappeared between two consecutive
  messages (:func:`qtree_scene.changes.scene_changes`). An object leaving the clutter by being
  grasped, carried or relocated is not a change, nor one put back down by an undone relocation
  (it was in the previous message, only its status changed);
* ``/motion_planner/events``: answers ``SCENE_CHANGED`` (304) and ``GRASP_FAILED`` (305);
* ``/task_planner/replans`` (``qtree_msgs/ReplanEvent``): each re-plan's start and new plan.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

from qtree_scene.changes import clutter_objects, scene_changes

REPLAN_TOPIC = '/task_planner/replans'
TOPICS = ('/scene', '/motion_planner/events', REPLAN_TOPIC)
WORLD_REASONS = {304: 'SCENE_CHANGED', 305: 'GRASP_FAILED'}


class WorldChanges:
    """Turns the messages of :data:`TOPICS`, in log order, into timeline lines."""

    def __init__(self) -> None:
        self._clutter: dict[str, Any] | None = None
        self._ids: set[str] = set()

    def on_message(self, topic: str, msg: Any) -> list[str]:
        """The lines ``msg`` adds to the timeline (often none); a malformed message gives one
        line saying so, never an exception.
        """
        try:
            if topic == '/scene':
                return self._on_scene(msg)
            if topic == '/motion_planner/events':
                return _on_planning_event(msg)
            if topic == REPLAN_TOPIC:
                return [replan_line(msg)]
        except (AttributeError, TypeError, ValueError) as err:
            return [f'unreadable {topic} message ({type(err).__name__}: {err})']
        return []

    def _on_scene(self, msg: Any) -> list[str]:
        clutter = clutter_objects(msg)
        ids = {str(o.id) for o in msg.objects}
        before, self._clutter = self._clutter, clutter
        known, self._ids = self._ids, ids
        if before is None:
            return []
        # left the clutter but still in the scene: carried or relocated, not a change
        kept = {k: v for k, v in before.items() if k in clutter or k not in ids}
        # back in the clutter (an undone relocation puts its object down): not new
        now = {k: v for k, v in clutter.items() if k in before or k not in known}
        changes = scene_changes(kept, now)
        return [f'scene: {", ".join(changes)}'] if changes else []


def _on_planning_event(msg: Any) -> list[str]:
    name = WORLD_REASONS.get(int(msg.reason))
    if name is None:
        return []
    return [f'motion planner: {name} relocating {str(msg.object_id)!r}: {msg.message}']


def replan_line(msg: Any) -> str:
    """One line of a ``ReplanEvent``, e.g. ``"re-plan 1 started: SCENE_CHANGED ..."``."""
    head = f're-plan {int(msg.replan)} {msg.phase}'
    if msg.phase == 'started':
        kept = ', '.join(msg.kept_ids) or 'none'
        return f'{head}: {msg.cause} (done so far: {kept})'
    rest = ' -> '.join(msg.sequence) or '(none)'
    return (
        f'{head}: kept {list(msg.kept_ids)}, then {rest}; {int(msg.reused_answers)} answers '
        f'reused, {int(msg.planner_runs)} planner runs'
    )


def timeline(messages: Iterable[Any], start_ns: int) -> Iterator[str]:
    """``"  +12.345 s  <line>"`` for every line of the decoded ``messages`` (``.topic``,
    ``.message``, ``.log_time_ns``) of :data:`TOPICS`, in order; times from ``start_ns``.
    """
    changes = WorldChanges()
    for item in messages:
        for line in changes.on_message(item.topic, item.message):
            yield f'  +{(item.log_time_ns - start_ns) * 1e-9:.3f} s  {line}'
