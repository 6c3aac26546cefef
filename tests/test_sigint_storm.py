"""#26: SIGINT delivered 200 times to each node at random moments always ends it with exit code 0.

Each node runs in processes of its own (``tests/sigint_storm.py``), started and interrupted
``STORM_RUNS`` times in all, with the garbage collector running every few allocations and a
thread dropping ``rclpy.task.Future`` cycles, so signals land in start-up, callbacks,
destructors, spinning and cleanup. Before #26 the handler raised ``KeyboardInterrupt``; one
landing in ``Future.__del__`` was dropped and the node spun until it was killed.

The runs are split over ``STORM_SHARDS`` processes at once, with DDS discovery off
(``ROS_AUTOMATIC_DISCOVERY_RANGE=OFF``: a storm node talks to nobody, so shards cannot meet):
one after the other, 200 runs of a node took 100-170 s of mostly idle waiting for the signal,
and the four storms were 5-10 minutes of the README's test command (the CI budget is 20 min).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

STORM_RUNS = int(os.environ.get('QTREE_STORM_RUNS', '200'))
STORM_SHARDS = 4  # processes sharing a node's runs, at once
MAX_STOP_S = 5.0  # bound on one stop; measured worst 0.6 s loaded (docs/RELIABILITY.md) [s]
SCRIPT = Path(__file__).with_name('sigint_storm.py')
NODES = ['sim_node', 'motion_planner_node', 'task_planner_node', 'recorder_node']


def _storm(node: str, runs: int, seed: int, output: Path) -> subprocess.Popen:
    """Start one shard: ``runs`` interrupted runs of ``node``, results in ``output``."""
    output.parent.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'OFF'}
    return subprocess.Popen(
        [sys.executable, str(SCRIPT), node, str(runs), str(seed), str(output)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


@pytest.mark.timeout(900)
@pytest.mark.parametrize('node', NODES)
def test_sigint_at_random_moments_always_exits_0(node: str, ros_domain: int, tmp_path) -> None:
    shares = [
        STORM_RUNS // STORM_SHARDS + (i < STORM_RUNS % STORM_SHARDS) for i in range(STORM_SHARDS)
    ]
    outputs = [tmp_path / f'shard{i}' / 'storm.json' for i in range(STORM_SHARDS)]
    shards = [
        _storm(node, runs, ros_domain * 100 + i, out)
        for i, (runs, out) in enumerate(zip(shares, outputs, strict=True))
        if runs
    ]
    errors = [shard.communicate(timeout=850)[1] for shard in shards]
    for shard, stderr in zip(shards, errors, strict=True):
        assert shard.returncode == 0, stderr[-3000:]
    codes: list[int] = []
    stop_s: list[float] = []
    landed = 0
    for out in outputs[: len(shards)]:
        storm = json.loads(out.read_text())
        codes += storm['codes']
        stop_s += storm['stop_s']
        landed += sum(storm['landed'].values())
    failed = [(i, code) for i, code in enumerate(codes) if code != 0]
    assert len(codes) == STORM_RUNS and not failed, (failed, [e[-1500:] for e in errors])
    assert max(stop_s) < MAX_STOP_S, sorted(stop_s)[-5:]
    assert landed == STORM_RUNS  # every signal reached the handler
