"""An MCAP writer that follows rosbag2's (Jazzy) conventions, on the plain ``mcap`` Writer.

What ``ros2 bag``, rosbags, Foxglove and Rerun expect (see RECORDING_NOTES.md):

* header profile ``ros2``; one schema per type named ``pkg/msg/Type``, encoding ``ros2msg``, with
  the complete definition text (:mod:`qtree_recorder.definitions`);
* one channel per topic, message encoding ``cdr``, metadata ``offered_qos_profiles`` (YAML list)
  and ``topic_type_hash`` (``RIHS01_<hex>``, empty when unknown);
* a ``rosbag2`` metadata record at close (``serialized_metadata`` = the bag metadata YAML), then
  the Statistics and summary sections written by ``mcap``.

Crash safety: zstd chunks of at most ``chunk_size`` bytes (256 KiB) and a time-based flush every
``flush_interval_s`` (1 s, also from :meth:`McapLog.tick` when no message arrives), each followed
by a flush of the file, so a SIGKILLed recording stays readable up to its last complete chunk.

Not thread-safe: one thread (the recorder's worker) owns a ``McapLog``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import yaml
from mcap.writer import CompressionType, Writer

from qtree_recorder.definitions import DefinitionLibrary
from qtree_recorder.exceptions import McapWriteError, WriterClosedError
from qtree_recorder.qos import QosProfileData, qos_yaml

PROFILE = 'ros2'
SCHEMA_ENCODING = 'ros2msg'
MESSAGE_ENCODING = 'cdr'
ROS_DISTRO = 'jazzy'
BAG_METADATA_VERSION = 9  # rosbag2 Jazzy
DEFAULT_CHUNK_SIZE = 256 * 1024  # [bytes] uncompressed
DEFAULT_FLUSH_INTERVAL_S = 1.0  # [s]
LIBRARY = 'qtree_recorder (mcap-python)'


@dataclass
class TopicRecord:
    """What the log knows about one recorded topic.

    Attributes:
        name: topic name.
        type_name: ``pkg/msg/Type``.
        channel_id: MCAP channel id.
        qos: offered QoS profiles recorded in the channel metadata.
        type_hash: ``RIHS01_<hex>`` or ``''``.
        message_count: messages written so far.
    """

    name: str
    type_name: str
    channel_id: int
    qos: tuple[QosProfileData, ...]
    type_hash: str = ''
    message_count: int = 0


@dataclass
class LogStats:
    """Totals of a log, as returned by :meth:`McapLog.close`.

    Attributes:
        path: the file.
        message_count: messages written.
        start_ns: first log time [ns since epoch] (0 when empty).
        end_ns: last log time [ns since epoch] (0 when empty).
        counts: messages per topic.
    """

    path: Path
    message_count: int = 0
    start_ns: int = 0
    end_ns: int = 0
    counts: dict[str, int] = field(default_factory=dict)


class McapLog:
    """Write ROS 2 CDR messages to an MCAP file the way rosbag2 does.

    Args:
        path: output file; missing parent directories are created.
        definitions: where full definition texts come from (a new library by default).
        chunk_size: largest uncompressed chunk [bytes].
        flush_interval_s: longest time a message stays in memory before its chunk is written [s].
        clock: monotonic clock [s] (injectable for tests).

    Raises:
        McapWriteError: the file cannot be created (unwritable directory, bad path...).
    """

    def __init__(
        self,
        path: str | Path,
        *,
        definitions: DefinitionLibrary | None = None,
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        flush_interval_s: float = DEFAULT_FLUSH_INTERVAL_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.path = Path(path)
        self._definitions = definitions or DefinitionLibrary()
        self._flush_interval_s = flush_interval_s
        self._clock = clock
        self._topics: dict[str, TopicRecord] = {}
        self._schemas: dict[str, int] = {}
        self._stats = LogStats(self.path)
        self._closed = False
        self._pending = False
        self._last_flush = clock()
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file: IO[bytes] = open(self.path, 'wb')  # noqa: SIM115 - closed in close()
            self._writer = Writer(
                self._file, chunk_size=chunk_size, compression=CompressionType.ZSTD
            )
            self._writer.start(profile=PROFILE, library=LIBRARY)
            self._file.flush()
        except OSError as err:
            raise McapWriteError(str(self.path), 'open', err) from None

    @property
    def closed(self) -> bool:
        """True once :meth:`close` ran."""
        return self._closed

    @property
    def topics(self) -> dict[str, TopicRecord]:
        """Recorded topics by name (read-only view intended)."""
        return self._topics

    @property
    def message_count(self) -> int:
        """Messages written so far."""
        return self._stats.message_count

    def _check_open(self) -> None:
        if self._closed:
            raise WriterClosedError(str(self.path))

    def add_topic(
        self,
        topic: str,
        type_name: str,
        qos: Sequence[QosProfileData] = (),
        type_hash: str = '',
    ) -> TopicRecord:
        """Register a topic (schema + channel) before its first message; idempotent.

        Raises:
            McapWriteError: the file cannot be written.
        """
        self._check_open()
        if topic in self._topics:
            return self._topics[topic]
        try:
            schema_id = self._schemas.get(type_name)
            if schema_id is None:
                text = self._definitions.definition(type_name).text
                schema_id = self._writer.register_schema(
                    type_name, SCHEMA_ENCODING, text.encode('utf-8')
                )
                self._schemas[type_name] = schema_id
            type_hash = type_hash or self._definitions.type_hash(type_name)
            metadata = {'offered_qos_profiles': qos_yaml(qos), 'topic_type_hash': type_hash}
            channel_id = self._writer.register_channel(
                topic, MESSAGE_ENCODING, schema_id, metadata
            )
        except OSError as err:
            raise McapWriteError(str(self.path), 'write', err) from None
        record = TopicRecord(topic, type_name, channel_id, tuple(qos), type_hash)
        self._topics[topic] = record
        return record

    def write(
        self,
        topic: str,
        type_name: str,
        cdr: bytes,
        log_time_ns: int,
        qos: Sequence[QosProfileData] = (),
        *,
        type_hash: str = '',
        publish_time_ns: int | None = None,
    ) -> None:
        """Write one CDR-serialised message (bytes unchanged).

        Args:
            topic: topic name; registered on its first message with ``type_name``, ``qos`` and
                ``type_hash``.
            type_name: ``pkg/msg/Type``.
            cdr: the serialised message (CDR with its 4-byte encapsulation header).
            log_time_ns: receive time [ns since epoch].
            qos: offered QoS profiles of the topic's publishers.
            type_hash: ``RIHS01_<hex>`` type hash; when empty, taken from the installed
                interface package if it is there.
            publish_time_ns: send time [ns]; defaults to ``log_time_ns``.

        Raises:
            WriterClosedError: after :meth:`close`.
            McapWriteError: the file cannot be written (full disk...).
        """
        record = self.add_topic(topic, type_name, qos, type_hash)
        publish = log_time_ns if publish_time_ns is None else publish_time_ns
        try:
            self._writer.add_message(
                record.channel_id, log_time_ns, bytes(cdr), publish, record.message_count
            )
        except OSError as err:
            raise McapWriteError(str(self.path), 'write', err) from None
        record.message_count += 1
        stats = self._stats
        stats.start_ns = (
            log_time_ns if stats.message_count == 0 else min(stats.start_ns, log_time_ns)
        )
        stats.end_ns = max(stats.end_ns, log_time_ns)
        stats.message_count += 1
        self._pending = True
        self.tick()

    def tick(self) -> None:
        """Write the open chunk if it is older than ``flush_interval_s`` (call when idle).

        Raises:
            McapWriteError: the file cannot be written.
        """
        if self._closed or not self._pending:
            return
        if self._clock() - self._last_flush >= self._flush_interval_s:
            self.flush()

    def flush(self) -> None:
        """Write the open chunk (if any) and flush the file to the operating system.

        Raises:
            McapWriteError: the file cannot be written.
        """
        self._check_open()
        try:
            self._writer.flush()
        except OSError as err:
            raise McapWriteError(str(self.path), 'write', err) from None
        self._pending = False
        self._last_flush = self._clock()

    def add_metadata(self, name: str, data: dict[str, Any]) -> None:
        """Write a metadata record; values are converted to strings (non-strings as JSON).

        Raises:
            McapWriteError: the file cannot be written.
        """
        self._check_open()
        text = {
            str(k): v if isinstance(v, str) else json.dumps(v, sort_keys=True, default=str)
            for k, v in data.items()
        }
        try:
            self._writer.add_metadata(name, text)
        except OSError as err:
            raise McapWriteError(str(self.path), 'write', err) from None

    def bag_metadata(self, custom_data: dict[str, str] | None = None) -> dict[str, Any]:
        """The rosbag2 ``BagMetadata`` of the log so far (the keys rosbag2 Jazzy writes)."""
        stats = self._stats
        duration = max(0, stats.end_ns - stats.start_ns)
        name = self.path.name
        return {
            'version': BAG_METADATA_VERSION,
            'storage_identifier': 'mcap',
            'duration': {'nanoseconds': duration},
            'starting_time': {'nanoseconds_since_epoch': stats.start_ns},
            'message_count': stats.message_count,
            'topics_with_message_count': [
                {
                    'topic_metadata': {
                        'name': t.name,
                        'type': t.type_name,
                        'serialization_format': MESSAGE_ENCODING,
                        'offered_qos_profiles': qos_yaml(t.qos),
                        'type_description_hash': t.type_hash,
                    },
                    'message_count': t.message_count,
                }
                for t in self._topics.values()
            ],
            'compression_format': '',
            'compression_mode': '',
            'relative_file_paths': [name],
            'files': [
                {
                    'path': name,
                    'starting_time': {'nanoseconds_since_epoch': stats.start_ns},
                    'duration': {'nanoseconds': duration},
                    'message_count': stats.message_count,
                }
            ],
            'custom_data': dict(custom_data or {}),
            'ros_distro': ROS_DISTRO,
        }

    def _write_bag_metadata(self, custom_data: dict[str, str] | None = None) -> None:
        serialized = yaml.safe_dump(
            self.bag_metadata(custom_data), sort_keys=False, default_flow_style=False
        )
        self._writer.add_metadata('rosbag2', {'serialized_metadata': serialized})

    def close(self, custom_data: dict[str, str] | None = None) -> LogStats:
        """Finish the file: last chunk, ``rosbag2`` record, summary, footer. Idempotent.

        Args:
            custom_data: ``custom_data`` of the rosbag2 metadata (strings).

        Raises:
            McapWriteError: the file cannot be finished (the data already flushed stays readable).
        """
        if self._closed:
            return self._stats
        self._closed = True
        try:
            self._write_bag_metadata(custom_data)  # only at close, as rosbag2 does
            self._writer.finish()
            self._file.close()
        except OSError as err:
            raise McapWriteError(str(self.path), 'close', err) from None
        self._stats.counts = {t.name: t.message_count for t in self._topics.values()}
        return self._stats

    def __enter__(self) -> McapLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
