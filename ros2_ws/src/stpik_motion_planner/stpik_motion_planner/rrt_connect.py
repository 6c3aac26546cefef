"""RRTConnect in joint space with a per-question random stream (plain numpy, no ROS).

Why not OMPL's ``og.RRTConnect`` (used until #29): OMPL draws every sampler's seed from one
process-wide generator that can be seeded once, before its first use (``ompl.util.RNG.setSeed``
afterwards only logs "Changing seed now will not lead to deterministic sampling"), and the Python
bindings installed here cannot give a state space a sampler of ours (no
``setStateSamplerAllocator``). A cached answer then depended on the questions asked before it in
the same process: the exact search found 3 relocations in one run and 4 in the next on the same
scene (#29, point 8). Here the stream is a ``numpy.random.Generator`` the caller seeds from the
question itself, and the search is bounded by a number of iterations, not by wall time, so the
same question gets the same path (or the same "no path") in any order, in any process, on any
load. The wall-clock deadline only ever ends it with :class:`~.exceptions.PlanningTimeout` (an
answer that is not cached).

The algorithm is Kuffner & LaValle's RRT-Connect (ICRA 2000): alternately extend one tree by at
most ``range_rad`` towards a uniform sample, then connect the other tree greedily to the new
node; every edge is checked at ``resolution_rad`` (largest joint step between two checked
configurations). The path is then shortened by random shortcuts drawn from the same stream.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable

import numpy as np

ADVANCED, REACHED, TRAPPED = 0, 1, 2


def question_seed(*parts: bytes | str | float | int) -> int:
    """A 64-bit seed from the bytes of a question (stable across processes, unlike ``hash``)."""
    digest = hashlib.blake2b(digest_size=8)
    for part in parts:
        digest.update(part if isinstance(part, bytes) else repr(part).encode())
    return int.from_bytes(digest.digest(), 'little')


def _bisection_order(n: int) -> list[int]:
    """1 … n, the end first, then midpoints of ever finer halves (each index once)."""
    order, seen = [n], {0, n}
    queue = [(0, n)]
    while queue:
        nxt = []
        for lo, hi in queue:
            mid = (lo + hi) // 2
            if mid not in seen:
                seen.add(mid)
                order.append(mid)
            if mid - lo > 1:
                nxt.append((lo, mid))
            if hi - mid > 1:
                nxt.append((mid, hi))
        queue = nxt
    return order


class _Tree:
    """Nodes (n, dof) [rad] and their parents (n,), preallocated and grown by doubling."""

    def __init__(self, root: np.ndarray) -> None:
        self.nodes = np.empty((64, root.size))
        self.parents = np.empty(64, dtype=int)
        self.nodes[0], self.parents[0], self.size = root, -1, 1

    def add(self, q: np.ndarray, parent: int) -> int:
        if self.size == len(self.nodes):
            self.nodes = np.vstack([self.nodes, np.empty_like(self.nodes)])
            self.parents = np.concatenate([self.parents, np.empty_like(self.parents)])
        self.nodes[self.size], self.parents[self.size] = q, parent
        self.size += 1
        return self.size - 1

    def nearest(self, q: np.ndarray) -> int:
        diff = self.nodes[: self.size] - q
        return int(np.argmin(np.einsum('ij,ij->i', diff, diff)))

    def branch(self, index: int) -> list[np.ndarray]:
        """Configurations from the root to ``index``."""
        out = []
        while index >= 0:
            out.append(self.nodes[index])
            index = int(self.parents[index])
        return out[::-1]


class RrtConnect:
    """One RRT-Connect search over a validity predicate.

    Attributes:
        checks: validity checks made (for the profile).
    """

    def __init__(
        self,
        valid: Callable[[np.ndarray], bool],
        low: np.ndarray,
        high: np.ndarray,
        rng: np.random.Generator,
        range_rad: float = 0.5,
        resolution_rad: float = 0.025,
        deadline: float = np.inf,
        on_deadline: Callable[[], Exception] | None = None,
    ) -> None:
        """Args:
        valid: ``valid(q)`` for a configuration [rad] (dof,).
        low, high: sampling box [rad] (dof,).
        rng: the question's random stream.
        range_rad: longest extension (Euclidean in joint space) [rad].
        resolution_rad: largest joint step between two checked configurations of an edge [rad].
        deadline: ``time.perf_counter()`` value past which the search raises ``on_deadline()``.
        """
        self.valid, self.low, self.high, self.rng = valid, low, high, rng
        self.range_rad, self.resolution_rad = range_rad, resolution_rad
        self.deadline, self.on_deadline = deadline, on_deadline
        self.checks = 0

    def motion_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """Every configuration after ``q_a`` up to ``q_b``, ≤ ``resolution_rad`` apart, valid.

        Checked in bisection order (the end, the middle, the quarters, ...): a blocked edge is
        usually found after a few checks instead of a march from ``q_a``; same answer.
        """
        n = max(1, int(np.ceil(np.max(np.abs(q_b - q_a)) / self.resolution_rad)))
        for i in _bisection_order(n):
            self.checks += 1
            if not self.valid(q_a + (q_b - q_a) * (i / n)):
                return False
        return True

    def _extend(self, tree: _Tree, q: np.ndarray) -> tuple[int, int]:
        near = tree.nearest(q)
        q_near = tree.nodes[near]
        step = q - q_near
        length = float(np.linalg.norm(step))
        reached = length <= self.range_rad
        q_new = q if reached else q_near + step * (self.range_rad / length)
        if not self.motion_valid(q_near, q_new):
            return TRAPPED, near
        return (REACHED if reached else ADVANCED), tree.add(q_new.copy(), near)

    def _check_deadline(self) -> None:
        if time.perf_counter() > self.deadline:
            raise (self.on_deadline() if self.on_deadline else TimeoutError('RRT deadline'))

    def solve(
        self, start: np.ndarray, goal: np.ndarray, max_iterations: int
    ) -> list[np.ndarray] | None:
        """Waypoints start → goal [rad] (each edge valid), or None after ``max_iterations``.

        The ends are assumed valid (the caller checks them).
        """
        if self.motion_valid(start, goal):
            return [start, goal]
        trees = [_Tree(start), _Tree(goal)]
        for iteration in range(max_iterations):
            self._check_deadline()
            grow, other = trees[iteration % 2], trees[1 - iteration % 2]
            status, new = self._extend(grow, self.rng.uniform(self.low, self.high))
            if status == TRAPPED:
                continue
            q_new = grow.nodes[new]
            status = ADVANCED
            while status == ADVANCED:
                status, last = self._extend(other, q_new)
            if status == REACHED:
                a, b = grow.branch(new), other.branch(last)
                path = a + b[::-1][1:]  # both branches end at q_new
                return path if iteration % 2 == 0 else path[::-1]
        return None

    def shortcut(self, path: list[np.ndarray], attempts: int) -> list[np.ndarray]:
        """Drop the waypoints between two random ones whenever the straight edge is valid."""
        path = list(path)
        for _ in range(attempts):
            if len(path) < 3:
                break
            self._check_deadline()
            i, j = sorted(self.rng.choice(len(path), size=2, replace=False))
            if j - i > 1 and self.motion_valid(path[i], path[j]):
                path = path[: i + 1] + path[j:]
        return path
