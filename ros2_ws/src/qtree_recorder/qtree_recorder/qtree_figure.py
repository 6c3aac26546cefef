"""The learned Q-tree drawn like Figure 3 of the paper: layout and pruning core, plus a PNG.

Input is the recorded ``qtree_msgs/msg/QTree`` in plain form: ``node_sequences`` (node i's
relocated ids joined by ','; node 0 is the root s_H) and one tuple per edge
``(parent, child, object_id, q, on_best_path[, reward])``. Levels are rows (level = depth from
the root, the target node of a sequence of m objects at level m). A large tree is pruned to the
``top_k`` nodes per level with the highest incoming Q among the children of kept nodes; the nodes
on the highlighted (extracted) path are always kept; what was left out is counted per level.

With set sharing (H-EG-SET) the "tree" is a DAG: each node is laid out under the parent of its
first incoming edge, the other incoming edges are drawn as well when both ends are kept.

No ROS and no matplotlib import at module level; :func:`save_png` imports matplotlib.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

ROOT_LABEL = 's_H'
TARGET_REWARD = 100.0  # r_T of eq. (8): a target edge's Q stays exactly r_T
KIND_FEASIBLE, KIND_INFEASIBLE, KIND_TARGET = 'feasible', 'infeasible', 'target'
DEFAULT_TOP_K = 4

EdgeTuple = tuple  # (parent, child, object_id, q, on_best_path[, reward])


@dataclass(frozen=True)
class DrawEdge:
    """One drawn edge.

    Attributes:
        parent: index of the parent node (in the message).
        child: index of the child node.
        object_id: the relocated object (the action).
        q: Q(s, a) [reward units].
        kind: ``'feasible'`` (obstacle relocated), ``'infeasible'`` (reward -1) or ``'target'``
            (the target relocated).
        highlighted: on the extracted sequence.
        tree_edge: the layout edge of the child (False: an extra DAG edge).
    """

    parent: int
    child: int
    object_id: str
    q: float
    kind: str
    highlighted: bool
    tree_edge: bool = True

    @property
    def label(self) -> str:
        """``O3 Q=+72.90``."""
        return f'{self.object_id} Q={self.q:+.2f}'


@dataclass
class TreeDrawing:
    """A laid-out, pruned Q-tree.

    Attributes:
        positions: kept node index -> (x, level); x in leaf slots (0, 1, 2, ...), level >= 0.
        labels: kept node index -> short label (the last relocated object, ``s_H`` for the root).
        edges: kept edges (both ends kept).
        path: node indices of the highlighted path, root first.
        omitted_per_level: level -> nodes left out at that level (pruned or below a pruned one).
        total_nodes: nodes in the message.
        total_edges: edges in the message.
        top_k: the pruning parameter.
    """

    positions: dict[int, tuple[float, int]]
    labels: dict[int, str]
    edges: list[DrawEdge]
    path: list[int]
    omitted_per_level: dict[int, int] = field(default_factory=dict)
    total_nodes: int = 0
    total_edges: int = 0
    top_k: int = DEFAULT_TOP_K

    @property
    def omitted_nodes(self) -> int:
        """Nodes left out."""
        return self.total_nodes - len(self.positions)

    @property
    def omitted_edges(self) -> int:
        """Edges left out."""
        return self.total_edges - len(self.edges)

    @property
    def levels(self) -> int:
        """Number of rows (deepest kept level + 1)."""
        return 1 + max((level for _, level in self.positions.values()), default=0)

    def note(self) -> str:
        """What was left out, e.g. ``pruned to the top 5 nodes per level by Q: 120 of 160 nodes
        and 121 of 163 edges not drawn (level 2: 30, level 3: 90)``; ``''`` when nothing was.
        """
        if not self.omitted_nodes and not self.omitted_edges:
            return ''
        per_level = ', '.join(
            f'level {level}: {count}' for level, count in sorted(self.omitted_per_level.items())
        )
        return (
            f'pruned to the top {self.top_k} nodes per level by Q (extracted path always kept): '
            f'{self.omitted_nodes} of {self.total_nodes} nodes and {self.omitted_edges} of '
            f'{self.total_edges} edges not drawn' + (f' ({per_level})' if per_level else '')
        )


def _kind(object_id: str, q: float, reward: float | None, target_id: str | None) -> str:
    value = q if reward is None else reward
    if value < 0.0:
        return KIND_INFEASIBLE
    if object_id == target_id:
        return KIND_TARGET
    return KIND_FEASIBLE


def infer_target(edges: Sequence[EdgeTuple]) -> str | None:
    """The target id: the object of an edge with a positive reward (only the target's, eq. 8),
    or, without rewards, of an edge whose Q is r_T.
    """
    for edge in edges:
        if (edge[5] > 0.0) if len(edge) > 5 else (edge[3] >= TARGET_REWARD):
            return str(edge[2])
    return None


def layout_tree(
    node_sequences: Sequence[str],
    edges: Sequence[EdgeTuple],
    *,
    top_k: int = DEFAULT_TOP_K,
    target_id: str | None = None,
) -> TreeDrawing:
    """Prune and lay out a recorded Q-tree (see the module docstring).

    Args:
        node_sequences: node i's sequence (ids joined by ','); node 0 is the root.
        edges: ``(parent, child, object_id, q, on_best_path[, reward])`` per edge, in creation
            order; indices out of range are ignored.
        top_k: nodes kept per level (>= 1), highlighted-path nodes come on top.
        target_id: the target's id (inferred from the r_T edges when None).

    Returns:
        The drawing (positions in leaf slots and levels).

    Raises:
        ValueError: ``top_k < 1``.
    """
    if top_k < 1:
        raise ValueError(f'top_k must be >= 1, got {top_k}')
    count = len(node_sequences)
    target_id = target_id if target_id is not None else infer_target(edges)
    valid = [e for e in edges if 0 <= int(e[0]) < count and 0 <= int(e[1]) < count]
    # spanning tree: a node hangs under the parent of its first incoming edge
    tree_parent: dict[int, int] = {}
    children: dict[int, list[int]] = {}
    incoming_q: dict[int, float] = {}
    for e in valid:
        parent, child = int(e[0]), int(e[1])
        if child != 0 and child not in tree_parent:
            tree_parent[child] = parent
            incoming_q[child] = float(e[3])
            children.setdefault(parent, []).append(child)
    path = _highlighted_path(valid)
    on_path = set(path)
    kept: dict[int, int] = {0: 0} if count else {}  # node -> level
    omitted: dict[int, int] = {}
    frontier = [0] if count else []
    level = 0
    while frontier:
        level += 1
        candidates = [c for p in frontier for c in children.get(p, [])]
        ranked = sorted(candidates, key=lambda c: (c not in on_path, -incoming_q[c]))
        chosen = ranked[:top_k] + [c for c in ranked[top_k:] if c in on_path]
        dropped = [c for c in candidates if c not in set(chosen)]
        if dropped:
            omitted[level] = omitted.get(level, 0) + len(dropped)
            _count_below(dropped, children, level, omitted)
        chosen_set = set(chosen)
        for c in candidates:  # keep creation order among the kept siblings
            if c in chosen_set:
                kept[c] = level
        frontier = [c for c in candidates if c in chosen_set]
    positions = _positions(kept, children)
    labels = {i: _label(node_sequences[i]) for i in kept}
    path_edges = set(itertools.pairwise(path))
    drawn = []
    for e in valid:
        parent, child = int(e[0]), int(e[1])
        if parent in kept and child in kept:
            reward = float(e[5]) if len(e) > 5 else None
            drawn.append(
                DrawEdge(
                    parent,
                    child,
                    str(e[2]),
                    float(e[3]),
                    _kind(str(e[2]), float(e[3]), reward, target_id),
                    (parent, child) in path_edges,
                    tree_parent.get(child) == parent,
                )
            )
    return TreeDrawing(positions, labels, drawn, path, omitted, count, len(edges), top_k)


def _highlighted_path(edges: Sequence[EdgeTuple]) -> list[int]:
    """Root-first node indices along the ``on_best_path`` edges."""
    best = {int(e[0]): int(e[1]) for e in edges if bool(e[4])}
    path = [0]
    while path[-1] in best and best[path[-1]] not in path:
        path.append(best[path[-1]])
    return path if len(path) > 1 else []


def _count_below(
    dropped: list[int], children: dict[int, list[int]], level: int, omitted: dict[int, int]
) -> None:
    """Add the descendants of the dropped nodes to the per-level counts."""
    layer = [c for d in dropped for c in children.get(d, [])]
    while layer:
        level += 1
        omitted[level] = omitted.get(level, 0) + len(layer)
        layer = [c for d in layer for c in children.get(d, [])]


def _positions(kept: dict[int, int], children: dict[int, list[int]]) -> dict[int, tuple]:
    """Tidy top-down layout: leaves in DFS order get slots 0, 1, 2, ...; parents centred."""
    positions: dict[int, tuple[float, int]] = {}
    next_slot = 0.0
    if not kept:
        return positions
    stack: list[tuple[int, bool]] = [(0, False)]
    while stack:
        node, expanded = stack.pop()
        kids = [k for k in children.get(node, []) if k in kept]
        if kids and not expanded:
            stack.append((node, True))
            stack.extend((k, False) for k in reversed(kids))
            continue
        if kids:
            x = sum(positions[k][0] for k in kids) / len(kids)
        else:
            x, next_slot = next_slot, next_slot + 1.0
        positions[node] = (x, kept[node])
    return positions


def _label(sequence: str) -> str:
    return sequence.split(',')[-1] if sequence else ROOT_LABEL


STYLE = {  # kind -> (colour, line style, width)
    KIND_FEASIBLE: ('#7f7f7f', '-', 1.0),
    KIND_INFEASIBLE: ('#d62728', ':', 1.0),
    KIND_TARGET: ('#2ca02c', '-', 1.8),
}
HIGHLIGHT = '#ff7f0e'


def save_png(drawing: TreeDrawing, path: Path | str, *, title: str = 'Q-tree') -> Path:
    """Draw the tree (levels as rows, edges labelled with Q, styled by kind, extracted path
    highlighted, the pruning note below) and write a PNG; returns the path.
    """
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    path = Path(path)
    width = max((x for x, _ in drawing.positions.values()), default=0.0) + 1.0
    fig, ax = plt.subplots(figsize=(min(40.0, 2.0 + 1.3 * width), 1.6 + 1.2 * drawing.levels))
    for edge in drawing.edges:
        (x0, y0), (x1, y1) = drawing.positions[edge.parent], drawing.positions[edge.child]
        color, style, lw = STYLE[edge.kind]
        if edge.highlighted:
            ax.plot([x0, x1], [y0, y1], color=HIGHLIGHT, lw=6, alpha=0.45, zorder=1)
        ax.plot([x0, x1], [y0, y1], color=color, ls=style, lw=lw if edge.tree_edge else 0.6,
                zorder=2)  # fmt: skip
        ax.text((x0 + x1) / 2, (y0 + y1) / 2, f'{edge.q:+.1f}', fontsize=6, ha='center',
                va='center', color=color, zorder=4,
                bbox={'fc': 'white', 'ec': 'none', 'pad': 0.3, 'alpha': 0.8})  # fmt: skip
    on_path = set(drawing.path)
    for node, (x, y) in drawing.positions.items():
        highlighted = node in on_path
        color = HIGHLIGHT if highlighted else '#dbe9f6'
        size = 260 if highlighted else 150
        ax.scatter([x], [y], s=size, zorder=3, color=color, edgecolors='#1f3b57')
        ax.text(x, y, drawing.labels[node], fontsize=7, ha='center', va='center', zorder=5)
    ax.set_yticks(range(drawing.levels), [f'level {i}' for i in range(drawing.levels)])
    ax.invert_yaxis()
    ax.set_xticks([])
    for side in ('top', 'right', 'bottom'):
        ax.spines[side].set_visible(False)
    ax.set_xlim(-0.7, width - 0.3)
    legend = [
        Line2D([], [], color=STYLE[KIND_FEASIBLE][0], label='obstacle relocated (r = 0)'),
        Line2D([], [], color=STYLE[KIND_INFEASIBLE][0], ls=':', label='infeasible (r = -1)'),
        Line2D([], [], color=STYLE[KIND_TARGET][0], lw=1.8, label='target relocated (r = 100)'),
        Line2D([], [], color=HIGHLIGHT, lw=6, alpha=0.45, label='extracted sequence (eq. 19)'),
    ]
    ax.set_title(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.legend(handles=legend, loc='lower center', bbox_to_anchor=(0.5, 0.03), ncol=4,
               fontsize=7, frameon=False)  # fmt: skip
    note = drawing.note() or f'all {drawing.total_nodes} nodes and {drawing.total_edges} edges'
    fig.text(0.01, 0.008, note, fontsize=7, ha='left', va='bottom', wrap=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def tree_png_from_message(msg, path: Path | str, *, top_k: int = DEFAULT_TOP_K,
                          title: str | None = None) -> Path:  # fmt: skip
    """Draw a decoded ``qtree_msgs/msg/QTree`` (attribute access) to a PNG."""
    edges = [(int(e.parent), int(e.child), str(e.object_id), float(e.q), bool(e.on_best_path),
              float(e.reward)) for e in msg.edges]  # fmt: skip
    drawing = layout_tree(list(msg.node_sequences), edges, top_k=top_k)
    sequence = ' -> '.join(drawing.labels[i] for i in drawing.path[1:]) or '(none)'
    title = title or f'Q-tree after episode {int(msg.episode)}: extracted {sequence}'
    return save_png(drawing, path, title=title)


def tree_png_from_run(run, path: Path | str, *, top_k: int = DEFAULT_TOP_K) -> Path:
    """Draw the LAST recorded /qtree snapshot of a run (the final tree after training).

    Args:
        run: a :class:`qtree_recorder.mcap_reader.McapRun`.
        path: output PNG.
        top_k: nodes kept per level.

    Raises:
        ReplayError: the log has no /qtree message.
    """
    from qtree_recorder.mcap_reader import ReplayError

    last = None
    for decoded in run.messages(['/qtree']):
        last = decoded.message
    if last is None:
        raise ReplayError(f'{run.path} has no /qtree message (no training recorded)')
    return tree_png_from_message(last, path, top_k=top_k)


def tree_png_beside(mcap: Path | str, *, top_k: int = DEFAULT_TOP_K) -> Path:
    """Draw a run's final Q-tree to ``<log stem>_qtree.png`` beside the MCAP (the demo's call).

    Raises:
        ReplayError: unreadable log or no /qtree message.
    """
    from qtree_recorder.mcap_reader import open_run

    mcap = Path(mcap)
    return tree_png_from_run(open_run(mcap), mcap.with_name(f'{mcap.stem}_qtree.png'), top_k=top_k)
