"""Read a qtree-tamp run log (MCAP, ros2 profile) without ROS, tolerant of truncated files.

The file is walked record by record from its start, so a log whose writer was killed (no
summary, no footer, a half-written last chunk) is read up to its last complete chunk. Messages
are decoded with ``mcap_ros2`` from the definitions embedded in the file, so ``qtree_msgs`` logs
need no ROS install. No rclpy import here.

Typical use::

    run = open_run('run.mcap')            # scans once, raises ReplayError subclasses
    run.topics['/joint_states'].count
    for msg in run.messages(['/scene']):  # decoded, in file order
        msg.message.objects
"""

from __future__ import annotations

import contextlib
import io
import logging
import re
import zlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import zstandard
from mcap.exceptions import McapError
from mcap.records import Channel, Chunk, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap_ros2.decoder import DecoderFactory

MCAP_MAGIC = b'\x89MCAP0\r\n'
ROBOT_PREFIX = 'j2s7s300_'  # every joint of the Jaco² j2s7s300 model starts with this
_RECORD_HEADER_BYTES = 9  # opcode (1) + record length (8)
_MAX_OPCODE = 0x0F  # highest opcode of the MCAP spec; 0x80..0xFF are user records

_LOG = logging.getLogger(__name__)


class ReplayError(Exception):
    """Base class of every error raised while reading a run log."""


class LogNotFoundError(ReplayError):
    """The path does not exist or is not a regular file."""


class NotMcapError(ReplayError):
    """The file does not start with the MCAP magic bytes."""


class CorruptLogError(ReplayError):
    """A record of the file cannot be decoded (bad CRC, bad compression, bad framing)."""


class WrongRobotError(ReplayError):
    """The log was recorded with another robot than the Jaco² j2s7s300."""


class NoReadableTopicsError(ReplayError):
    """No channel of the file has a schema this reader can decode."""


@dataclass(frozen=True)
class TopicInfo:
    """One recorded topic.

    Attributes:
        name: topic name, e.g. ``'/joint_states'``.
        type: ROS type name, e.g. ``'sensor_msgs/msg/JointState'``.
        count: number of complete messages in the file.
        qos_profiles: the channel's ``offered_qos_profiles`` YAML text ('' when absent).
        definition: full ``ros2msg`` definition text of the schema.
    """

    name: str
    type: str
    count: int
    qos_profiles: str
    definition: str


@dataclass(frozen=True)
class RecordedMessage:
    """Where and when one message was recorded (the first fields of every message read).

    Attributes:
        topic: topic name.
        type: ROS type name.
        log_time_ns: time the recorder received it [ns since epoch].
    """

    topic: str
    type: str
    log_time_ns: int


@dataclass(frozen=True)
class RawMessage(RecordedMessage):
    """One recorded message as CDR bytes (what ``ros2 bag play`` publishes).

    Attributes:
        publish_time_ns: time it was published [ns since epoch] (= log time when unknown).
        data: serialized message (CDR, with encapsulation header).
    """

    publish_time_ns: int
    data: bytes


@dataclass(frozen=True)
class DecodedMessage(RecordedMessage):
    """One recorded message decoded from the embedded definition.

    Attributes:
        message: decoded message with the fields of the ``.msg`` as attributes.
    """

    message: Any


def _iter_records(path: Path) -> Iterator[tuple[int, Any]]:
    """Yield ``(offset, record)`` for each complete top-level record; chunks are unpacked.

    Stops silently at the first incomplete record (a truncated file) and at the footer.

    Raises:
        CorruptLogError: a complete record cannot be decoded.
    """
    with path.open('rb') as handle:
        handle.seek(len(MCAP_MAGIC))
        offset = len(MCAP_MAGIC)
        while True:
            head = handle.read(_RECORD_HEADER_BYTES)
            if len(head) < _RECORD_HEADER_BYTES:
                return
            opcode = head[0]
            length = int.from_bytes(head[1:], 'little')
            if opcode == 0 or _MAX_OPCODE < opcode < 0x80:
                raise CorruptLogError(f'{path}: invalid record opcode {opcode} at byte {offset}')
            body = handle.read(length)
            if len(body) < length:
                return
            start, offset = offset, offset + _RECORD_HEADER_BYTES + length
            if opcode > _MAX_OPCODE:  # a user record: nothing for us
                continue
            record = _parse_record(path, start, head + body)
            if isinstance(record, Chunk):
                try:
                    for inner in breakup_chunk(record, validate_crc=True):
                        yield start, inner
                except (
                    McapError,
                    ValueError,
                    zlib.error,
                    zstandard.ZstdError,
                    RuntimeError,
                ) as err:
                    message = f'{path}: damaged chunk at byte {start} ({err})'
                    raise CorruptLogError(message) from None
            elif record is not None:
                yield start, record
            if isinstance(record, Footer):
                return


def _parse_record(path: Path, offset: int, data: bytes) -> Any:
    """Decode one framed record with the ``mcap`` reader (``None`` for unknown user records)."""
    reader = StreamReader(io.BytesIO(data), skip_magic=True, emit_chunks=True)
    try:
        return next(iter(reader.records), None)
    except (McapError, ValueError, UnicodeDecodeError, IndexError) as err:
        raise CorruptLogError(f'{path}: undecodable record at byte {offset} ({err})') from None
    except Exception as err:  # struct.error and friends: the record body is inconsistent
        raise CorruptLogError(f'{path}: undecodable record at byte {offset} ({err})') from None


@dataclass
class _Channel:
    topic: str
    type: str
    qos_profiles: str
    definition: str
    decoder: Callable[[bytes], Any]
    count: int = 0


@dataclass
class McapRun:
    """A scanned run log; construct with :func:`open_run`.

    Attributes:
        path: the file.
        profile: MCAP header profile (``'ros2'`` for rosbag2-compatible logs).
        metadata: metadata records by name (e.g. ``'rosbag2'``, the run metadata), each a dict.
        topics: readable topics by name.
        truncated: True when the file ends before its footer (read up to the last full chunk).
        start_ns: earliest log time [ns] (0 when there is no message).
        end_ns: latest log time [ns].
        warnings: one line per problem found (skipped channels, truncation).
    """

    path: Path
    profile: str = ''
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    topics: dict[str, TopicInfo] = field(default_factory=dict)
    truncated: bool = False
    start_ns: int = 0
    end_ns: int = 0
    warnings: list[str] = field(default_factory=list)
    _channels: dict[int, _Channel] = field(default_factory=dict, repr=False)

    @property
    def duration_s(self) -> float:
        """Time between the first and the last message [s]."""
        return (self.end_ns - self.start_ns) * 1e-9

    @property
    def message_count(self) -> int:
        """Number of readable messages."""
        return sum(t.count for t in self.topics.values())

    def raw_messages(self, topics: Iterable[str] | None = None) -> Iterator[RawMessage]:
        """Iterate over the readable messages as CDR bytes, in file order.

        Args:
            topics: topic names to keep (all readable topics when None).
        """
        wanted = None if topics is None else set(topics)
        for _, record in _iter_records(self.path):
            if not isinstance(record, Message):
                continue
            channel = self._channels.get(record.channel_id)
            if channel is None or (wanted is not None and channel.topic not in wanted):
                continue
            publish = record.publish_time or record.log_time
            yield RawMessage(channel.topic, channel.type, record.log_time, publish, record.data)

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[DecodedMessage]:
        """Iterate over the readable messages decoded, in file order.

        A message whose bytes do not decode is skipped with one warning per topic.

        Args:
            topics: topic names to keep (all readable topics when None).
        """
        failed: set[str] = set()
        decoders = {c.topic: c.decoder for c in self._channels.values()}
        for raw in self.raw_messages(topics):
            try:
                message = decoders[raw.topic](raw.data)
            except Exception as err:  # any decoder failure means "skip it"
                if raw.topic not in failed:
                    failed.add(raw.topic)
                    self._warn(f'{raw.topic}: undecodable message skipped ({err})')
                continue
            yield DecodedMessage(raw.topic, raw.type, raw.log_time_ns, message)

    def _warn(self, text: str) -> None:
        self.warnings.append(text)
        _LOG.warning(text)


def open_run(path: str | Path) -> McapRun:
    """Scan a run log: header, metadata, channels, per-topic counts, time range, robot.

    Args:
        path: the ``.mcap`` file.

    Returns:
        The scanned run.

    Raises:
        LogNotFoundError: no such file.
        NotMcapError: not an MCAP file.
        CorruptLogError: a damaged record, or truncated before any complete message.
        WrongRobotError: ``/joint_states`` names joints that are not ``j2s7s300_*``.
        NoReadableTopicsError: messages exist but none has a decodable schema.
    """
    path = Path(path)
    if not path.is_file():
        raise LogNotFoundError(f'{path}: no such file')
    with path.open('rb') as handle:
        magic = handle.read(len(MCAP_MAGIC))
    if magic != MCAP_MAGIC:
        raise NotMcapError(f'{path}: not an MCAP file (bad magic bytes)')
    run = McapRun(path=path)
    schemas: dict[int, Schema] = {}
    factory = DecoderFactory()
    skipped: dict[int, str] = {}
    seen_footer = seen_message = False
    for _, record in _iter_records(path):
        if isinstance(record, Header):
            run.profile = record.profile
        elif isinstance(record, Schema):
            schemas[record.id] = record
        elif isinstance(record, Channel) and record.id not in {*run._channels, *skipped}:
            channel = _make_channel(record, schemas.get(record.schema_id), factory)
            if channel is None:
                skipped[record.id] = record.topic
            else:
                run._channels[record.id] = channel
        elif isinstance(record, Metadata):
            run.metadata[record.name] = dict(record.metadata)
        elif isinstance(record, Message):
            seen_message = True
            channel = run._channels.get(record.channel_id)
            if channel is None:
                continue
            if channel.count == 0:  # decode the first message: the definition must be complete
                try:
                    first = channel.decoder(record.data)
                except Exception:
                    skipped[record.channel_id] = run._channels.pop(record.channel_id).topic
                    continue
                _check_robot(path, channel, first)
            channel.count += 1
            run.start_ns = (
                record.log_time if not run.start_ns else min(run.start_ns, record.log_time)
            )
            run.end_ns = max(run.end_ns, record.log_time)
        elif isinstance(record, Footer):
            seen_footer = True
    run.truncated = not seen_footer
    _finish(run, skipped, seen_message)
    return run


def _finish(run: McapRun, skipped: dict[int, str], seen_message: bool) -> None:
    """Fill ``run.topics``, record warnings and reject logs with nothing readable."""
    for channel in run._channels.values():
        old = run.topics.get(channel.topic)
        count = channel.count + (old.count if old else 0)
        run.topics[channel.topic] = TopicInfo(
            channel.topic, channel.type, count, channel.qos_profiles, channel.definition
        )
    if run.truncated:
        if not seen_message:
            raise CorruptLogError(f'{run.path}: truncated before the first complete chunk')
        run._warn(f'{run.path}: file is truncated; read up to its last complete chunk')
    if skipped:
        names = ', '.join(sorted(set(skipped.values())))
        run._warn(f'skipped channels with unknown or undecodable schemas: {names}')
    if seen_message and not any(c.count for c in run._channels.values()):
        raise NoReadableTopicsError(f'{run.path}: no channel has a decodable ros2msg schema')


def _make_channel(
    record: Channel, schema: Schema | None, factory: DecoderFactory
) -> _Channel | None:
    """Build a decodable channel, or None when its schema is missing, foreign or broken."""
    if schema is None or schema.encoding != 'ros2msg' or record.message_encoding != 'cdr':
        return None
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # mcap_ros2 prints parse errors
            decoder = factory.decoder_for(record.message_encoding, _msg_style(schema))
    except Exception:  # a definition the parser rejects: unknown schema
        return None
    if decoder is None:
        return None
    qos = record.metadata.get('offered_qos_profiles', '')
    return _Channel(record.topic, schema.name, qos, schema.data.decode(errors='replace'), decoder)


# Generated action/service types (``pkg/action/X_FeedbackMessage``) are valid in rosbag2 logs, but
# mcap_ros2's parser only accepts ``pkg/Name`` with Name matching ``[A-Z][A-Za-z0-9]*``.
_GENERATED_TYPE = re.compile(r'\b([a-z][a-z0-9_]*)/(?:action|srv)/([A-Z][A-Za-z0-9_]*)')


def _msg_style(schema: Schema) -> Schema:
    """The schema with generated action/service type names rewritten for mcap_ros2's parser.

    ``qtree_msgs/action/RetrieveTarget_Feedback`` becomes ``qtree_msgs/RetrieveTargetFeedback``
    in the schema name, the field types and the ``MSG:`` headers alike; the CDR layout is
    unchanged, so the decoded messages are the same.
    """
    if not _GENERATED_TYPE.search(schema.name + schema.data.decode(errors='replace')):
        return schema

    def rename(match: re.Match[str]) -> str:
        return f'{match.group(1)}/{match.group(2).replace("_", "")}'

    data = _GENERATED_TYPE.sub(rename, schema.data.decode(errors='replace')).encode()
    return Schema(id=schema.id, name=_GENERATED_TYPE.sub(rename, schema.name),
                  encoding=schema.encoding, data=data)  # fmt: skip


_ROBOT_NAME = re.compile(r'<robot\b[^>]*\bname\s*=\s*["\']([^"\']+)["\']')


def _check_robot(path: Path, channel: _Channel, message: Any) -> None:
    """Reject logs of another robot from the first joint state or robot description.

    Raises:
        WrongRobotError: the joints (or the URDF's robot name) are not the j2s7s300's.
    """
    if channel.type == 'sensor_msgs/msg/JointState':
        foreign = [n for n in message.name if not n.startswith(ROBOT_PREFIX)]
        if foreign:
            more = '…' if len(foreign) > 3 else ''
            text = (
                f'{path}: recorded with another robot (joints {", ".join(foreign[:3])}{more}; '
                f'expected {ROBOT_PREFIX}*)'
            )
            raise WrongRobotError(text)
    elif channel.topic == '/robot_description':
        match = _ROBOT_NAME.search(str(message.data))
        if match and not (match.group(1) + '_').startswith(ROBOT_PREFIX):
            raise WrongRobotError(f'{path}: recorded with robot {match.group(1)!r}, not j2s7s300')
