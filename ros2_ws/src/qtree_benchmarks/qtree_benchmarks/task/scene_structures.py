"""Blocking structures of a given difficulty, before any geometry (#31 item 1; no ROS import).

The paper measures its policies on scenes of known difficulty: S1, S2, S3 with optimal levels
4 / 5 / 6 (the target included), ξ_p = 10 / 20 / 20 feasible target sequences (every order that
ends with the target grasped, eq. (7)'s feasible subset, counted by
:func:`qtree_task_planner.exact.count_feasible_sequences`) and ξ* = 1 optimal sequence. Which
objects must go before which decides those three numbers alone, so a layout is designed in two
steps: first a STRUCTURE with the wanted numbers (this module, exact and instant), then a
geometry that realises it with the real planner (``scripts/design_scenarios.py``).

A :class:`Structure` is a CHAIN c1 → c2 → … → cL → T (each object free once the one before it
is gone, the target once the whole chain is: one optimal sequence at level L + 1) and EXTRAS,
each free once one given object is gone (a chain object or an earlier extra) or from the start
(a decoy). Extras never free the target, so they only add longer sequences to ξ_p. The current
S1, where the target needs A gone and A needs both of a pair gone, is the structure with ξ* = 2
that :func:`pair_structure_counts` counts (the two orders of the pair).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from qtree_task_planner.exact import SequenceCounts, count_feasible_sequences
from qtree_task_planner.oracle import TableOracle

TARGET = 'T'


@dataclass(frozen=True)
class Structure:
    """Who frees whom: a chain to the target and extras hanging off it.

    Attributes:
        chain: the chain's objects in the only order that frees the target (c1 first).
        unlocks: per extra ``e1, e2, …``, the object whose removal frees it (a chain object or
            an earlier extra), None for a decoy free from the start.
    """

    chain: tuple[str, ...]
    unlocks: tuple[str | None, ...] = ()

    @property
    def extras(self) -> tuple[str, ...]:
        """The extras' ids, ``e1, e2, …``."""
        return tuple(f'e{j + 1}' for j in range(len(self.unlocks)))

    @property
    def obstacles(self) -> tuple[str, ...]:
        """Every obstacle, the chain first."""
        return self.chain + self.extras

    def requirements(self) -> dict[str, list[set[str]]]:
        """The structure as :class:`~qtree_task_planner.oracle.TableOracle` clearing sets."""
        needs: dict[str, list[set[str]]] = {TARGET: [set(self.chain)]}
        for before, after in zip(self.chain, self.chain[1:], strict=False):
            needs[after] = [{before}]
        for extra, unlock in zip(self.extras, self.unlocks, strict=True):
            if unlock is not None:
                needs[extra] = [{unlock}]
        return needs

    def counts(self) -> SequenceCounts:
        """ξ_p, ξ* and the sequences by level, counted as for a scene."""
        oracle = TableOracle(self.requirements())
        return count_feasible_sequences(self.obstacles, TARGET, oracle)

    def __str__(self) -> str:
        chain = ' -> '.join((*self.chain, TARGET))
        extras = ', '.join(
            f'{e} free' if u is None else f'{e} after {u}'
            for e, u in zip(self.extras, self.unlocks, strict=True)
        )
        return f'{chain}; {extras or "no extras"}'


def structures(level: int, xi_p: int, max_extras: int = 3) -> Iterator[Structure]:
    """Every structure (fewest extras first) with the target at ``level`` (target included),
    exactly one optimal sequence and ``xi_p`` feasible target sequences.

    Raises:
        ValueError: ``level`` < 1, ``xi_p`` < 1 or ``max_extras`` < 0.
    """
    if level < 1 or xi_p < 1 or max_extras < 0:
        raise ValueError(f'need level >= 1, xi_p >= 1, max_extras >= 0: {level}, {xi_p}')
    chain = tuple(f'c{i + 1}' for i in range(level - 1))
    for count in range(max_extras + 1):
        for unlocks in _unlock_choices(chain, count):
            structure = Structure(chain, unlocks)
            if structure.counts().feasible == xi_p:
                yield structure


def _unlock_choices(chain: Sequence[str], count: int) -> Iterator[tuple[str | None, ...]]:
    """Each extra's unlock among None, the chain and the earlier extras; extras of the same
    unlock listed once (their order does not change the counts).
    """
    for unlocks in itertools.product(*(_unlocks_of(chain, j) for j in range(count))):
        if _canonical(unlocks):
            yield unlocks


def _unlocks_of(chain: Sequence[str], j: int) -> list[str | None]:
    return [None, *chain, *(f'e{k + 1}' for k in range(j))]


def _canonical(unlocks: tuple[str | None, ...]) -> bool:
    """Free-or-chain extras in non-decreasing order of their unlock (the rest as drawn)."""
    rank = [-1 if u is None else int(u[1:]) for u in unlocks if u is None or u.startswith('c')]
    return rank == sorted(rank)


def pair_structure_counts(decoys: int = 1) -> SequenceCounts:
    """The counts of the current S1's structure: T needs A gone, A needs B1 and B2 gone (the
    pair, in either order), and ``decoys`` free decoys.
    """
    needs: dict[str, list[set[str]]] = {TARGET: [{'A'}], 'A': [{'B1', 'B2'}]}
    obstacles = ('A', 'B1', 'B2', *(f'D{k + 1}' for k in range(decoys)))
    return count_feasible_sequences(obstacles, TARGET, TableOracle(needs))
