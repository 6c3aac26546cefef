"""Feasibility oracles: who answers "can object o be relocated once S has been relocated?".

The Q-Tree only needs a binary answer (Sect. 3.2). Implementations:

* :class:`TableOracle`: a hand-built table, for unit tests and property tests only.
* :class:`MotionPlannerOracle`: the real in-process STPIK motion planner (imported lazily).
* :class:`MemoOracle`: memoises any oracle on the set key ``(frozenset(S), o)`` (Assumption 2) and
  counts the distinct keys it had to forward: the real planner runs of one training.
* The ROS client oracle (RelocateObject service) lives in ``task_planner_node``.

``planner_runs`` counts real planner runs (cache misses); ``queries`` counts every call.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

from qtree_task_planner.exceptions import OracleUnavailableError
from qtree_task_planner.retry import Backoff

SetKey = tuple[frozenset[str], str]


@runtime_checkable
class FeasibilityOracle(Protocol):
    """Answers feasibility queries (the motion-planner layer of Figure 2).

    Attributes:
        planner_runs: real planner runs so far (cache misses).
    """

    planner_runs: int

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Can ``object_id`` be grasped and relocated once ``relocated`` are gone?

        Raises:
            OracleUnavailableError: no answer (only oracles that talk to another process).
        """
        ...


class TableOracle:
    """Hand-built feasibility: an object is feasible once ANY of its clearing sets is relocated.

    Args:
        requirements: object id -> list of clearing sets (each an iterable of object ids). An
            object absent from the mapping is always feasible; an object mapped to ``[]`` never is.

    Example:
        ``TableOracle({'T': [{'O1', 'O2'}, {'O3'}], 'O1': [{'O3'}]})``: T needs O1 and O2 gone, or
        O3 gone; O1 needs O3 gone.
    """

    def __init__(self, requirements: Mapping[str, Sequence[Iterable[str]]]) -> None:
        self.requirements = {o: [frozenset(s) for s in sets] for o, sets in requirements.items()}
        self.planner_runs = 0
        self.queries = 0
        self._seen: set[SetKey] = set()

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """True if some clearing set of ``object_id`` is contained in ``relocated``."""
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self._seen:
            self._seen.add(key)
            self.planner_runs += 1
        if object_id not in self.requirements:
            return True
        done = key[0]
        return any(need <= done for need in self.requirements[object_id])


class MemoOracle:
    """Memoise another oracle on ``(frozenset(relocated), object_id)``.

    Args:
        inner: the oracle asked on a cache miss.

    Attributes:
        planner_runs: distinct set keys forwarded to ``inner`` (what a fresh planner with a set
            cache would have run).
        queries: every call.
        results: the memo, set key -> feasible.
    """

    def __init__(self, inner: FeasibilityOracle) -> None:
        self.inner = inner
        self.planner_runs = 0
        self.queries = 0
        self.results: dict[SetKey, bool] = {}

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Answer from the memo, or ask ``inner`` once."""
        self.queries += 1
        key = (frozenset(relocated), object_id)
        if key not in self.results:
            self.results[key] = bool(self.inner.feasible(tuple(relocated), object_id))
            self.planner_runs += 1
        return self.results[key]


PLANNING_TIMEOUT = 301  # RelocateObject.TIMEOUT / stpik_motion_planner Reason.TIMEOUT


class MotionPlannerOracle:
    """The real in-process motion planner (``stpik_motion_planner.planner.MotionPlanner``).

    Args:
        scenario: a ``qtree_scene.scene.Scenario`` or an installed scenario name (``'s1'``).
        planner: an existing ``MotionPlanner`` to reuse (its cache persists across trainings).

    Attributes:
        planner_runs: planner answers not served from the planner's own cache.
        planning_time_s: total planning time reported by the planner [s].
    """

    def __init__(self, scenario: Any, planner: Any | None = None) -> None:
        if planner is None:
            from stpik_motion_planner.planner import MotionPlanner  # lazy: heavy imports

            if isinstance(scenario, str):
                from qtree_scene.scenario import load_scenario

                scenario = load_scenario(scenario)
            planner = MotionPlanner(scenario)
        self.scenario = scenario
        self.planner = planner
        self.planner_runs = 0
        self.queries = 0
        self.planning_time_s = 0.0

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Ask the planner (``check(object_id, relocated_ids)``) and count real runs.

        A planning TIMEOUT (301: the time limit ran out, e.g. on a loaded machine; not cached by
        the planner) is not an answer: it is asked again up to ``Backoff().retries`` times (#18).

        Raises:
            OracleUnavailableError: still TIMEOUT after the retries.
        """
        self.queries += 1
        for _ in range(Backoff().retries + 1):
            result = self.planner.check(object_id, list(relocated))
            if int(getattr(result, 'reason', 0)) != PLANNING_TIMEOUT:
                break
        else:
            raise OracleUnavailableError(object_id, tuple(relocated), f'TIMEOUT: {result.message}')
        if not getattr(result, 'from_cache', False):
            self.planner_runs += 1
            self.planning_time_s += float(getattr(result, 'planning_time', 0.0) or 0.0)
        return bool(result.feasible)
