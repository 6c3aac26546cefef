"""#26: SIGINT delivered 200 times to each node at random moments always ends it with exit code 0.

Each node runs in a process of its own (``tests/sigint_storm.py``), started and interrupted
``STORM_RUNS`` times in turn, with the garbage collector running every few allocations and a
thread dropping ``rclpy.task.Future`` cycles, so signals land in start-up, callbacks,
destructors, spinning and cleanup. Before #26 the handler raised ``KeyboardInterrupt``; one
landing in ``Future.__del__`` was dropped and the node spun until it was killed.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

STORM_RUNS = int(os.environ.get('QTREE_STORM_RUNS', '200'))
MAX_STOP_S = 5.0  # bound on one stop; measured worst 0.6 s loaded (docs/RELIABILITY.md) [s]
SCRIPT = Path(__file__).with_name('sigint_storm.py')
NODES = ['sim_node', 'motion_planner_node', 'task_planner_node', 'recorder_node']


@pytest.mark.timeout(900)
@pytest.mark.parametrize('node', NODES)
def test_sigint_at_random_moments_always_exits_0(node: str, ros_domain: int, tmp_path) -> None:
    output = tmp_path / 'storm.json'
    done = subprocess.run(
        [sys.executable, str(SCRIPT), node, str(STORM_RUNS), str(ros_domain), str(output)],
        capture_output=True,
        text=True,
        timeout=850,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    storm = json.loads(output.read_text())
    failed = [(i, code) for i, code in enumerate(storm['codes']) if code != 0]
    assert len(storm['codes']) == STORM_RUNS and not failed, (failed, done.stderr[-3000:])
    assert max(storm['stop_s']) < MAX_STOP_S, sorted(storm['stop_s'])[-5:]
    assert sum(storm['landed'].values()) == STORM_RUNS  # every signal reached the handler
