"""scripts/replay.py as a user runs it: --summary, --rerun, --publish and bad input."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
REPLAY = REPO_ROOT / 'scripts' / 'replay.py'
FIXTURES = REPO_ROOT / 'ros2_ws' / 'src' / 'qtree_recorder' / 'test' / 'replay_fixtures.py'


def _load_fixtures() -> Any:
    name = 'qtree_recorder_replay_fixtures'
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, FIXTURES)
        sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    return sys.modules[name]


FX = _load_fixtures()


def replay(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """Run ``python scripts/replay.py ARGS`` in this test's environment."""
    env = dict(os.environ, RERUN_ANALYTICS='0', PYTHONUNBUFFERED='1')
    return subprocess.run(
        [sys.executable, str(REPLAY), *args],
        capture_output=True, text=True, timeout=timeout, env=env, cwd=REPO_ROOT,
    )  # fmt: skip


@pytest.fixture
def log(tmp_path: Path) -> Path:
    from jaco2_description.model import urdf_text

    path = tmp_path / 'run.mcap'
    FX.write_run(path, urdf_text=urdf_text())
    return path


def test_help_documents_every_option() -> None:
    result = replay('--help')
    assert result.returncode == 0
    for option in ('--summary', '--rerun', '--rrd', '--spawn', '--publish', '--rate', '--topics',
                   '--screenshot', '--tree-png', '--top-k', 'truncated'):  # fmt: skip
        assert option in result.stdout


def test_summary_lists_topics_and_training_result(log: Path) -> None:
    result = replay(str(log), '--summary')
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert '[complete]' in out
    lines = {
        line.split()[0]: line.split()[1:] for line in out.splitlines() if line.startswith('  /')
    }
    assert lines['/joint_states'] == ['sensor_msgs/msg/JointState', '20']
    assert lines['/motion_planner/events'] == ['qtree_msgs/msg/PlanningEvent', '4']
    assert 'metadata qtree_run: scenario=fixture' in out
    assert 'metadata rosbag2: version=9' in out
    assert 'duration: 1.050 s' in out
    assert 'episodes recorded: 4 (last episode 3, policy H-eG)' in out
    assert 'best sequence: O2 -> T' in out
    assert 'planner events: 4 (2 feasible, 2 infeasible)' in out
    assert result.stderr == ''


def test_rerun_conversion_writes_the_live_view(log: Path, tmp_path: Path) -> None:
    rrd = tmp_path / 'out.rrd'
    result = replay(str(log), '--rerun', '--rrd', str(rrd))
    assert result.returncode == 0, result.stderr
    assert f'wrote {rrd} (35 messages)' in result.stdout
    entities = FX.rrd_entities(rrd)
    expected = {
        '/j2s7s300/visual_geometries/j2s7s300_link_7/visual_0', '/tf/j2s7s300_joint_4',
        '/scene/objects/T', '/scene/objects/O2', '/scene/objects/table', '/scene/drop_zone',
        '/plans/O1', '/events', '/qtree/nodes', '/qtree/edges', '/stats/q_bar',
        '/stats/mp_calls', '/stats/epsilon',
    }  # fmt: skip
    assert expected <= entities, expected - entities
    assert len(FX.rrd_column(rrd, '/tf/j2s7s300_joint_4', 'Transform3D:translation')) == 20
    assert len(FX.rrd_column(rrd, '/stats/epsilon', 'Scalars:scalars')) == 4


def test_tree_png_draws_the_last_recorded_tree(log: Path, tmp_path: Path) -> None:
    png = tmp_path / 'tree.png'
    result = replay('--tree-png', str(png), str(log))
    assert result.returncode == 0, result.stderr
    assert png.stat().st_size > 5000 and f'wrote {png}' in result.stdout
    from qtree_recorder.mcap_reader import open_run
    from qtree_recorder.qtree_figure import KIND_INFEASIBLE, KIND_TARGET, layout_tree

    last = list(open_run(log).messages(['/qtree']))[-1].message
    edges = [(e.parent, e.child, e.object_id, e.q, e.on_best_path, e.reward) for e in last.edges]
    drawing = layout_tree(list(last.node_sequences), edges)
    assert drawing.path == [0, 2, 3]
    assert [e.kind for e in drawing.edges] == [KIND_INFEASIBLE, 'feasible', KIND_TARGET]
    bad = replay('--tree-png', str(png), str(log), '--top-k', '0')
    assert bad.returncode == 2 and '--top-k' in bad.stderr


def test_truncated_log_replays_with_a_warning(tmp_path: Path) -> None:
    path = tmp_path / 'killed.mcap'
    FX.write_run(path, joint_states=60, chunk_size=2048, close=False)
    path.write_bytes(path.read_bytes()[: int(path.stat().st_size * 0.6)])
    result = replay(str(path), '--summary')
    assert result.returncode == 0, result.stderr
    assert 'TRUNCATED' in result.stdout
    assert 'warning:' in result.stderr and 'truncated' in result.stderr
    count = int(next(line for line in result.stdout.splitlines()
                     if line.startswith('  /joint_states')).split()[-1])  # fmt: skip
    assert 0 < count < 60
    rrd = tmp_path / 'killed.rrd'
    assert replay(str(path), '--rerun', '--rrd', str(rrd), '-q').returncode == 0
    assert '/tf/j2s7s300_joint_1' in FX.rrd_entities(rrd)


def _bad_inputs(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    good = tmp_path / 'good.mcap'
    FX.write_run(good)
    text = tmp_path / 'notes.mcap'
    text.write_text('not a log\n')
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(good.read_bytes()[:40])
    other = tmp_path / 'other.mcap'
    FX.write_run(other, robot_prefix='panda_')
    return {
        'missing': (tmp_path / 'missing.mcap', 'no such file'),
        'not mcap': (text, 'not an MCAP file'),
        'truncated before data': (cut, 'truncated before the first complete chunk'),
        'other robot': (other, 'another robot'),
    }


@pytest.mark.parametrize('case', ['missing', 'not mcap', 'truncated before data', 'other robot'])
@pytest.mark.parametrize('mode', ['--summary', '--rerun'])
def test_bad_input_gives_one_clean_line(tmp_path: Path, case: str, mode: str) -> None:
    path, message = _bad_inputs(tmp_path)[case]
    result = replay(str(path), mode, '--rrd', str(tmp_path / 'x.rrd')) if mode == '--rerun' \
        else replay(str(path), mode)  # fmt: skip
    assert result.returncode == 2
    assert 'Traceback' not in result.stderr + result.stdout
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('replay.py: error: ')
    assert message in lines[0]
    assert not (tmp_path / 'x.rrd').exists()


def test_publish_replays_the_recorded_joint_states(log: Path, ros_node: Any) -> None:
    from sensor_msgs.msg import JointState

    received: list[JointState] = []
    ros_node.create_subscription(JointState, '/joint_states', received.append, 50)
    process = subprocess.Popen(
        [sys.executable, str(REPLAY), str(log), '--publish', '--rate', '4', '--topics',
         '/joint_states', '/scene', '--wait-subscribers', '10'],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO_ROOT,
    )  # fmt: skip
    try:
        assert ros_node.spin_until(lambda: len(received) >= 20, timeout_s=30)
        out, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0, err
    assert 'published 22 messages on 2 topics' in out
    assert len(received) == 20
    assert received[0].name[0] == 'j2s7s300_joint_1'
    assert received[-1].position[0] == pytest.approx(FX.HOME[0])


def test_summary_and_rerun_show_a_replan_on_the_timeline(tmp_path: Path) -> None:
    """#32 item 5: a recording with a scene event and a re-plan shows both, in time order."""
    from jaco2_description.model import urdf_text

    log = tmp_path / 'world.mcap'
    FX.write_run(log, urdf_text=urdf_text(), world=True)
    result = replay(str(log), '--summary')
    assert result.returncode == 0, result.stderr
    out = result.stdout.splitlines()
    start = out.index('changing world: 4 events')
    lines = out[start + 1 : start + 5]
    assert "scene: 'O3' moved 0.100 m" in lines[0]  # O2 carried away is not a scene event
    assert "motion planner: SCENE_CHANGED relocating 'T'" in lines[1]
    assert "re-plan 1 started: SCENE_CHANGED relocating 'T'" in lines[2]
    assert 'done so far: O2' in lines[2]
    assert "re-plan 1 planned: kept ['O2'], then O3 -> T; 3 answers reused" in lines[3]
    times = [float(line.split()[0].lstrip('+')) for line in lines]
    assert times == sorted(times) and times[0] > 1.0
    plain = tmp_path / 'plain.mcap'
    FX.write_run(plain, urdf_text=urdf_text())
    assert 'changing world: no events' in replay(str(plain), '--summary').stdout
    rrd = tmp_path / 'world.rrd'
    assert replay(str(log), '--rerun', '--rrd', str(rrd)).returncode == 0
    texts = [str(t) for t in FX.rrd_column(rrd, '/events/world', 'TextLog:text')]
    assert len(texts) == 4 and 're-plan 1 planned' in texts[-1], texts
