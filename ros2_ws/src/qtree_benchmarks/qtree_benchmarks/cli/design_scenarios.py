"""Lay out the paper's three scenarios and check them with the real motion planner.

The layouts are geometric: a target T at the back of the table, a blocker A in front of it, a
pair B1, B2 in front of A (either one occludes A), for S3 a pair C1, C2 in front of the B pair,
for S2 one C1, and decoy cylinders at the sides that can be relocated but never help. Which object
occludes which is NOT written anywhere: this script asks the motion planner (exact breadth-first
search over sets of relocated objects, ``qtree_task_planner.exact``) and prints the optimal level
(depth of the target node in the Q-tree, target included) and the number of feasible target
sequences xi_p, then writes the YAML files with ``--write``.

``--structures`` prints, for the paper's difficulty of each scene (level, ξ_p, ξ* = 1 of
:data:`PAPER_DIFFICULTY`), the blocking structures that have it (:mod:`..task.scene_structures`):
which object must free which, before any geometry (#31).

Example:
    ./qtree run python scripts/design_scenarios.py               # check
    ./qtree run python scripts/design_scenarios.py --write       # and rewrite s1/s2/s3.yaml
    ./qtree run python scripts/design_scenarios.py --structures  # structures of the paper's
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time

from qtree_scene.scenario import dump_scenario, load_scenario
from qtree_scene.scene import ObjectSpec, Role, Scenario
from qtree_task_planner.exact import count_feasible_sequences, solve_exact
from qtree_task_planner.oracle import MotionPlannerOracle

from qtree_benchmarks.paths import repo_root
from qtree_benchmarks.task.scene_structures import structures

# The paper's scenes: (optimal level with the target, xi_p, xi*) (Sect. 4).
PAPER_DIFFICULTY = {'s1': (4, 10, 1), 's2': (5, 20, 1), 's3': (6, 20, 1)}
SCENARIO_DIR = repo_root() / 'ros2_ws/src/qtree_scene/qtree_scene/scenarios'
RADIUS = 0.03  # cylinder radius [m]

# The occluding core, (x, y) [m] in the robot base frame.
CORE = {
    'T': (0.80, 0.00),
    'A': (0.70, 0.00),
    'B1': (0.60, -0.075),
    'B2': (0.60, 0.075),
    'C1': (0.50, -0.10),
    'C2': (0.50, 0.10),
}
# Decoys at the sides, free to relocate but useless: (range [m], bearing [rad]) from the base.
DECOYS = [(0.62, 0.55), (0.62, -0.55), (0.74, 0.50), (0.74, -0.50)]
# Objects that stay occluded or out of the arm's side-grasp reach, (x, y) [m]: behind the target
# first, then far at the sides.
HIDDEN = [
    (0.90, -0.07),
    (0.90, 0.07),
    (0.86, -0.16),
    (0.86, 0.16),
    (0.92, 0.0),
    (0.84, -0.30),
    (0.92, 0.30),
    (0.92, -0.22),
    (0.20, -0.55),
]
# name -> (core obstacles, number of decoys, number of hidden objects, description)
LAYOUTS = {
    's1': (['A', 'B1', 'B2'], 1, 1, 'Scenario 1 of the paper: 5 obstacles, optimal level 4.'),
    's2': (
        ['A', 'B1', 'B2', 'C1'],
        1,
        5,
        'Scenario 2 of the paper: 10 obstacles, optimal level 5.',
    ),
    's3': (
        ['A', 'B1', 'B2', 'C1', 'C2'],
        1,
        9,
        'Scenario 3 of the paper: 15 obstacles, optimal level 6.',
    ),
}


def cylinder(object_id: str, role: Role, x: float, y: float, height: float) -> ObjectSpec:
    """A cylinder standing on the table (top face z = 0)."""
    return ObjectSpec(
        object_id, role, 'cylinder', (x, y, height / 2), radius=RADIUS, height=height
    )


def layout(name: str) -> Scenario:
    """Build scenario ``name`` from the core and decoy spots."""
    base = load_scenario(name)
    core, n_decoys, n_hidden, description = LAYOUTS[name]
    objects = [o for o in base.objects if o.role == 'static']
    objects.append(cylinder('T', 'target', *CORE['T'], 0.16))
    heights = [0.14, 0.12, 0.15, 0.13]
    obstacles = [(CORE[key][0], CORE[key][1]) for key in core]
    obstacles += [(r * math.cos(b), r * math.sin(b)) for r, b in DECOYS[:n_decoys]]
    obstacles += HIDDEN[:n_hidden]
    for index, (x, y) in enumerate(obstacles, start=1):
        objects.append(cylinder(f'O{index}', 'obstacle', x, y, heights[index % len(heights)]))
    return dataclasses.replace(base, objects=tuple(objects), description=description)


def check(scenario: Scenario) -> dict[str, object]:
    """Optimal level and sequence counts with the real motion planner as oracle."""
    oracle = MotionPlannerOracle(scenario)
    obstacles = tuple(o.id for o in scenario.obstacles)
    start = time.perf_counter()
    exact = solve_exact(obstacles, scenario.target.id, oracle)
    counts = count_feasible_sequences(obstacles, scenario.target.id, oracle)
    return {
        'level': exact.level,
        'sequence': exact.sequence,
        'xi_p': counts.feasible,
        'xi_star': counts.optimal,
        'by_level': dict(sorted(counts.by_level.items())),
        'reachable_sets': counts.reachable_sets,
        'planner_runs': oracle.planner_runs,
        'seconds': round(time.perf_counter() - start, 1),
    }


def main(argv: list[str] | None = None) -> int:
    """Check (and with --write, save) the three layouts; exit 1 if a level is off."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--write', action='store_true', help='rewrite s1/s2/s3.yaml')
    parser.add_argument('--only', nargs='*', default=sorted(LAYOUTS), help='scenarios to do')
    parser.add_argument(
        '--structures', action='store_true', help="print the paper's structures and stop"
    )
    args = parser.parse_args(argv)
    unknown = sorted(set(args.only) - set(LAYOUTS))
    if unknown:
        parser.error(f'--only: unknown scenario {unknown[0]!r} (one of {sorted(LAYOUTS)})')
    if args.structures:
        for name in args.only:
            level, xi_p, _ = PAPER_DIFFICULTY[name]
            found = list(structures(level, xi_p))
            print(f'{name}: level {level}, xi_p {xi_p}, xi* 1: {len(found)} structures')
            for structure in found[:5]:
                print(f'  {structure}')
        return 0
    wanted = {'s1': 4, 's2': 5, 's3': 6}
    ok = True
    for name in args.only:
        scenario = layout(name)
        figures = check(scenario)
        good = figures['level'] == wanted[name]
        ok &= good
        print(f'{name}: {figures}  {"OK" if good else "level should be " + str(wanted[name])}')
        if args.write and good:
            text = dump_scenario(scenario)
            header = (
                f'# {scenario.description}\n'
                '# Laid out by scripts/design_scenarios.py; which object occludes which\n'
                '# comes from the geometry through the motion planner. Lengths [m], angles\n'
                '# [rad]; world frame = robot base frame, table top at z = 0.\n'
                '# Schema: README.md beside this file.\n'
            )
            (SCENARIO_DIR / f'{name}.yaml').write_text(header + text)
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
