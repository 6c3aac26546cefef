"""Figure 3 of the paper for recorded trees: layout and pruning core (not pixels)."""

from pathlib import Path

import pytest
from qtree_recorder.qtree_figure import (
    KIND_FEASIBLE,
    KIND_INFEASIBLE,
    KIND_TARGET,
    layout_tree,
    save_png,
)

# Hand-built tree: root -> O1, O2, T(-1); O1 -> T(100), O2; O2 -> O1, T(-1); O2,O1 -> T(100).
NODES = ['', 'O1', 'O2', '!T', 'O1,T', 'O1,O2', 'O2,O1', 'O2,!T', 'O2,O1,T']
EDGES = [
    (0, 1, 'O1', 90.0, True, 0.0),
    (0, 2, 'O2', 72.0, False, 0.0),
    (0, 3, 'T', -1.0, False, -1.0),
    (1, 4, 'T', 100.0, True, 100.0),
    (1, 5, 'O2', 0.0, False, 0.0),
    (2, 6, 'O1', 80.0, False, 0.0),
    (2, 7, 'T', -1.0, False, -1.0),
    (6, 8, 'T', 100.0, False, 100.0),
]


def test_whole_tree_counts_kinds_levels_and_highlighted_path() -> None:
    drawing = layout_tree(NODES, EDGES, top_k=10)
    assert len(drawing.positions) == 9 and len(drawing.edges) == 8
    assert drawing.omitted_nodes == drawing.omitted_edges == 0 and drawing.note() == ''
    assert drawing.path == [0, 1, 4]
    assert [(e.parent, e.child) for e in drawing.edges if e.highlighted] == [(0, 1), (1, 4)]
    kinds = {(e.parent, e.child): e.kind for e in drawing.edges}
    assert kinds[(0, 3)] == kinds[(2, 7)] == KIND_INFEASIBLE
    assert kinds[(1, 4)] == kinds[(6, 8)] == KIND_TARGET
    assert kinds[(0, 1)] == kinds[(6, 8)].replace(KIND_TARGET, KIND_FEASIBLE)
    levels = {node: level for node, (_, level) in drawing.positions.items()}
    assert levels == {0: 0, 1: 1, 2: 1, 3: 1, 4: 2, 5: 2, 6: 2, 7: 2, 8: 3}
    assert drawing.labels[0] == 's_H' and drawing.labels[8] == 'T'
    xs = {node: x for node, (x, _) in drawing.positions.items()}
    assert len({xs[n] for n in (3, 4, 5, 7, 8)}) == 5  # leaves apart
    assert xs[1] == pytest.approx((xs[4] + xs[5]) / 2)  # parent centred over its children
    assert drawing.edges[0].label == 'O1 Q=+90.00'


def test_pruning_keeps_top_k_per_level_and_the_path_and_counts_what_is_left_out() -> None:
    drawing = layout_tree(NODES, EDGES, top_k=1)
    # level 1: O1 (on the path) only; O2 (72) and !T dropped, with O2's 3 descendants
    assert set(drawing.positions) == {0, 1, 4}
    assert drawing.path == [0, 1, 4] and len(drawing.edges) == 2
    assert drawing.omitted_per_level == {1: 2, 2: 3, 3: 1}
    assert drawing.omitted_nodes == 6 and drawing.omitted_edges == 6
    assert 'top 1 nodes per level' in drawing.note() and '6 of 9 nodes' in drawing.note()
    two = layout_tree(NODES, EDGES, top_k=2)
    assert set(two.positions) == {0, 1, 2, 4, 6, 8}  # by Q: O1, O2; then T (100), O1 (80)
    assert two.omitted_per_level == {1: 1, 2: 2}


def test_a_set_shared_dag_draws_the_extra_edge_and_rejects_bad_k(tmp_path: Path) -> None:
    nodes = ['', 'O1', 'O2', 'O1,O2', 'O1,O2,T']
    edges = [(0, 1, 'O1', 81.0, True), (0, 2, 'O2', 81.0, False), (1, 3, 'O2', 90.0, True),
             (2, 3, 'O1', 90.0, False), (3, 4, 'T', 100.0, True)]  # fmt: skip
    drawing = layout_tree(nodes, edges)
    assert len(drawing.edges) == 5 and drawing.path == [0, 1, 3, 4]
    assert [e.tree_edge for e in drawing.edges] == [True, True, True, False, True]
    assert save_png(drawing, tmp_path / 'tree.png').stat().st_size > 1000
    with pytest.raises(ValueError, match='top_k'):
        layout_tree(nodes, edges, top_k=0)
