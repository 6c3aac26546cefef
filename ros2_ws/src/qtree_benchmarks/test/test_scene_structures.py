"""Blocking structures of the paper's difficulty (#31 item 1): counted exactly, as for a scene."""

from __future__ import annotations

import pytest
from qtree_benchmarks.task.scene_structures import (
    Structure,
    pair_structure_counts,
    structures,
)


def test_the_current_s1_structure_has_two_optimal_sequences() -> None:
    """The pair in front of A gives ξ* = 2: the live planner's figures for S1 (4, 10, 2)."""
    counts = pair_structure_counts(decoys=1)
    assert (counts.feasible, counts.optimal, counts.by_level) == (10, 2, {4: 2, 5: 8})


@pytest.mark.parametrize(('level', 'xi_p'), [(4, 10), (5, 20), (6, 20)])
def test_each_paper_scene_has_a_structure_with_one_optimal_sequence(level, xi_p) -> None:
    found = list(structures(level, xi_p, max_extras=3))
    assert found, (level, xi_p)
    for structure in found:
        counts = structure.counts()
        assert (counts.feasible, counts.optimal, min(counts.by_level)) == (xi_p, 1, level)


def test_the_smallest_structures_are_the_ones_counted_by_hand() -> None:
    """S1: the chain c1 -> c2 -> c3 -> T, e1 freed by c1 and e2 by e1: 1 + 3 + 6 = 10.
    S2: a chain of four, a free decoy and one extra freed by c3. S3: a chain of five, extras
    freed by c1 and by c4."""
    assert next(structures(4, 10)) == Structure(('c1', 'c2', 'c3'), ('c1', 'e1'))
    assert next(structures(5, 20)) == Structure(('c1', 'c2', 'c3', 'c4'), (None, 'c3'))
    assert next(structures(6, 20)) == Structure(('c1', 'c2', 'c3', 'c4', 'c5'), ('c1', 'c4'))
    assert str(next(structures(4, 10))) == 'c1 -> c2 -> c3 -> T; e1 after c1, e2 after e1'


def test_a_chain_alone_has_one_sequence_and_a_free_decoy_adds_one_per_position() -> None:
    assert Structure(('c1', 'c2')).counts().feasible == 1
    assert Structure(('c1', 'c2'), (None,)).counts().feasible == 1 + 3


def test_bad_targets_are_refused() -> None:
    with pytest.raises(ValueError, match='level'):
        next(structures(0, 10))


def test_design_scenarios_prints_the_structures_and_refuses_unknown_scenes(capsys) -> None:
    from qtree_benchmarks.cli import design_scenarios

    assert design_scenarios.main(['--structures', '--only', 's1']) == 0
    out = capsys.readouterr().out
    assert 's1: level 4, xi_p 10, xi* 1: 2 structures' in out
    assert 'c1 -> c2 -> c3 -> T; e1 after c1, e2 after e1' in out
    with pytest.raises(SystemExit):
        design_scenarios.main(['--structures', '--only', 's9'])
    assert "unknown scenario 's9'" in capsys.readouterr().err
