"""Ask the motion planner questions in a given order; print each answer's fingerprint (JSON).

Usage: python determinism_worker.py SCENARIO ORDER_SEED N  (see test_determinism.py)
"""

from __future__ import annotations

import hashlib
import itertools
import json
import random
import sys

from qtree_scene.scenario import load_scenario
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.planner import MotionPlanner


def questions(scenario_name: str, n: int) -> list[tuple[tuple[str, ...], str]]:
    """The first ``n`` (relocated set, object) questions of the scene, in a fixed order."""
    scenario = load_scenario(scenario_name)
    movable = [o.id for o in scenario.objects if o.role == 'obstacle']
    target = next(o.id for o in scenario.objects if o.role == 'target')
    out = []
    for k in range(len(movable)):
        for relocated in itertools.combinations(movable, k):
            for obj in [*[m for m in movable if m not in relocated], target]:
                out.append((relocated, obj))
    return random.Random(0).sample(out, n)


def main(scenario_name: str, order_seed: int, n: int) -> None:
    asked = questions(scenario_name, n)
    random.Random(order_seed).shuffle(asked)
    planner = MotionPlanner(load_scenario(scenario_name), PlannerConfig(time_limit_s=120.0))
    answers = {}
    for relocated, obj in asked:
        result = planner.check(obj, relocated)
        trajectory = b'' if result.joint_trajectory is None else result.joint_trajectory.tobytes()
        digest = hashlib.sha1(trajectory).hexdigest()[:12]
        answers[f'{"+".join(relocated)}|{obj}'] = [int(result.reason), digest]
    print(json.dumps(answers))


if __name__ == '__main__':
    main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))
