"""The orchestration script: starts the whole graph with the ament-index fallback of ``ros2 run``,
runs a training to the end, and stops every node cleanly, also on Ctrl-C.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from qtree_node_support.orchestration import node_command

REPO_ROOT = Path(__file__).resolve().parents[1]
DEMO = REPO_ROOT / 'scripts' / 'run_demo.py'
NODE_EXECUTABLES = ('sim_node', 'motion_planner_node', 'task_planner_node', 'recorder_node')


def _node_pids(domain_id: int) -> list[int]:
    """PIDs of running qtree-tamp node processes on ROS domain ``domain_id``."""
    pids = []
    marker = f'ROS_DOMAIN_ID={domain_id}'.encode()
    for entry in Path('/proc').iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / 'cmdline').read_bytes().replace(b'\0', b' ').decode()
            environ = (entry / 'environ').read_bytes().split(b'\0')
        except OSError:
            continue
        if marker in environ and any(exe in cmdline for exe in NODE_EXECUTABLES):
            pids.append(int(entry.name))
    return pids


def test_node_command_resolves_like_ros2_run() -> None:
    command = node_command('jaco2_sim', 'sim_node', {'scenario': 's2', 'sim_rate_hz': 50.0})
    assert command[0].endswith('/lib/jaco2_sim/sim_node')
    assert os.access(command[0], os.X_OK)
    assert command[1:] == ['--ros-args', '-p', "scenario:='s2'", '-p', 'sim_rate_hz:=50.0']


def test_demo_rejects_bad_command_line() -> None:
    result = subprocess.run(
        [sys.executable, str(DEMO), '--max-episodes', '0'], capture_output=True, text=True
    )
    assert result.returncode == 2
    assert '--max-episodes must be > 0' in result.stderr
    assert 'Traceback' not in result.stderr


@pytest.mark.parametrize(
    ('events', 'message'),
    [
        ('[{kind: move, object: O9, xy: [0.7, 0.0], at_s: 1}]', "unknown object 'O9'"),
        ('[{kind: move, object: O5, xy: [0.8, 0.0], at_s: 1}]', "xy: 'O5' overlaps 'T'"),
        ('[{kind: grasp_failure, object: T, attempt: 0}]', 'scene_events[0].attempt'),
        ('{kind: move}', 'a list of events expected'),
    ],
)
def test_demo_refuses_bad_scene_events_before_starting_a_node(events: str, message: str) -> None:
    """A typo in ``--scene-events`` is a command-line error naming the field (exit 2), found
    with the simulator's own parser before any node starts."""
    result = subprocess.run(
        [sys.executable, str(DEMO), '--scenario', 's1', '--scene-events', events],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2, result.stdout + result.stderr
    assert message in result.stderr and '--scene-events: ' in result.stderr, result.stderr
    assert 'Traceback' not in result.stderr and 'starting the node graph' not in result.stdout


def test_demo_trains_and_stops_cleanly(ros_domain: int, tmp_path: Path) -> None:
    result = subprocess.run(
        [
            sys.executable,
            str(DEMO),
            '--headless',
            '--no-execute',
            '--scenario',
            's1',
            '--seed',
            '1',
            '--output-dir',
            str(tmp_path),
            '--timeout',
            '300',
        ],
        capture_output=True,
        text=True,
        timeout=420,
        cwd=tmp_path,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, output[-4000:]
    assert 'result:    success' in output
    assert 'nodes that did not exit cleanly' not in output
    mcaps = list(tmp_path.glob('qtree_*_s1.mcap'))
    assert len(mcaps) == 1 and mcaps[0].stat().st_size > 1000, output[-2000:]
    assert list(tmp_path.glob('qtree_*_s1.rrd')), 'the headless demo writes a .rrd file'
    assert not _node_pids(ros_domain), 'a node outlived the demo'


def test_demo_ctrl_c_stops_every_node(ros_domain: int, tmp_path: Path) -> None:
    process = subprocess.Popen(
        [
            sys.executable,
            str(DEMO),
            '--headless',
            '--scenario',
            's3',
            '--max-episodes',
            '5000',
            '--output-dir',
            str(tmp_path),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        cwd=tmp_path,
    )
    deadline = time.monotonic() + 120
    lines = []
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        lines.append(line)
        if 'nodes ready' in line or process.poll() is not None:
            break
    assert any('nodes ready' in line for line in lines), ''.join(lines)
    time.sleep(2.0)
    process.send_signal(signal.SIGINT)
    try:
        rest, _ = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail('the demo did not stop within 60 s of Ctrl-C')
    output = ''.join(lines) + rest
    assert process.returncode == 130, output[-3000:]
    assert 'interrupted: stopping every node' in output
    assert 'nodes that did not exit cleanly' not in output, output[-3000:]
    assert 'Traceback' not in output, output[-3000:]
    assert not _node_pids(ros_domain), 'a node outlived the demo'
    assert list(tmp_path.glob('qtree_*_s3.mcap')), 'the recording is kept after Ctrl-C'


def test_ctrl_c_right_after_rclpy_init_is_an_interrupt(monkeypatch) -> None:
    """The suite of 9ffde18: a SIGINT between ``rclpy.init()`` and ``create_node`` (rclpy's
    handler shuts the context down) ended the demo with RCLError and exit code 1, not 130."""
    import argparse

    import rclpy
    from qtree_benchmarks import demo_goal

    real_init = rclpy.init

    def init_then_sigint(*args, **kwargs):
        real_init(*args, **kwargs)
        rclpy.shutdown()  # what rclpy's SIGINT handler does

    monkeypatch.setattr(rclpy, 'init', init_then_sigint)
    args = argparse.Namespace(timeout=5.0)
    with pytest.raises(KeyboardInterrupt):
        demo_goal.retrieve_target(args, [])
