"""#26: only the end of a whole trajectory is an event; streamed references are counted.

Before #26 the closed loop's streamed references (one per control tick) each ended with
"trajectory finished" logged at INFO: hundreds of /rosout lines per execution.
"""

from __future__ import annotations

import numpy as np
from jaco2_description.model import ARM_JOINTS
from jaco2_sim.simulation import Simulation

RATE_HZ = 500.0


def steps_until_idle(sim: Simulation, max_steps: int = 5000) -> list[bool]:
    """Step ``sim`` until its integrator is idle; the ``finished`` flag of every step."""
    flags = []
    for _ in range(max_steps):
        finished, errors = sim.step()
        assert not errors
        flags.append(finished)
        if not sim.sim.active:
            break
    return flags


def test_a_streamed_reference_end_is_counted_not_reported_as_finished() -> None:
    sim = Simulation('s1', RATE_HZ, 0.0)
    home = np.asarray(sim.scenario.home, dtype=float)
    for tick in range(1, 4):  # three control ticks of a closed loop
        assert sim.command_point(list(ARM_JOINTS), list(home + 0.002 * tick)) == ''
        flags = steps_until_idle(sim)
        assert not any(flags)
        assert sim.references_reached == tick


def test_the_end_of_a_whole_trajectory_is_reported_once() -> None:
    sim = Simulation('s1', RATE_HZ, 0.0)
    home = np.asarray(sim.scenario.home, dtype=float)
    positions = [list(home), list(home + 0.05)]
    sim.follow(list(ARM_JOINTS), [0.0, 0.5], positions, None)
    flags = steps_until_idle(sim)
    assert flags.count(True) == 1 and flags[-1]
    assert sim.references_reached == 0
    np.testing.assert_allclose(sim.sim.q, home + 0.05, atol=1e-9)
