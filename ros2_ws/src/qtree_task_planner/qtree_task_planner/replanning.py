"""Re-planning the rest of a retrieval after the world changed under its execution (#32; no ROS).

The goal's execution (:mod:`.sequence_execution`) stops for a re-plan when the motion planner
answers ``SCENE_CHANGED`` or ``GRASP_FAILED`` (the relocation was undone: the arm is back at the
start of its plan and the object where it was), when a step of the sequence is no longer feasible
(a planning failure 2xx: the scene it was learned on is gone), or when the scene changed between
two relocations. Then (:func:`~.goal_run.run_goal`):

* what was executed is kept: the objects relocated so far stay relocated and become the prefix of
  every later question (:class:`PrefixOracle`: the planner sees them gone, as in training);
* the interrupted relocation is **undone**, not finished, by the motion planner (see
  ``stpik_motion_planner.undo`` for why): its object is in the clutter again and is re-planned
  with the rest;
* the remaining retrieval is learned again from the current /scene with the goal's own planner
  (policy, budget and seed), and its sequence is executed after the prefix.

What is still true is kept too (item 4): the motion planner carries over to the new scene every
cached answer the change provably leaves true (``stpik_motion_planner.answer_reuse``), so the
re-plan's questions about them are answered from its cache; :class:`ReuseCounter` counts them
(``reused_answers``, one per re-plan).

At most the goal's ``max_replans`` re-plans; the next cause then ends the goal with
``REPLAN_LIMIT`` naming it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from typing import Any

from stpik_motion_planner.result import ReasonFamily, reason_family

from qtree_task_planner.oracle import FeasibilityAnswer

SCENE_CHANGED, GRASP_FAILED = 304, 305  # RelocateObject.Response reason codes (#32)
REPLAN_REASONS = {SCENE_CHANGED: 'SCENE_CHANGED', GRASP_FAILED: 'GRASP_FAILED'}
DEFAULT_MAX_REPLANS = 3  # RetrieveTarget.Goal.max_replans default [-]
MAX_REPLANS = 100  # largest max_replans accepted [-]


def replan_cause(object_id: str, reason: int, message: str) -> str | None:
    """The cause line of an execute=true answer that calls for a re-plan, else None.

    Args:
        object_id: the object whose relocation was answered.
        reason: the answer's reason code.
        message: the answer's message.

    Returns:
        e.g. ``"SCENE_CHANGED relocating 'O3': ..."``; for a planning failure (2xx) during the
        execution ``"'O3' no longer feasible (reason 205): ..."``; None for other failures.
    """
    if reason in REPLAN_REASONS:
        return f'{REPLAN_REASONS[reason]} relocating {object_id!r}: {message}'
    if reason_family(reason) == ReasonFamily.PLANNING_FAILURE:
        return f'{object_id!r} no longer feasible (reason {reason}): {message}'
    return None


def kept_prefix(executed: Iterable[str], relocated_now: Iterable[str]) -> tuple[str, ...]:
    """The relocations that stay done: the executed ids the scene shows RELOCATED, in order."""
    relocated = set(relocated_now)
    return tuple(object_id for object_id in executed if object_id in relocated)


class ReuseCounter:
    """Counts the distinct questions of one training answered from the motion planner's cache.

    In a re-plan's training, the first time a ``(set, object)`` question is asked an answer from
    the cache can only be one the planner kept across the scene change (its cache was rebuilt
    with only those; repeats of a question asked in this training are not counted).

    Attributes:
        reused: distinct questions answered from the cache since :meth:`reset` [-].
    """

    def __init__(self) -> None:
        self._seen: set[tuple[frozenset[str], str]] = set()
        self.reused = 0

    def reset(self) -> None:
        """Start counting for a new training."""
        self._seen.clear()
        self.reused = 0

    def count(self, relocated: Iterable[str], object_id: str, from_cache: bool) -> None:
        """Note one answer to "``object_id`` after ``relocated``" (``from_cache``: the
        response's flag).
        """
        key = (frozenset(relocated), object_id)
        if key in self._seen:
            return
        self._seen.add(key)
        self.reused += bool(from_cache)


class PrefixOracle:
    """A feasibility oracle whose every question has ``prefix`` relocated first.

    Other attributes (``planner_runs``, ``retries``, ...) are the wrapped oracle's.
    """

    def __init__(self, inner: Any, prefix: Sequence[str]) -> None:
        self.inner = inner
        self.prefix = tuple(prefix)

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Whether ``object_id`` can be relocated after the prefix then ``relocated``."""
        return self.inner.feasible((*self.prefix, *relocated), object_id)

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """The wrapped answer (with blockers) after the prefix then ``relocated``."""
        return self.inner.answer((*self.prefix, *relocated), object_id)

    def approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[frozenset[str], ...] | None:
        """The wrapped per-approach blockers after the prefix then ``relocated``."""
        return self.inner.approach_blockers((*self.prefix, *relocated), object_id)

    def __getattr__(self, name: str) -> Any:
        inner = getattr(self.inner, name)  # AttributeError when the wrapped oracle has none
        if name == 'clear_zone_feasible':  # a question too: after the prefix (it was asked
            # without it, so BLOCKER-SEARCH's verifications tested another state and a re-plan
            # with the in-process planner could miss a sequence the exact search finds)
            return lambda relocated, object_id: inner((*self.prefix, *relocated), object_id)
        return inner


def combined(results: Sequence[Any], prefix: Sequence[str]) -> Any:
    """One training result for the goal: the last training's, its sequence after ``prefix``
    (the relocations kept before it), episodes, MP calls, planner runs and time summed [s].
    """
    last = results[-1]
    return dataclasses.replace(
        last,
        sequence=(*prefix, *last.sequence),
        episodes=sum(r.episodes for r in results),
        mp_calls=sum(r.mp_calls for r in results),
        planner_runs=sum(r.planner_runs for r in results),
        wall_time_s=sum(r.wall_time_s for r in results),
    )
