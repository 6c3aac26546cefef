"""Exact reference: the true minimal relocation sequence by breadth-first search over SETS.

By Assumption 2 the feasibility of relocating o after S depends only on the set of S, so the
state space is the lattice of reachable sets (at most 2^N_o states instead of the N_o! orderings
of the tree). Level L holds the sets of L - 1 obstacles relocated in some feasible order; the
first level where the target is feasible is the optimal level m (depth of the target node, target
included, the convention of :mod:`qtree_task_planner.extraction`).

:func:`count_feasible_sequences` also counts xi_p (feasible target sequences, Sect. 4) and xi*
(those of minimal length) by dynamic programming over the reachable sets.
"""

from __future__ import annotations

from dataclasses import dataclass

from qtree_task_planner.exceptions import SearchLimitExceededError
from qtree_task_planner.oracle import FeasibilityOracle


@dataclass(frozen=True)
class ExactSolution:
    """Result of the exact search.

    Attributes:
        sequence: a minimal feasible sequence, obstacles then the target; ``()`` if none exists.
        level: optimal level m = ``len(sequence)`` (0 if no solution).
        queries: feasibility queries made (each a distinct (set, object) pair).
        sets_explored: reachable sets expanded.
    """

    sequence: tuple[str, ...]
    level: int
    queries: int
    sets_explored: int

    @property
    def solvable(self) -> bool:
        """A feasible sequence exists."""
        return bool(self.sequence)


def solve_exact(
    obstacle_ids: tuple[str, ...],
    target_id: str,
    oracle: FeasibilityOracle,
    *,
    max_sets: int = 100_000,
) -> ExactSolution:
    """Minimal feasible sequence by BFS over sets of relocated obstacles.

    Sets of one level are expanded in lexicographic order of their sorted ids, so the returned
    sequence is deterministic.

    Args:
        obstacle_ids: the obstacles O_1..O_No.
        target_id: the target T.
        oracle: feasibility oracle.
        max_sets: budget of expanded sets.

    Returns:
        The solution (``sequence == ()`` when the target is unreachable).

    Raises:
        SearchLimitExceededError: more than ``max_sets`` sets expanded.
    """
    queries = 0
    explored = 0
    # frontier: set -> one feasible order reaching it
    frontier: dict[frozenset[str], tuple[str, ...]] = {frozenset(): ()}
    while frontier:
        ordered = sorted(frontier.items(), key=lambda item: sorted(item[0]))
        for _, order in ordered:  # target check first: the shallowest level wins
            queries += 1
            if oracle.feasible(order, target_id):
                return ExactSolution((*order, target_id), len(order) + 1, queries, explored)
        nxt: dict[frozenset[str], tuple[str, ...]] = {}
        for done, order in ordered:
            explored += 1
            if explored > max_sets:
                raise SearchLimitExceededError(max_sets)
            for obstacle in obstacle_ids:
                if obstacle in done or (done | {obstacle}) in nxt:
                    continue
                queries += 1
                if oracle.feasible(order, obstacle):
                    nxt[done | {obstacle}] = (*order, obstacle)
        frontier = nxt
    return ExactSolution((), 0, queries, explored)


@dataclass(frozen=True)
class SequenceCounts:
    """Counts of feasible target sequences (Sect. 4).

    Attributes:
        feasible: xi_p, feasible sequences ending with the target.
        optimal: xi*, those of minimal length.
        by_level: level -> number of feasible target sequences at that level.
        reachable_sets: reachable sets of relocated obstacles (root included).
    """

    feasible: int
    optimal: int
    by_level: dict[int, int]
    reachable_sets: int


def count_feasible_sequences(
    obstacle_ids: tuple[str, ...],
    target_id: str,
    oracle: FeasibilityOracle,
    *,
    max_sets: int = 20_000,
) -> SequenceCounts:
    """Count every feasible target sequence (all orders) over the reachable sets.

    ways(S) = number of feasible orders reaching S; xi_p = sum over S with T feasible of ways(S).

    Raises:
        SearchLimitExceededError: more than ``max_sets`` reachable sets.
    """
    ways: dict[frozenset[str], int] = {frozenset(): 1}
    orders: dict[frozenset[str], tuple[str, ...]] = {frozenset(): ()}
    by_level: dict[int, int] = {}
    level_sets: list[frozenset[str]] = [frozenset()]
    total_sets = 1
    while level_sets:
        nxt: dict[frozenset[str], int] = {}
        for done in level_sets:
            order = orders[done]
            if oracle.feasible(order, target_id):
                level = len(done) + 1
                by_level[level] = by_level.get(level, 0) + ways[done]
            for obstacle in obstacle_ids:
                if obstacle not in done and oracle.feasible(order, obstacle):
                    child = done | {obstacle}
                    if child not in nxt:
                        orders[child] = (*order, obstacle)
                    nxt[child] = nxt.get(child, 0) + ways[done]
        total_sets += len(nxt)
        if total_sets > max_sets:
            raise SearchLimitExceededError(max_sets)
        ways.update(nxt)
        level_sets = sorted(nxt, key=sorted)
    feasible = sum(by_level.values())
    optimal = by_level[min(by_level)] if by_level else 0
    return SequenceCounts(feasible, optimal, dict(sorted(by_level.items())), total_sets)
