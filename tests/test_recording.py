"""A real run of jaco2_sim + recorder: the MCAP opens in rosbags and Rerun with the arm moving.

(a) rosbags ``AnyReader`` reads every message, topics and counts are as expected, the final joint
state is the commanded goal; (b) ``rerun mcap convert`` gives ``Transform3D`` rows for the arm's
links and the URDF geometry, with no unresolved channel; (c) every channel carries
``offered_qos_profiles`` and the file has the ``rosbag2`` record; (d) a SIGKILLed recorder leaves
a file that reads and converts up to its last complete chunk.
"""

from __future__ import annotations

import json
import re
import struct
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

RERUN = str(Path(sys.executable).with_name('rerun'))
ARM = [f'j2s7s300_joint_{i}' for i in range(1, 8)]
DELTA = np.array([0.3, 0.1, -0.2, 0.1, 0.1, -0.1, 0.2])  # [rad] commanded motion
MOVE_S = 1.2  # [s] trajectory duration (joint 1 needs >= 0.48 s at 0.6283 rad/s)


def start_graph(launch: Any, out: Path, file_name: str, **extra: Any) -> tuple[Any, Any]:
    sim = launch('jaco2_sim', 'sim_node', parameters={'sim_rate_hz': 100.0})
    recorder = launch('qtree_recorder', 'recorder_node', parameters={
        'output_dir': str(out), 'file_name': file_name, 'scenario': 's1',
        'discovery_period_s': 0.2,
        'run_metadata': json.dumps({'policy': 'H-EG', 'seed': 3, 'parameters': {'a': 0.5}}),
        **extra,
    })  # fmt: skip
    sim.wait_for_log('ready', timeout_s=40.0)
    recorder.wait_for_log('recorder ready', timeout_s=40.0)
    for topic in ('/joint_states', '/robot_description', '/scene'):
        recorder.wait_for_log(f'recording {topic} ', timeout_s=20.0)
    return sim, recorder


def rerun_convert(mcap: Path, *extra: str) -> tuple[str, str]:
    """Convert to .rrd; return the converter's log and ``rerun rrd print`` of the result."""
    rrd = mcap.with_suffix('.rrd')
    convert = subprocess.run([RERUN, 'mcap', 'convert', str(mcap), '-o', str(rrd),
                              '--application-id', 'qtree_test', *extra],
                             capture_output=True, text=True, timeout=120)  # fmt: skip
    assert convert.returncode == 0, convert.stderr[-2000:]
    printed = subprocess.run([RERUN, 'rrd', 'print', str(rrd)], capture_output=True, text=True,
                             timeout=120)  # fmt: skip
    assert printed.returncode == 0, printed.stderr[-2000:]
    return convert.stdout + convert.stderr, printed.stdout + printed.stderr


def rows(printed: str, entity: str, column: str) -> int:
    """Rows of ``entity`` chunks that carry ``column`` in ``rerun rrd print`` output."""
    pattern = re.compile(rf'with (\d+) rows .* - {re.escape(entity)} - data columns: \[(.*)\]')
    return sum(int(m[1]) for m in pattern.finditer(printed) if column in m[2])


def test_real_run_reads_everywhere(launch: Any, ros_node: Any, tmp_path: Path) -> None:
    from qtree_msgs.msg import TrainingStats
    from qtree_recorder.qos import parse_qos_yaml
    from rosbags.highlevel import AnyReader
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    live = tmp_path / 'live.rrd'
    _, recorder = start_graph(launch, tmp_path, 'run.mcap', rerun_mode='save', rrd_path=str(live))
    states: list[np.ndarray] = []
    ros_node.create_subscription(
        JointState, '/joint_states', lambda m: states.append(np.array(m.position[:7])), 10
    )
    trajectory_pub = ros_node.create_publisher(JointTrajectory, '/joint_trajectory', 10)
    stats_pub = ros_node.create_publisher(TrainingStats, '/training_stats', 10)
    assert ros_node.spin_until(lambda: bool(states), 20.0)
    recorder.wait_for_log('recording /joint_trajectory ', timeout_s=20.0)
    recorder.wait_for_log('recording /training_stats ', timeout_s=20.0)
    # sim and recorder subscribed to /joint_trajectory, recorder to /training_stats
    assert ros_node.spin_until(lambda: trajectory_pub.get_subscription_count() >= 2, 20.0)
    ros_node.wait_matched(stats_pub)
    goal = states[-1] + DELTA
    point = JointTrajectoryPoint(positions=[float(v) for v in goal])
    point.time_from_start.sec, point.time_from_start.nanosec = 1, int((MOVE_S - 1) * 1e9)
    trajectory_pub.publish(JointTrajectory(joint_names=ARM, points=[point]))
    for episode in range(3):
        stats_pub.publish(TrainingStats(policy='H-EG', episode=episode, q_bar=0.5 * episode))
    assert ros_node.spin_until(lambda: np.max(np.abs(states[-1] - goal)) < 1e-3, 15.0)
    ros_node.spin_until(lambda: False, 0.5)
    code = recorder.stop()
    output = recorder.log_path.read_text()  # the log file is closed after stop()
    assert code == 0, output[-3000:]
    path = tmp_path / 'run.mcap'
    assert f'recording to {path}' in output and 'recording finished' in output

    # (a) every message decodes; topics, counts, final state.
    counts: Counter[str] = Counter()
    last: dict[str, Any] = {}
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            last[connection.topic] = reader.deserialize(raw, connection.msgtype)
            counts[connection.topic] += 1
    assert counts['/robot_description'] == 1 and counts['/tf_static'] == 1
    assert counts['/joint_trajectory'] == 1 and counts['/training_stats'] == 3
    assert counts['/scene'] >= 1 and counts['/scene_markers'] == counts['/scene']
    assert counts['/joint_states'] >= 150  # >= 1.5 s at 100 Hz
    arm_tf = counts['/tf'] - counts['/scene']  # object frames come with each /scene
    assert 0.1 * counts['/joint_states'] <= arm_tf <= 0.45 * counts['/joint_states']  # 30 Hz
    np.testing.assert_allclose(last['/joint_states'].position[:7], goal, atol=2e-3)
    assert '<robot name="j2s7s300"' in last['/robot_description'].data
    assert last['/training_stats'].q_bar == 1.0

    # (c) QoS metadata on every channel, the rosbag2 record, the run metadata.
    from mcap.reader import make_reader

    with open(path, 'rb') as stream:
        mcap = make_reader(stream)
        summary = mcap.get_summary()
        records = {m.name: m.metadata for m in mcap.iter_metadata()}
    channels = {c.topic: c for c in summary.channels.values()}
    for channel in channels.values():
        assert parse_qos_yaml(channel.metadata['offered_qos_profiles']), channel.topic
    for topic in ('/scene', '/robot_description', '/tf_static'):
        qos = parse_qos_yaml(channels[topic].metadata['offered_qos_profiles'])
        assert qos[0].durability == 'transient_local', topic
    for topic in ('/joint_states', '/scene', '/training_stats', '/scene_markers'):
        assert channels[topic].metadata['topic_type_hash'].startswith('RIHS01_'), topic
    bag = yaml.safe_load(records['rosbag2']['serialized_metadata'])
    assert bag['message_count'] == sum(counts.values()) == summary.statistics.message_count
    topic_counts = {t['topic_metadata']['name']: t['message_count']
                    for t in bag['topics_with_message_count']}  # fmt: skip
    assert topic_counts == dict(counts)
    assert records['qtree_run']['policy'] == 'H-EG' and records['qtree_run']['scenario'] == 's1'

    # (b) Rerun: URDF geometry and one Transform3D row per arm link and /tf message.
    log, printed = rerun_convert(path)
    assert not re.search(r'(could not|cannot) (be )?resolve', log + printed, re.IGNORECASE)
    assert '/j2s7s300/visual_geometries/j2s7s300_link_7' in log
    assert rows(printed, '/tf', 'Transform3D:child_frame') >= 13 * arm_tf
    assert rows(printed, '/tf_static', 'Transform3D:child_frame') == 2
    for topic in ('/training_stats', '/scene', '/joint_trajectory'):
        assert re.search(rf' - {topic} - data columns: \[(?!McapChannel)', printed), topic

    # The live Rerun view hosted by the recorder: the arm's joints and the training curves.
    printed_live = subprocess.run([RERUN, 'rrd', 'print', str(live)], capture_output=True,
                                  text=True, timeout=120).stdout  # fmt: skip
    assert rows(printed_live, '/tf/j2s7s300_joint_1', 'Transform3D') >= 100
    assert rows(printed_live, '/stats/q_bar', 'Scalars') == 3


def test_sigkilled_recorder_leaves_a_readable_file(launch: Any, tmp_path: Path) -> None:
    from mcap.exceptions import McapError
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    _, recorder = start_graph(launch, tmp_path, 'killed.mcap')
    time.sleep(2.5)  # > 2 flush intervals of 1 s
    recorder.kill()
    path = tmp_path / 'killed.mcap'
    topics: dict[int, str] = {}
    counts: Counter[str] = Counter()
    with open(path, 'rb') as stream:
        try:
            for record in StreamReader(stream).records:
                if isinstance(record, Channel):
                    topics[record.id] = record.topic
                elif isinstance(record, Message):
                    counts[topics[record.channel_id]] += 1
        except (McapError, EOFError, ValueError, struct.error):
            pass  # the chunk being written when the process died
    assert counts['/robot_description'] == 1 and counts['/tf_static'] == 1
    assert counts['/joint_states'] >= 100 and counts['/tf'] >= 25
    log, printed = rerun_convert(path, '--recover')
    assert '/j2s7s300/visual_geometries/j2s7s300_link_7' in log
    assert rows(printed, '/tf', 'Transform3D:child_frame') >= 13 * 25


@pytest.mark.parametrize('bad', ['{not json'])
def test_bad_parameters_keep_the_recorder_running(launch: Any, tmp_path: Path, bad: str) -> None:
    blocker = tmp_path / 'a_file'
    blocker.write_text('x')
    recorder = launch('qtree_recorder', 'recorder_node', parameters={
        'output_dir': str(blocker), 'run_metadata': bad, 'rerun_mode': 'bogus',
        'tf_rate_hz': -3.0})  # fmt: skip
    recorder.wait_for_log('recorder ready', timeout_s=40.0)
    text = recorder.log_text()
    assert 'run_metadata is not valid JSON' in text
    assert 'not recording: cannot open MCAP file' in text
    assert "rerun_mode must be one of off, save, spawn, got 'bogus'" in text
    assert 'tf_rate_hz must be >= 0' in text
    assert recorder.alive()
