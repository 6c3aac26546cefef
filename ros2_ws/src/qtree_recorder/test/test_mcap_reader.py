"""Tests of the run-log reader: complete, truncated and bad files (no rclpy)."""

from __future__ import annotations

import importlib.util
import logging
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from qtree_recorder.mcap_reader import (
    CorruptLogError,
    LogNotFoundError,
    NoReadableTopicsError,
    NotMcapError,
    ReplayError,
    WrongRobotError,
    open_run,
)


def _load_fixtures():
    name = 'qtree_recorder_replay_fixtures'
    if name not in sys.modules:
        path = Path(__file__).with_name('replay_fixtures.py')
        spec = importlib.util.spec_from_file_location(name, path)
        sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    return sys.modules[name]


FX = _load_fixtures()
SMALL_CHUNK = 2048  # [bytes]: many chunks in a small log


@pytest.fixture
def log(tmp_path: Path) -> Path:
    path = tmp_path / 'run.mcap'
    FX.write_run(path, urdf_text='<robot name="j2s7s300"></robot>')
    return path


def test_complete_log_gives_topics_metadata_and_messages(log: Path) -> None:
    run = open_run(log)
    assert not run.truncated and run.profile == 'ros2' and not run.warnings
    counts = {name: topic.count for name, topic in run.topics.items()}
    assert counts == {'/robot_description': 1, '/scene': 2, '/joint_states': 20,
                      '/motion_planner/events': 4, '/qtree': 4, '/training_stats': 4}  # fmt: skip
    assert run.topics['/joint_states'].type == 'sensor_msgs/msg/JointState'
    assert 'transient_local' in run.topics['/scene'].qos_profiles
    assert 'volatile' in run.topics['/joint_states'].qos_profiles
    assert 'builtin_interfaces/Time' in run.topics['/joint_states'].definition
    assert {'rosbag2', 'qtree_run'} <= set(run.metadata)
    assert run.metadata['qtree_run']['seed'] == '7'
    assert run.start_ns == FX.T0_NS
    assert run.duration_s == pytest.approx(21 * FX.JOINT_PERIOD_NS * 1e-9)
    scenes = list(run.messages(['/scene']))
    assert [o.id for o in scenes[-1].message.objects] == ['table', 'T', 'O1', 'O2', 'O3']
    assert scenes[-1].message.objects[3].status == 2  # O2 relocated
    raw = list(run.raw_messages(['/joint_states']))
    assert len(raw) == 20 and all(m.data[:4] == b'\x00\x01\x00\x00' for m in raw)
    assert [m.log_time_ns for m in raw] == sorted(m.log_time_ns for m in raw)
    assert sum(1 for _ in run.messages()) == run.message_count == 35


def _expected_after_truncation(reference: Path, length: int) -> int:
    """Messages of the chunks that end within ``length`` bytes (from the reference's summary)."""
    with reference.open('rb') as handle:
        reader = make_reader(handle)
        indexes = reader.get_summary().chunk_indexes
        complete = [c for c in indexes if c.chunk_start_offset + c.chunk_length <= length]
        if not complete:
            return 0
        end = max(c.message_end_time for c in complete)
        return sum(1 for _, _, m in reader.iter_messages() if m.log_time <= end)


@pytest.mark.parametrize('fraction', [0.35, 0.6, 0.97])
def test_truncated_log_is_read_up_to_its_last_complete_chunk(
    tmp_path: Path, fraction: float
) -> None:
    reference, killed = tmp_path / 'reference.mcap', tmp_path / 'killed.mcap'
    FX.write_run(reference, joint_states=60, chunk_size=SMALL_CHUNK)
    FX.write_run(killed, joint_states=60, chunk_size=SMALL_CHUNK, close=False)
    length = int(killed.stat().st_size * fraction)
    killed.write_bytes(killed.read_bytes()[:length])
    expected = _expected_after_truncation(reference, length)
    assert 0 < expected < 60 + 14
    run = open_run(killed)
    assert run.truncated
    assert any('truncated' in w for w in run.warnings)
    assert run.message_count == expected
    assert sum(1 for _ in run.messages()) == expected


def test_unclosed_log_without_summary_reads_everything(tmp_path: Path) -> None:
    path = tmp_path / 'killed.mcap'
    FX.write_run(path, chunk_size=SMALL_CHUNK, close=False)
    run = open_run(path)
    assert run.truncated and run.message_count == 34  # every message (no /robot_description)
    assert 'rosbag2' not in run.metadata


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(LogNotFoundError, match='no such file'):
        open_run(tmp_path / 'nope.mcap')


@pytest.mark.parametrize('content', [b'', b'hello, this is not a log\n', b'\x89MCAP1\r\n'])
def test_not_an_mcap(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / 'x.mcap'
    path.write_bytes(content)
    with pytest.raises(NotMcapError, match='not an MCAP'):
        open_run(path)


def test_truncated_before_any_chunk_is_corrupt(log: Path) -> None:
    log.write_bytes(log.read_bytes()[:60])
    with pytest.raises(CorruptLogError, match='before the first complete chunk'):
        open_run(log)


def test_damaged_chunk_is_corrupt(log: Path) -> None:
    data = bytearray(log.read_bytes())
    with log.open('rb') as handle:
        first = make_reader(handle).get_summary().chunk_indexes[0]
    middle = first.chunk_start_offset + first.chunk_length // 2
    data[middle : middle + 16] = bytes(16)
    log.write_bytes(bytes(data))
    with pytest.raises(CorruptLogError, match='chunk at byte'):
        open_run(log)


def test_garbage_record_is_corrupt(log: Path) -> None:
    data = log.read_bytes()
    log.write_bytes(data[:8] + b'\x00' * 64 + data[8:])
    with pytest.raises(CorruptLogError, match='invalid record opcode 0'):
        open_run(log)


def test_log_of_another_robot(tmp_path: Path) -> None:
    path = tmp_path / 'ur5.mcap'
    FX.write_run(path, robot_prefix='ur5_')
    with pytest.raises(WrongRobotError, match=r'another robot .*ur5_joint_1'):
        open_run(path)


def test_robot_description_of_another_robot(tmp_path: Path) -> None:
    path = tmp_path / 'panda.mcap'
    FX.write_run(path, joint_states=0, urdf_text='<robot name="panda"><link name="a"/></robot>')
    with pytest.raises(WrongRobotError, match="'panda'"):
        open_run(path)


def _write_foreign(path: Path, with_ros_channel: bool) -> None:
    with path.open('wb') as handle:
        writer = Writer(handle)
        writer.start(profile='ros2', library='test')
        json_schema = writer.register_schema('Foo', 'jsonschema', b'{}')
        json_channel = writer.register_channel('/foo', 'json', json_schema)
        broken = writer.register_schema('pkg/msg/Bar', 'ros2msg', b'nosuchpkg/Baz baz\n')
        broken_channel = writer.register_channel('/bar', 'cdr', broken)
        writer.add_message(json_channel, FX.T0_NS, b'{}', FX.T0_NS)
        writer.add_message(broken_channel, FX.T0_NS, b'\x00\x01\x00\x00', FX.T0_NS)
        if with_ros_channel:
            string = writer.register_schema('std_msgs/msg/String', 'ros2msg', b'string data\n')
            channel = writer.register_channel('/chatter', 'cdr', string, {})
            cdr = b'\x00\x01\x00\x00' + (3).to_bytes(4, 'little') + b'hi\x00'
            writer.add_message(channel, FX.T0_NS + 1, cdr, FX.T0_NS + 1)
        writer.finish()


def test_unknown_schemas_are_skipped_with_one_warning(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / 'mixed.mcap'
    _write_foreign(path, with_ros_channel=True)
    with caplog.at_level(logging.WARNING):
        run = open_run(path)
    assert list(run.topics) == ['/chatter']
    assert [m.message.data for m in run.messages()] == ['hi']
    skipped = [w for w in run.warnings if 'unknown' in w]
    assert len(skipped) == 1 and '/bar' in skipped[0] and '/foo' in skipped[0]
    assert sum('unknown' in r.getMessage() for r in caplog.records) == 1


def test_only_unknown_schemas(tmp_path: Path) -> None:
    path = tmp_path / 'foreign.mcap'
    _write_foreign(path, with_ros_channel=False)
    with pytest.raises(NoReadableTopicsError):
        open_run(path)


def test_every_error_is_a_replay_error() -> None:
    for error in (LogNotFoundError, NotMcapError, CorruptLogError, WrongRobotError,
                  NoReadableTopicsError):  # fmt: skip
        assert issubclass(error, ReplayError)
