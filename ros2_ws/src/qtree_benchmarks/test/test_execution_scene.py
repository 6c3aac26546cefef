"""The in-process executor checks every object standing, those on drop slots included (#29)."""

from __future__ import annotations

from qtree_benchmarks.motion.execution import DISTURBANCES, Executor
from qtree_scene.scenario import load_scenario
from stpik_motion_planner.planner import MotionPlanner


def test_an_object_on_the_drop_slot_in_the_path_stops_the_arm_before_penetrating(robot):
    """#29 point 5: the executor's live scene left out the objects already on their drop slots.

    O2 is planned into slot 0 (nothing relocated yet) and executed as if O3 had been relocated
    first, so O3 stands on slot 0, where the carried O2 is set down. Before the fix the closed
    loop did not see O3 and completed the relocation through it; now the obstacle task holds
    the arm and the loop stops with O3 named. The controller's carried body was SETTLE_M = 20 mm
    short at each end against everything, so the carried bottom still went 7.5 mm into O3; now it
    is short only against static bodies and the arm stops with it 3.7 mm from O3 (deterministic:
    simulated time).
    """
    scenario = load_scenario('s1')
    planner = MotionPlanner(scenario, model=robot)
    planner.blockers.enabled = False
    result = planner.check('O2', [])
    assert result.feasible, result.message
    run = Executor(scenario, ['O3'], 'O2', result, DISTURBANCES['none'], robot=robot)
    assert 'O3' in run.scene.objects  # standing on slot 0
    out = run.run('closed_loop')
    assert not out.completed
    assert 'O3' in out.failure, out.failure
    assert out.min_clearance_m > 0.0015 and out.min_clearance_pair == 'attached / O3'
