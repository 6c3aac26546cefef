"""Feasibility cache keyed on the set of relocated objects and the object (no ROS import).

With Assumption 2 of the paper (relocating an object does not disturb the others), whether object
``o`` can be relocated after the sequence ``S`` depends only on the SET of objects in ``S``.
"""

from __future__ import annotations

from collections.abc import Iterable

from stpik_motion_planner.result import PlanResult

CacheKey = tuple[frozenset[str], str]


class FeasibilityCache:
    """Results by ``(frozenset(relocated_ids), object_id)``, with hit and miss counters.

    Attributes:
        hits: number of :meth:`get` calls answered from the cache.
        misses: number of :meth:`get` calls not found.
    """

    def __init__(self) -> None:
        self._results: dict[CacheKey, PlanResult] = {}
        self.hits = 0
        self.misses = 0

    @staticmethod
    def key(object_id: str, relocated_ids: Iterable[str]) -> CacheKey:
        """The cache key of a request: ``(frozenset(relocated_ids), object_id)``."""
        return frozenset(relocated_ids), object_id

    def get(self, object_id: str, relocated_ids: Iterable[str]) -> PlanResult | None:
        """The stored result of this request, or None; counts a hit or a miss."""
        result = self._results.get(self.key(object_id, relocated_ids))
        if result is None:
            self.misses += 1
        else:
            self.hits += 1
        return result

    def put(self, object_id: str, relocated_ids: Iterable[str], result: PlanResult) -> None:
        """Store ``result`` for this request (overwrites)."""
        self._results[self.key(object_id, relocated_ids)] = result

    def clear(self) -> None:
        """Forget every result and reset the counters."""
        self._results.clear()
        self.hits = 0
        self.misses = 0

    @property
    def hit_rate(self) -> float:
        """Hits / (hits + misses), 0 when nothing was asked."""
        total = self.hits + self.misses
        return self.hits / total if total else 0.0

    def items(self) -> list[tuple[CacheKey, PlanResult]]:
        """Every stored ``(key, result)``, from a copy (atomic under the GIL: a check on another
        thread may fill the cache meanwhile).
        """
        return list(self._results.copy().items())

    def __len__(self) -> int:
        return len(self._results)
