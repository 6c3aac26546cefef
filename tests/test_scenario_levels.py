"""The three scenarios have the paper's difficulty (level, ξ_p, ξ*), from the geometry (#31).

The motion planner is the oracle of an exact breadth-first search over sets of relocated
objects; nothing here says which object occludes which.
"""

from __future__ import annotations

import pytest
from qtree_scene.scenario import load_scenario
from qtree_task_planner.exact import count_feasible_sequences, solve_exact
from qtree_task_planner.oracle import MotionPlannerOracle

# scenario -> (obstacles, optimal level = depth of the target node, target included, ξ_p, ξ*)
EXPECTED = {'s1': (5, 4, 10, 1), 's2': (10, 5, 20, 1), 's3': (15, 6, 20, 1)}


@pytest.mark.parametrize('name', sorted(EXPECTED))
def test_optimal_level_comes_from_the_geometry(name: str) -> None:
    scenario = load_scenario(name)
    n_obstacles, level, xi_p, xi_star = EXPECTED[name]
    assert len(scenario.obstacles) == n_obstacles
    oracle = MotionPlannerOracle(scenario)
    solution = solve_exact(tuple(o.id for o in scenario.obstacles), scenario.target.id, oracle)
    assert solution.level == level, solution
    assert solution.sequence[-1] == scenario.target.id
    # the sequence really is feasible step by step, and no shorter prefix reaches the target
    for index, object_id in enumerate(solution.sequence):
        assert oracle.feasible(solution.sequence[:index], object_id)
    assert not oracle.feasible((), scenario.target.id)
    counts = count_feasible_sequences(
        tuple(o.id for o in scenario.obstacles), scenario.target.id, oracle
    )
    assert (counts.feasible, counts.optimal, min(counts.by_level)) == (xi_p, xi_star, level)
