"""The Q-Tree: a tree of relocated-object sequences whose edges carry Q values (Sect. 3.2).

A node stands for the sequence S_{s_k} of objects relocated so far; the root s_H is the empty
sequence ``()``. An edge from node s by action a (relocate object a) carries the reward r(s, a)
of eq. (8) and the value Q(s, a). A new edge is initialised to its reward; a revisited edge is
updated with eq. (5), which the paper rewrites as eq. (12)::

    Q_{k+1}(s_k, a_k) = (1 - alpha) Q_k(s_k, a_k) + alpha r_{k+1}
                        + alpha gamma max_a Q_k(s_{k+1}, a)

where the max over the child's edges is 0 when the child has none (a leaf or a terminal node).

Terminal nodes (Sect. 3.2): a sequence ending with an obstacle that could not be relocated, or
ending with the target T, whether the target could be relocated or not.

Set sharing (``share_sets=True``, our H-EG-SET, not in the paper): by Assumption 2 the feasibility
of an action, and therefore the whole sub-tree below a node, depends only on the SET of relocated
objects. With set sharing, nodes reached by permutations of the same set are one node (a
transposition table: the tree becomes a DAG keyed by the sorted sequence), so every (set, object)
pair is asked once and learned values are shared. Infeasible children are never shared with a
feasible node of the same set: their key is the parent's key plus ``'!' + action``.

Optimism (``optimistic_over``, also H-EG-SET): untried actions count with an upper bound of their
value in eq. (5) and in the greedy choice, and a new obstacle edge starts at that bound instead of
its reward (:meth:`QTree.value`).

Bookkeeping (issue #14, results unchanged): the optimistic V(s) of :meth:`QTree.value` is memoised
and a memo entry is dropped when anything it was computed from changes (an edge of the node is
added or updated, or a child set it valued optimistically gains edges or appears); the explored
steady-state value and best edge of every node (what :func:`~qtree_task_planner.extraction.
best_known_sequence` reads) are kept up to date edge by edge instead of re-sorting every node after
every episode.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from qtree_task_planner.rewards import REWARD_INFEASIBLE, REWARD_TARGET

NodeKey = tuple[str, ...]
INFEASIBLE_MARK = '!'  # prefix of a failed action in the key of an infeasible terminal node


@dataclass
class Edge:
    """One edge of the tree.

    Attributes:
        parent: key of the parent node.
        action: id of the relocated object (the action a).
        child: key of the child node.
        reward: r(s, a) of eq. (8) [reward units].
        q: current Q(s, a) [reward units].
        visits: how many times the edge was selected (creation included).
    """

    parent: NodeKey
    action: str
    child: NodeKey
    reward: float
    q: float
    visits: int = 1

    @property
    def feasible(self) -> bool:
        """True when the motion planner could relocate the object."""
        return self.reward > REWARD_INFEASIBLE


@dataclass
class TreeNode:
    """One node of the tree.

    Attributes:
        key: the node's key (the sequence, or the sorted sequence with set sharing).
        sequence: the relocated sequence S_{s_k} that first reached the node.
        depth: tree level, ``len(sequence)`` (the root is level 0).
        terminal: no action can follow (failed action, or the target was tried).
        children: outgoing edges by action, in creation order.
    """

    key: NodeKey
    sequence: tuple[str, ...]
    depth: int
    terminal: bool = False
    children: dict[str, Edge] = field(default_factory=dict)


class QTree:
    """The Q-Tree with the eq. (5) update.

    Args:
        target_id: id of the target T (its edges are terminal).
        alpha: learning rate of eq. (5), in (0, 1].
        gamma: discount of eq. (5), in (0, 1].
        share_sets: merge nodes with the same set of relocated objects (H-EG-SET).
    """

    def __init__(
        self,
        target_id: str,
        alpha: float,
        gamma: float,
        *,
        share_sets: bool = False,
        optimistic_over: tuple[str, ...] | None = None,
    ) -> None:
        self.target_id = target_id
        self.alpha = alpha
        self.gamma = gamma
        self.share_sets = share_sets
        self.optimistic_over = optimistic_over
        self.root = TreeNode(key=(), sequence=(), depth=0)
        self._nodes: dict[NodeKey, TreeNode] = {(): self.root}
        self._num_edges = 0
        self._q_bar = 0.0  # eq. (10), kept up to date edge by edge
        self._memo: dict[NodeKey, float] = {}  # optimistic V(s), see :meth:`value`
        # explored steady-state value and best edge of each node (see :meth:`known_choice`)
        self._known: dict[NodeKey, tuple[float, Edge | None]] = {(): (0.0, None)}
        self._in_edges: dict[NodeKey, list[Edge]] = {}  # feasible obstacle edges into a node

    # -- look-up ---------------------------------------------------------------------------------

    def key_of(self, sequence: tuple[str, ...]) -> NodeKey:
        """Key of the node of a feasible sequence (the sequence, or sorted with set sharing)."""
        return tuple(sorted(sequence)) if self.share_sets else tuple(sequence)

    def node(self, key: NodeKey) -> TreeNode:
        """The node with this key.

        Raises:
            KeyError: no such node.
        """
        return self._nodes[key]

    def __contains__(self, key: object) -> bool:
        return key in self._nodes

    def nodes(self) -> Iterator[TreeNode]:
        """All nodes, in creation order (root first)."""
        return iter(self._nodes.values())

    def edges(self) -> Iterator[Edge]:
        """All edges, parents in creation order."""
        for node in self._nodes.values():
            yield from node.children.values()

    @property
    def num_nodes(self) -> int:
        """Number of nodes, root included."""
        return len(self._nodes)

    @property
    def num_edges(self) -> int:
        """Number of edges = motion-planner calls as the paper counts them (Sect. 3.2.2)."""
        return self._num_edges

    @property
    def q_bar(self) -> float:
        """Sum of |Q| over all edges, eq. (10)."""
        return self._q_bar

    def max_q(self, key: NodeKey) -> float:
        """max_a Q(s, a) over the node's edges; 0 for a node without edges (eq. (5))."""
        children = self._nodes[key].children
        return max((edge.q for edge in children.values()), default=0.0)

    def value(self, key: NodeKey) -> float:
        """V(s) used as max_a' Q(s', a') in eq. (5).

        Without optimism this is :meth:`max_q`. With ``optimistic_over`` (H-EG-SET), actions not
        yet tried from a non-terminal node count with their best possible value, an upper bound of
        what they can bring (optimism in the face of uncertainty): r_T for an untried target,
        gamma r_T for an untried obstacle (relocate it, then the target). Memoised; the memo is
        invalidated by every change it depends on (:meth:`_invalidate`), so the value is the
        same float as a fresh recursion.
        """
        if self.optimistic_over is None:
            return self.max_q(key)
        memo = self._memo.get(key)
        if memo is not None:
            return memo
        node = self._nodes[key]
        best = max((edge.q for edge in node.children.values()), default=None)
        if not node.terminal:
            for action in self.optimistic_over:
                if action not in node.children and action not in node.sequence:
                    bound = self.untried_value(key, action)
                    best = bound if best is None else max(best, bound)
        value = 0.0 if best is None else best
        self._memo[key] = value
        return value

    def untried_value(self, key: NodeKey, action: str) -> float:
        """Value given to an action not yet tried from node ``key`` by the greedy choice.

        0 (the value a new obstacle edge starts with) without optimism; with optimism r_T for the
        target, gamma r_T for an obstacle, or gamma V(child) when the child set is already known.
        """
        if self.optimistic_over is None:
            return 0.0
        if action == self.target_id:
            return REWARD_TARGET
        child = self.key_of((*self._nodes[key].sequence, action))
        if child in self._nodes:
            return self.gamma * self.value(child)
        return self.gamma * REWARD_TARGET

    def _invalidate(self, key: NodeKey) -> None:
        """Drop the memoised V of ``key`` and of every node whose memo was computed from it.

        A node may read V(key) through an untried action: its key is ``key`` minus one id (an
        over-approximation, which only costs a recomputation). A node whose memo is absent has no
        memoised dependent (computing a value memoises what it read), so the walk stops there.
        """
        stack = [key]
        while stack:
            k = stack.pop()
            if self._memo.pop(k, None) is None:
                continue
            stack.extend(self._untried_parents(k))

    def _untried_parents(self, key: NodeKey) -> list[NodeKey]:
        """Existing nodes whose key is ``key`` without one of its ids."""
        parents = (key[:i] + key[i + 1 :] for i in range(len(key)))
        return [p for p in parents if p in self._nodes]

    def known_value(self, key: NodeKey) -> float:
        """Explored steady-state value of a node: max over its edges of r + gamma V(child) (the
        reward alone for the target and failed edges), 0 without edges; optimism ignored.
        """
        return self._known[key][0]

    def known_choice(self, key: NodeKey) -> Edge | None:
        """The earliest-created edge reaching :meth:`known_value`, None without edges."""
        return self._known[key][1]

    def _refresh_known(self, key: NodeKey) -> None:
        """Recompute :meth:`known_value` of ``key`` and propagate a change to its parents."""
        stack = [key]
        while stack:
            k = stack.pop()
            best: Edge | None = None
            best_value = 0.0
            for edge in self._nodes[k].children.values():
                if edge.feasible and edge.action != self.target_id:
                    q = edge.reward + self.gamma * self._known[edge.child][0]
                else:
                    q = edge.reward
                if best is None or q > best_value:
                    best, best_value = edge, q
            changed = best_value != self._known[k][0]
            self._known[k] = (best_value, best)
            if changed:
                stack.extend(edge.parent for edge in self._in_edges.get(k, ()))

    def failed_actions(self, key: NodeKey) -> set[str]:
        """Actions already tried unsuccessfully from this node (reward -1)."""
        return {a for a, edge in self._nodes[key].children.items() if not edge.feasible}

    # -- growth and learning ---------------------------------------------------------------------

    def add_edge(self, parent: NodeKey, action: str, reward: float) -> tuple[Edge, bool]:
        """Create the edge (parent, action), initialised to its reward (Sect. 3.2, case (i)).

        Args:
            parent: key of an existing, non-terminal node.
            action: object id; not yet relocated in the parent's sequence.
            reward: r(s, a) of eq. (8).

        Returns:
            The new edge and whether a new child node was created (always True without set
            sharing; False when the child set was already reached by another order).

        Raises:
            ValueError: the edge exists, the parent is terminal or ``action`` was relocated.
        """
        node = self._nodes[parent]
        if action in node.children:
            raise ValueError(f'edge {parent} -> {action!r} exists already')
        if node.terminal:
            raise ValueError(f'node {parent} is terminal')
        if action in node.sequence:
            raise ValueError(f'{action!r} was already relocated in {node.sequence}')
        sequence = (*node.sequence, action)
        feasible = reward > REWARD_INFEASIBLE
        if feasible or not self.share_sets:
            child_key = self.key_of(sequence)
        else:  # never merge a failed attempt with a feasible node of the same set
            child_key = (*parent, INFEASIBLE_MARK + action)
        created = child_key not in self._nodes
        if created:
            terminal = (not feasible) or action == self.target_id
            self._nodes[child_key] = TreeNode(child_key, sequence, len(sequence), terminal)
            self._known[child_key] = (0.0, None)
            for key in self._untried_parents(child_key):  # valued gamma r_T until now
                self._invalidate(key)
        q = reward
        if self.optimistic_over is not None and feasible and action != self.target_id:
            q = reward + self.gamma * self.value(child_key)  # optimistic initial value
        edge = Edge(parent, action, child_key, reward, q=q)
        node.children[action] = edge
        self._num_edges += 1
        self._q_bar += abs(edge.q)
        self._invalidate(parent)  # ``action`` is tried from the parent now
        if feasible and action != self.target_id:
            self._in_edges.setdefault(child_key, []).append(edge)
        self._refresh_known(parent)
        return edge, created

    def update(self, edge: Edge) -> float:
        """Revisit an edge: Bellman update of eq. (5) (Sect. 3.2, case (ii)).

        Implements eq. (5): Q <- Q + alpha (r + gamma max_a' Q(s', a') - Q).

        Args:
            edge: an edge of this tree.

        Returns:
            The change of Q [reward units].
        """
        target = edge.reward + self.gamma * self.value(edge.child)
        delta = self.alpha * (target - edge.q)
        self._q_bar += abs(edge.q + delta) - abs(edge.q)
        edge.q += delta
        edge.visits += 1
        self._invalidate(edge.parent)
        return delta

    def sweep(self) -> None:
        """Bellman backup of every edge, deepest first: the alpha = 1 fixed point of eq. (5).

        Sets each feasible edge to r + gamma max_a' Q(s', a') using only what the tree already
        knows (no planner call), i.e. the steady-state values of eqs. (16)-(17) on the explored
        tree. Children are always one level deeper than their parent, so one pass in decreasing
        depth order is exact, for the tree and for the set-shared DAG alike. Used by H-EG-SET
        before extraction (not part of the paper).
        """
        for node in sorted(self._nodes.values(), key=lambda n: n.depth, reverse=True):
            for edge in node.children.values():
                if edge.feasible and edge.action != self.target_id:
                    edge.q = edge.reward + self.gamma * self.max_q(edge.child)
        self._memo.clear()
        self.recompute_q_bar()

    def recompute_q_bar(self) -> float:
        """Recompute eq. (10) from scratch (removes floating-point drift); returns it."""
        self._q_bar = sum(abs(edge.q) for edge in self.edges())
        return self._q_bar
