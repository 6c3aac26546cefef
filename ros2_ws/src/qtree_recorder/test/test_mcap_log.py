"""rosbag2-style MCAP writing (qtree_recorder.mcap_log): round trip, metadata, crash safety."""

from __future__ import annotations

import math
import signal
import struct
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
import yaml
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader
from qtree_recorder.encoding import DynamicEncoder
from qtree_recorder.exceptions import McapWriteError, WriterClosedError
from qtree_recorder.mcap_log import McapLog
from qtree_recorder.qos import INFINITE_NS, QosProfileData, parse_qos_yaml
from rosbags.highlevel import AnyReader

T0 = 1_700_000_000_000_000_000  # [ns] a fixed epoch time
LATCHED = (QosProfileData.transient_local(),)
HASH = 'RIHS01_' + 'ab' * 32


def joint_state(i: int) -> dict:
    stamp = {'sec': (T0 + i) // 10**9, 'nanosec': (T0 + i) % 10**9}
    return {
        'header': {'stamp': stamp, 'frame_id': ''},
        'name': ['j1', 'j2'],
        'position': [0.01 * i, -0.5],
        'velocity': [],
        'effort': [],
    }


def read_complete_chunks(path: Path) -> tuple[list[Message], int]:
    """Messages a streaming reader recovers from a possibly truncated file, and chunk count."""

    def records(emit_chunks: bool) -> list:
        out = []
        with open(path, 'rb') as stream:
            try:
                for record in StreamReader(stream, emit_chunks=emit_chunks).records:
                    out.append(record)
            except (McapError, EOFError, ValueError, OSError, IndexError, struct.error):
                pass  # the truncated tail
        return out

    messages = [r for r in records(False) if isinstance(r, Message)]
    chunks = sum(isinstance(r, Chunk) for r in records(True))
    return messages, chunks


def test_round_trip_with_rosbags_and_metadata(tmp_path: Path) -> None:
    encoder = DynamicEncoder()
    path = tmp_path / 'run.mcap'
    with McapLog(path) as log:
        log.add_metadata('qtree_run', {'scenario': 's1', 'seed': 7, 'parameters': {'a': 1}})
        for i in range(50):
            cdr = encoder.encode('sensor_msgs/msg/JointState', joint_state(i))
            log.write('/joint_states', 'sensor_msgs/msg/JointState', cdr, T0 + i * 10**7,
                      (QosProfileData(),), type_hash=HASH)  # fmt: skip
        description = encoder.encode('std_msgs/msg/String', {'data': '<robot name="r"/>'})
        log.write('/robot_description', 'std_msgs/msg/String', description, T0, LATCHED)
    with AnyReader([path]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert counts == {'/joint_states': 50, '/robot_description': 1}
        positions = []
        for connection, timestamp, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            if connection.topic == '/joint_states':
                positions.append(float(msg.position[0]))
                assert list(msg.name) == ['j1', 'j2'] and timestamp >= T0
            else:
                assert msg.data == '<robot name="r"/>'
        assert positions == pytest.approx([0.01 * i for i in range(50)])

    with open(path, 'rb') as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
        assert summary.statistics.message_count == 51
        schemas = {s.name: s for s in summary.schemas.values()}
        assert schemas['sensor_msgs/msg/JointState'].encoding == 'ros2msg'
        assert b'MSG: builtin_interfaces/Time' in schemas['sensor_msgs/msg/JointState'].data
        for channel in summary.channels.values():
            assert channel.message_encoding == 'cdr'
            assert 'offered_qos_profiles' in channel.metadata
        channels = {c.topic: c for c in summary.channels.values()}
        latched = parse_qos_yaml(channels['/robot_description'].metadata['offered_qos_profiles'])
        assert latched == list(LATCHED)
        assert channels['/joint_states'].metadata['topic_type_hash'] == HASH  # as given
        assert channels['/robot_description'].metadata['topic_type_hash'].startswith('RIHS01_')
        names = [m.name for m in reader.iter_metadata()]
        records = {m.name: m.metadata for m in reader.iter_metadata()}  # the last of each name
    assert names == ['qtree_run', 'rosbag2']  # rosbag2 record at close only
    assert records['qtree_run']['scenario'] == 's1' and records['qtree_run']['seed'] == '7'
    bag = yaml.safe_load(records['rosbag2']['serialized_metadata'])
    assert bag['version'] == 9 and bag['storage_identifier'] == 'mcap'
    assert bag['ros_distro'] == 'jazzy' and bag['message_count'] == 51
    assert bag['relative_file_paths'] == ['run.mcap']
    assert bag['duration']['nanoseconds'] == 49 * 10**7
    assert bag['starting_time']['nanoseconds_since_epoch'] == T0
    topics = {t['topic_metadata']['name']: t for t in bag['topics_with_message_count']}
    assert topics['/joint_states']['message_count'] == 50
    meta = topics['/joint_states']['topic_metadata']
    assert meta['serialization_format'] == 'cdr' and meta['type_description_hash'] == HASH
    assert parse_qos_yaml(meta['offered_qos_profiles'])[0].deadline_ns == INFINITE_NS
    assert bag['files'][0]['message_count'] == 51


def test_qos_yaml_matches_rosbag2_jazzy_layout() -> None:
    from qtree_recorder.qos import qos_yaml

    text = qos_yaml(LATCHED)
    assert text.splitlines()[:4] == [
        '- history: keep_last',
        '  depth: 1',
        '  reliability: reliable',
        '  durability: transient_local',
    ]
    assert '  deadline:\n    sec: 9223372036\n    nsec: 854775807' in text
    assert qos_yaml([]) == '[]'


def test_small_chunks_and_time_flush(tmp_path: Path) -> None:
    now = [0.0]
    path = tmp_path / 'chunks.mcap'
    log = McapLog(path, chunk_size=64 * 1024, flush_interval_s=1.0, clock=lambda: now[0])
    payload = bytes(4) + bytes(range(256)) * 8  # 2 KiB of "CDR"
    log.write('/blob', 'std_msgs/msg/String', payload, T0)
    size_before = path.stat().st_size
    now[0] = 0.5
    log.tick()
    assert path.stat().st_size == size_before  # younger than 1 s: still in memory
    now[0] = 1.01
    log.tick()
    assert path.stat().st_size > size_before  # flushed by time, without a new message
    for i in range(200):  # 400 KiB → several size-bounded chunks
        log.write('/blob', 'std_msgs/msg/String', payload, T0 + i)
    log.close()
    with open(path, 'rb') as stream:
        summary = make_reader(stream).get_summary()
    sizes = [c.uncompressed_size for c in summary.chunk_indexes]
    assert len(sizes) >= 6 and max(sizes) <= 64 * 1024 + len(payload) + 1024
    assert all(c.compression == 'zstd' for c in summary.chunk_indexes)


def test_truncated_file_reads_up_to_last_complete_chunk(tmp_path: Path) -> None:
    path = tmp_path / 'cut.mcap'
    log = McapLog(path, chunk_size=16 * 1024)
    for i in range(400):
        log.write('/n', 'std_msgs/msg/String', bytes(4) + i.to_bytes(4, 'little') * 64, T0 + i)
    log.close()
    data = path.read_bytes()
    full, chunks = read_complete_chunks(path)
    assert len(full) == 400 and chunks >= 5
    cut = tmp_path / 'cut_part.mcap'
    cut.write_bytes(data[: len(data) // 2])
    messages, complete = read_complete_chunks(cut)
    assert 0 < complete < chunks
    assert 100 <= len(messages) < 400
    sequence = [int.from_bytes(m.data[4:8], 'little') for m in messages]
    assert sequence == list(range(len(messages)))  # a prefix, in order, nothing corrupted


WRITER = textwrap.dedent("""
    import sys, time
    from qtree_recorder.mcap_log import McapLog
    log = McapLog(sys.argv[1], flush_interval_s=0.2)
    i = 0
    while True:
        log.write('/n', 'std_msgs/msg/String', bytes(4) + i.to_bytes(4, 'little'), time.time_ns())
        print(i, flush=True)
        i += 1
        time.sleep(0.002)
""")


def test_sigkilled_writer_leaves_a_readable_prefix(tmp_path: Path) -> None:
    path = tmp_path / 'killed.mcap'
    process = subprocess.Popen([sys.executable, '-c', WRITER, str(path)],
                               stdout=subprocess.PIPE, text=True)  # fmt: skip
    written: list[tuple[float, int]] = []

    def read_lines() -> None:
        for line in process.stdout:  # type: ignore[union-attr]
            written.append((time.monotonic(), int(line)))

    reader = threading.Thread(target=read_lines, daemon=True)
    reader.start()
    deadline = time.monotonic() + 20.0
    while (
        len(written) < 300 or written[-1][0] - written[0][0] < 1.5
    ) and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    killed_at = time.monotonic()
    process.wait()
    reader.join(timeout=5)
    assert len(written) >= 300, 'writer subprocess too slow'
    old_enough = max(i for t, i in written if t < killed_at - 0.6)  # flushed 0.2 s cadence
    messages, _ = read_complete_chunks(path)
    sequence = [int.from_bytes(m.data[4:8], 'little') for m in messages]
    assert sequence == list(range(len(sequence)))
    assert len(sequence) > old_enough
    with open(path, 'rb') as stream, pytest.raises(McapError):  # no summary, no footer
        make_reader(stream).get_summary()


def test_errors_are_typed(tmp_path: Path) -> None:
    blocker = tmp_path / 'a_file'
    blocker.write_text('x')
    with pytest.raises(McapWriteError, match=r'cannot open MCAP file .*a_file/run\.mcap'):
        McapLog(blocker / 'run.mcap')
    if Path('/dev/full').exists():
        with pytest.raises(McapWriteError, match='No space left'):
            McapLog('/dev/full')
    log = McapLog(tmp_path / 'closed.mcap')
    log.close()
    log.close()  # idempotent
    with pytest.raises(WriterClosedError, match='already closed'):
        log.write('/x', 'std_msgs/msg/String', bytes(8), T0)


def test_unknown_type_is_still_recorded(tmp_path: Path) -> None:
    warnings: list[str] = []
    from qtree_recorder.definitions import DefinitionLibrary

    path = tmp_path / 'unknown.mcap'
    with McapLog(path, definitions=DefinitionLibrary(warn=warnings.append)) as log:
        log.write('/mystery', 'nope_msgs/msg/Thing', bytes(8), T0)
        log.write('/mystery', 'nope_msgs/msg/Thing', bytes(8), T0 + 1)
    assert len(warnings) == 1 and 'nope_msgs/msg/Thing' in warnings[0]
    with open(path, 'rb') as stream:
        messages = list(make_reader(stream).iter_messages())
    assert len(messages) == 2 and messages[0][0].name == 'nope_msgs/msg/Thing'
    assert math.isclose(len(messages[1][2].data), 8)
