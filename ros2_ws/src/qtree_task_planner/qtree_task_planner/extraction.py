"""Retrieval of the learned sequence, eq. (19), and the steady-state value of eq. (17).

Tree level convention used everywhere in this package: the level of a target node is its tree
depth, ``len(sequence)`` with the target included (Figure 3: the target leaves of a complete tree
with N_o obstacles are at level N_o + 1). With eq. (5), at steady state every edge on a path to a
target node at level m converges to gamma^(levels left - 1) r_T, so the root edge of an optimal
branch holds gamma^(m - 1) r_T. The paper writes eq. (17) as gamma^m r_T, i.e. it counts m as the
number of obstacles before T; :func:`steady_state_root_q` takes our level and documents both.
"""

from __future__ import annotations

from qtree_task_planner.rewards import REWARD_TARGET
from qtree_task_planner.tree import Edge, NodeKey, QTree


def greedy_path(tree: QTree) -> list[Edge]:
    """Edges chosen from the root by a* = argmax_a Q(s, a), eq. (19), until a terminal node.

    Ties are broken by the earliest-created edge (deterministic).

    Args:
        tree: a trained Q-Tree.

    Returns:
        The edges walked, possibly ending at a failed edge or a node without edges.
    """
    path: list[Edge] = []
    key: NodeKey = ()
    while True:
        node = tree.node(key)
        if node.terminal or not node.children:
            return path
        best = max(node.children.values(), key=lambda edge: edge.q)  # eq. (19)
        path.append(best)
        key = best.child


def extract_sequence(tree: QTree) -> tuple[str, ...]:
    """The learned (sub-)optimal sequence, eq. (19): obstacles to relocate, then the target.

    Args:
        tree: a trained Q-Tree.

    Returns:
        The greedy sequence if it ends with a feasible target edge, else ``()`` (no solution
        learned yet).
    """
    path = greedy_path(tree)
    if not path or path[-1].action != tree.target_id or not path[-1].feasible:
        return ()
    return tuple(edge.action for edge in path)


EXTRACTION_EQ19 = 'eq19'
EXTRACTION_FALLBACK = 'best-known-fallback'
EXTRACTION_NONE = 'none'


def extract(tree: QTree) -> tuple[tuple[str, ...], str]:
    """The learned sequence and how it was found: eq. (19), else the best known sequence.

    Eq. (19) can return nothing although episodes reached the target: for the paper's policies
    the reward of the target propagates one edge per revisit, so after a short training the root
    edges may all still hold 0 and the greedy walk (ties: first edge) ends in a dead branch. Then
    the best explored target-reaching sequence (:func:`best_known_sequence`) is returned,
    labelled ``'best-known-fallback'``.

    Returns:
        (sequence, method): method is ``'eq19'``, ``'best-known-fallback'`` or ``'none'``
        (``sequence == ()``: no explored sequence reaches the target).
    """
    sequence = extract_sequence(tree)
    if sequence:
        return sequence, EXTRACTION_EQ19
    sequence = best_known_sequence(tree)
    return sequence, EXTRACTION_FALLBACK if sequence else EXTRACTION_NONE


def path_of(tree: QTree, sequence: tuple[str, ...]) -> list[Edge]:
    """The edges that ``sequence`` walks from the root (stops where the tree has no such edge)."""
    path: list[Edge] = []
    key: NodeKey = ()
    for action in sequence:
        if key not in tree:
            break
        edge = tree.node(key).children.get(action)
        if edge is None:
            break
        path.append(edge)
        key = edge.child
    return path


def best_known_sequence(tree: QTree) -> tuple[str, ...]:
    """Eq. (19) on the steady-state values of what the tree knows, without modifying it.

    Follows, from the root, the edge maximising r + gamma V(s') with V(s) = max_a [r + gamma V(s')]
    over the explored edges (the values :meth:`QTree.sweep` would write, optimism ignored; ties to
    the earliest-created edge). The tree keeps these values up to date as edges are added
    (:meth:`QTree.known_choice`), so this is O(depth), not a sort of every node per episode.
    Used for the per-episode best sequence of H-EG-SET, whose Q values are optimistic.

    Returns:
        The best explored sequence ending with a feasible target edge, or ``()``.
    """
    sequence: list[str] = []
    key: NodeKey = ()
    while (edge := tree.known_choice(key)) is not None:
        sequence.append(edge.action)
        if edge.action == tree.target_id:
            return tuple(sequence) if edge.feasible else ()
        if not edge.feasible:
            return ()
        key = edge.child
    return ()


def steady_state_root_q(level: int, gamma: float, reward_target: float = REWARD_TARGET) -> float:
    """Steady-state Q of the root edge of a branch whose target node is at ``level``, eq. (17).

    Implements eq. (17) with our level convention: gamma^(level - 1) r_T (the paper's gamma^m r_T
    with m = level - 1 obstacles before the target).

    Args:
        level: depth of the target node (sequence length, target included), >= 1.
        gamma: discount of eq. (5).
        reward_target: r_T of eq. (8).

    Returns:
        The root edge value [reward units].
    """
    if level < 1:
        raise ValueError(f'level must be >= 1, got {level}')
    return gamma ** (level - 1) * reward_target


def path_values_at_steady_state(level: int, gamma: float) -> list[float]:
    """Steady-state Q of each edge along a path to a target node at ``level`` (eq. (16) chained).

    Returns:
        ``level`` values, root edge first, the target edge (r_T) last.
    """
    return [steady_state_root_q(level - i, gamma) for i in range(level)]
