"""Room for 30 relocations (#13 item 2): every drop slot of a 30-object scene is reachable.

The object O6 of ``generate_clutter(30, 0.1, 4, layout='uniform')`` (feasible in the untouched
scene) is relocated after k = 0 … 29 others, so into slot k with slots 0 … k−1 standing as the
occupied envelopes:
every plan passes the planner's independent verifier (it returns no trajectory otherwise) and
releases on its slot. Relocation 31 (the target after the 30 obstacles) is ``NO_PLACEMENT``.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from jaco2_description.model import HOME
from qtree_scene.generator import generate_clutter
from qtree_scene.placement import drop_slots
from qtree_scene.scene import ObjectSpec, Scenario
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import Reason
from stpik_motion_planner.verifier import Carried, TrajectoryVerifier

# Layouts before #31 re-laid S1-S3: the regressions below were measured on them.
SCENES = pathlib.Path(__file__).parent / 'scenes'

MOVER = 'O6'


@pytest.fixture(scope='module')
def planner(robot):
    return MotionPlanner(generate_clutter(30, 0.1, 4, layout='uniform'), model=robot)


def test_thirty_relocations_each_reach_their_own_slot(planner, robot):
    scenario = planner.scenario
    slots = drop_slots(scenario)
    assert len(slots) >= 30  # no cap of 30 any more (#29): the table area decides
    others = [o.id for o in scenario.objects if o.role != 'static' and o.id != MOVER]
    verifier = TrajectoryVerifier(robot)
    obj = scenario.object(MOVER)
    for k in range(30):
        relocated = others[:k]
        result = planner.plan(MOVER, relocated)
        assert result.feasible, (k, result.message)
        release = robot.ee_pose(result.joint_trajectory[result.release_index]).translation
        assert np.linalg.norm(release[:2] - np.array(slots[k].xy)) < 0.012, k
        if k in (0, 29):  # independently again, against the placed envelopes of slots 0 … k−1
            report = verifier.verify(
                result.joint_trajectory,
                planner.planning_scene(MOVER, relocated),
                Carried(obj, result.grasp_index, result.release_index),
            )
            assert report.ok, report.summary()


def test_relocation_beyond_the_room_is_no_placement(robot):
    from qtree_scene.scenario import load_scenario

    # 15 obstacles, room for 15 (the re-laid s3 has room for 19)
    s3 = MotionPlanner(load_scenario(str(SCENES / 's3_before_31.yaml')), model=robot)
    obstacles = [o.id for o in s3.scenario.obstacles]
    assert len(obstacles) == len(drop_slots(s3.scenario)) == 15
    result = s3.check('T', obstacles)  # the 16th relocation
    assert not result.feasible and result.reason == Reason.NO_PLACEMENT
    assert 'relocation 16 of a scene with room for 15' in result.message
    assert len(result.joint_trajectory) == 0


def test_scene_without_free_table_in_reach_is_no_placement(make_cylinder, robot):
    """A table that ends just beyond the clutter: no slot at all, the first relocation says so."""
    table = ObjectSpec('table', 'static', 'box', (0.6, 0.0, -0.025), size=(0.5, 0.4, 0.05))
    scene = Scenario(
        'no_room',
        (make_cylinder('T', 0.6, 0.0, 'target'), make_cylinder('O1', 0.7, 0.1), table),
        (0.0, 0.5, 0.15),
        (0.3, 0.3, 0.3),
        tuple(float(v) for v in HOME),
    )
    assert drop_slots(scene) == ()
    result = MotionPlanner(scene, model=robot).check('T', [])
    assert not result.feasible and result.reason == Reason.NO_PLACEMENT
    assert 'relocation 1 of a scene with room for 0' in result.message
    assert len(result.joint_trajectory) == 0
