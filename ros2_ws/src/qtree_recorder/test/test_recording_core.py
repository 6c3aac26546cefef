"""Derived viewer topics (qtree_recorder.recording) and the node's pure helpers (graph_topics)."""

from __future__ import annotations

import math
from datetime import datetime
from pathlib import Path
from types import SimpleNamespace as Msg

import pytest
from jaco2_description import model as jaco2_model
from qtree_recorder import graph_topics
from qtree_recorder.mcap_log import McapLog
from qtree_recorder.qos import QosProfileData
from qtree_recorder.recording import Recording
from rosbags.highlevel import AnyReader

T0 = 1_700_000_000_000_000_000  # [ns]
ARM = [f'j2s7s300_joint_{i}' for i in range(1, 8)]
EMPTY_STRING_CDR = bytes([0, 1, 0, 0]) + (1).to_bytes(4, 'little') + b'\x00'  # std_msgs/String ''


def read_counts(path: Path) -> dict[str, int]:
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)  # every message decodes
        return {c.topic: c.msgcount for c in reader.connections}


def test_tf_rate_limit_and_buffered_first_state(tmp_path: Path) -> None:
    path = tmp_path / 'r.mcap'
    rec = Recording(McapLog(path), tf_rate_hz=10.0)
    assert not rec.on_joint_state(ARM, [math.pi] * 7, T0)  # no model yet: kept for later
    rec.on_robot_description(jaco2_model.urdf_text(), T0 + 1)  # /tf_static + /tf of that state
    written = [rec.on_joint_state(ARM, [math.pi] * 7, T0 + i * 10_000_000) for i in range(1, 31)]
    assert written.count(True) == 2 and written[10] and written[20]  # 100 Hz in, 10 Hz out
    scene = Msg(objects=[], attached_id='', drop_zone=None, drop_zone_size=None)
    rec.on_scene(scene, T0 + 5)
    rec.close()
    assert read_counts(path) == {'/tf_static': 1, '/tf': 3, '/scene_markers': 1}


def test_bad_urdf_stops_tf_only(tmp_path: Path) -> None:
    warnings: list[str] = []
    path = tmp_path / 'bad.mcap'
    rec = Recording(McapLog(path), tf_rate_hz=0.0, warn=warnings.append)
    rec.on_robot_description('<robot name="broken"><link name="a">', T0)
    assert 'cannot build the /tf model' in rec.tf_error
    for i in range(5):
        rec.on_joint_state(ARM, [0.0] * 7, T0 + i)
        rec.record('/joint_states', 'std_msgs/msg/String', EMPTY_STRING_CDR, T0 + i)
    rec.on_robot_description(jaco2_model.urdf_text(), T0 + 9)  # the first URDF decides
    rec.close()
    assert len(warnings) == 1 and '/tf writer stopped' in warnings[0]
    assert read_counts(path) == {'/joint_states': 5}
    with pytest.raises(ValueError, match='tf_rate_hz'):
        rec.set_tf_rate(-1.0)


def test_topic_selection_and_qos_policy() -> None:
    assert graph_topics.should_record('/joint_states')
    assert graph_topics.should_record('/retrieve_target/_action/feedback')
    assert graph_topics.should_record('/retrieve_target/_action/status')
    for topic in ('/tf', '/tf_static', '/scene_markers', '/parameter_events',
                  '/_hidden', '/retrieve_target/_action/other'):  # fmt: skip
        assert not graph_topics.should_record(topic), topic
    latched = QosProfileData.transient_local()
    volatile_best_effort = QosProfileData(reliability='best_effort')
    assert graph_topics.subscription_policy([latched]) == ('reliable', 'transient_local')
    assert graph_topics.subscription_policy([latched, volatile_best_effort]) == (
        'best_effort', 'volatile')  # fmt: skip


def test_type_paths_file_names_and_metadata() -> None:
    assert graph_topics.python_type_path('sensor_msgs/msg/JointState') == (
        'sensor_msgs.msg', ('JointState',))  # fmt: skip
    assert graph_topics.python_type_path('qtree_msgs/action/RetrieveTarget_FeedbackMessage') == (
        'qtree_msgs.action', ('RetrieveTarget', 'Impl', 'FeedbackMessage'))  # fmt: skip
    with pytest.raises(ValueError, match='unexpected ROS type name'):
        graph_topics.python_type_path('JointState')
    now = datetime(2026, 1, 2, 3, 4, 5)
    assert graph_topics.default_file_name('s1', now) == 'qtree_20260102-030405_s1.mcap'
    assert graph_topics.default_file_name('a b/../c', now) == 'qtree_20260102-030405_a_b_.._c.mcap'
    assert graph_topics.default_file_name('', now) == 'qtree_20260102-030405.mcap'
    assert graph_topics.parse_run_metadata('') == {}
    assert graph_topics.parse_run_metadata('{"seed": 3}') == {'seed': 3}
    for bad in ('{seed: 3}', '[1, 2]'):
        with pytest.raises(ValueError, match='run_metadata'):
            graph_topics.parse_run_metadata(bad)
    record = graph_topics.run_metadata_record(
        's2', {'policy': 'H-EG', 'seed': 4, 'parameters': {'alpha': 0.5}}, {'x': '1'}, 7
    )
    assert record['policy'] == 'H-EG' and record['seed'] == '4'
    assert record['parameters'] == '{"alpha": 0.5}' and record['started_ns'] == '7'


def test_tf_mean_rate_follows_tf_rate_hz(tmp_path: Path) -> None:
    rec = Recording(McapLog(tmp_path / 'rate.mcap'), tf_rate_hz=30.0)
    rec.on_robot_description(jaco2_model.urdf_text(), T0)
    period_ns = 10_600_000  # 94 Hz joint states: 30 Hz is not a divisor of it
    written = sum(rec.on_joint_state(ARM, [3.0] * 7, T0 + i * period_ns) for i in range(189))
    assert written == pytest.approx(60, abs=1)  # 2.0 s at 30 Hz
    rec.close()


def test_start_settings_replace_bad_values() -> None:
    from qtree_recorder.graph_topics import start_settings, tf_rate_problem
    from qtree_recorder.recording import DEFAULT_TF_RATE_HZ

    errors: list[str] = []
    p = {'run_metadata': '{not json', 'tf_rate_hz': -1.0, 'discovery_period_s': 0.0}
    metadata, tf_rate, period = start_settings(p, errors.append)
    assert metadata == {'raw': '{not json'} and tf_rate == DEFAULT_TF_RATE_HZ and period == 0.5
    assert len(errors) == 2 and 'tf_rate_hz must be >= 0' in errors[1]
    good = {'run_metadata': '{"seed": 3}', 'tf_rate_hz': 5.0, 'discovery_period_s': 0.2}
    assert start_settings(good, errors.append) == ({'seed': 3}, 5.0, 0.2) and len(errors) == 2
    assert tf_rate_problem(2) and tf_rate_problem(float('nan')) and not tf_rate_problem(0.0)
