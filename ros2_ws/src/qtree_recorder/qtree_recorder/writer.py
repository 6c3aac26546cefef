"""The recorder node's writer thread: queued CDR messages → MCAP, derived /tf, Rerun.

The node's subscriptions only queue ``(topic, type, raw bytes, receive time, QoS offers, type
hash)``; :class:`RecordWriter` writes them unchanged on its own thread, decodes the few types it
derives from (joint states → /tf, /robot_description, /scene → /scene_markers) and feeds the live
Rerun view. An exception (a bad message, a full disk) is logged, throttled, and never stops it.

The MCAP file comes first: when the writer falls behind (a loaded machine, a slow Rerun viewer)
the live view skips the high-rate messages (joint states and everything it decodes itself) until
the queue is short again, and at the end the backlog is written to the file only. The README
demo, with a type check running beside it, was SIGKILLed at its 10 s stop while the writer still
decoded joint states for Rerun: the MCAP was cut at its last complete chunk.
"""

from __future__ import annotations

import functools
import queue
import threading
from collections.abc import Callable
from typing import Any

from qtree_msgs.msg import Scene
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from qtree_recorder.exceptions import RecorderError
from qtree_recorder.recording import Recording
from qtree_recorder.rerun_feed import RerunFeed

IDLE_WAIT_S = 0.2  # [s] worker wake-up period when no message arrives
FINISH_WAIT_S = 30.0  # [s] longest wait for the queue to drain at the end
# queued messages above which the live Rerun view skips high-rate messages (the MCAP keeps them)
RERUN_BACKLOG = 200


class RecordWriter:
    """One worker thread writing what the subscriptions queued.

    Attributes:
        errors: exceptions caught so far (logged: the first 5, then every 1000th).
        rerun_skipped: messages written to the MCAP but not shown live, because the writer was
            behind (more than :data:`RERUN_BACKLOG` queued) or finishing.
    """

    def __init__(
        self, recording: Recording | None, rerun: RerunFeed, error: Callable[[str], None]
    ) -> None:
        """Start the thread; ``recording`` None records nothing (the Rerun view still runs)."""
        self.recording, self.rerun, self._error = recording, rerun, error
        self._queue: queue.Queue = queue.Queue()
        self.errors = 0
        self.rerun_skipped = 0
        self._finishing = threading.Event()
        self._worker = threading.Thread(target=self._work, name='mcap_writer', daemon=True)
        self._worker.start()

    def put(self, *item: Any) -> None:
        """Queue ``(topic, type_name, raw, t_ns, offers, type_hash)`` (any thread, no wait)."""
        self._queue.put(item)

    def _tick(self) -> None:
        if self.recording is not None:
            self.recording.tick()

    def _work(self) -> None:
        while True:
            try:
                item = self._queue.get(timeout=IDLE_WAIT_S)
            except queue.Empty:
                self._guard(self._tick)
                continue
            if item is None:
                return
            self._guard(functools.partial(self._process, *item))

    def _guard(self, action: Callable[[], Any]) -> None:
        try:
            action()
        except Exception as err:  # a bad message or a full disk must never stop the writer
            self.errors += 1
            if self.errors <= 5 or self.errors % 1000 == 0:  # throttled
                kind = '' if isinstance(err, RecorderError) else f'{type(err).__name__}: '
                self._error(f'recording error #{self.errors}: {kind}{err}')

    def _process(self, topic, type_name, raw, t_ns, offers, type_hash) -> None:
        rec = self.recording
        if rec is not None:
            rec.record(topic, type_name, raw, t_ns, offers, type_hash=type_hash)
        behind = self._finishing.is_set() or self._queue.qsize() > RERUN_BACKLOG
        if type_name == 'sensor_msgs/msg/JointState':
            msg = deserialize_message(raw, JointState)
            if rec is not None:
                rec.on_joint_state(msg.name, msg.position, t_ns)
        elif topic == '/robot_description' and type_name == 'std_msgs/msg/String':
            msg = deserialize_message(raw, String)
            if rec is not None:
                rec.on_robot_description(msg.data, t_ns)
            behind = False  # rare, and the view cannot draw the arm without it
        elif type_name == 'qtree_msgs/msg/Scene':
            msg = deserialize_message(raw, Scene)
            if rec is not None:
                rec.on_scene(msg, t_ns)
            behind = False  # rare: the objects the view draws
        else:
            msg = None
        if behind:
            self.rerun_skipped += 1
        elif msg is None:
            self.rerun.on_raw(topic, type_name, raw, t_ns)
        else:
            self.rerun.on_decoded(topic, msg, t_ns)

    def finish(self, custom: dict[str, str], path: Any) -> tuple[str, bool]:
        """Write everything queued, finish the file and the Rerun view: (log line, is error).

        The backlog goes to the MCAP only (the live view skips it), so a writer that was behind
        finishes in the time the file needs, well within a node's stop time-out.
        """
        self._finishing.set()
        self._queue.put(None)
        self._worker.join(timeout=FINISH_WAIT_S)
        line, failed = '', False
        if self.recording is not None:
            try:
                stats = self.recording.close(custom)
                line = f'recording finished: {stats.message_count} messages in {path}'
            except RecorderError as err:
                line, failed = f'{err} (data up to the last chunk stays readable)', True
        if self.rerun_skipped:
            note = f'the live Rerun view skipped {self.rerun_skipped} messages it was behind on'
            line = f'{line} ({note}; the MCAP has them)' if line else note
        self.rerun.close()
        return line, failed
