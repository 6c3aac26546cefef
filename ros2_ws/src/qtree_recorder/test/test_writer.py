"""The writer thread puts the MCAP first: a live view that falls behind never costs the file.

Found with the README demo on a loaded machine: the writer still decoded joint states for Rerun
when the demo's 10 s stop ran out; the recorder was SIGKILLed and its MCAP cut short.
"""

from __future__ import annotations

import threading
from types import SimpleNamespace

from qtree_recorder.writer import RERUN_BACKLOG, RecordWriter

TOPIC, TYPE = '/training_stats', 'qtree_msgs/msg/TrainingStats'


class CountingRecording:
    """Stands in for :class:`~qtree_recorder.recording.Recording`: counts what it is given."""

    def __init__(self) -> None:
        self.recorded: list[int] = []

    def record(self, topic, type_name, raw, t_ns, offers, type_hash=None) -> None:
        self.recorded.append(t_ns)

    def tick(self) -> None:
        pass

    def close(self, custom):
        return SimpleNamespace(message_count=len(self.recorded))


class StuckView:
    """A live view that blocks on its first message until released (a slow Rerun viewer)."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.entered = threading.Event()
        self.shown: list[int] = []
        self.closed = False

    def on_raw(self, topic, type_name, raw, t_ns) -> None:
        self.entered.set()
        self.release.wait(10.0)
        self.shown.append(t_ns)

    def on_decoded(self, topic, msg, t_ns) -> None:
        self.shown.append(t_ns)

    def close(self) -> None:
        self.closed = True


def test_a_writer_behind_its_live_view_finishes_the_whole_file() -> None:
    recording, view = CountingRecording(), StuckView()
    writer = RecordWriter(recording, view, lambda _line: None)
    total = 3 * RERUN_BACKLOG
    writer.put(TOPIC, TYPE, b'\0', 0, [], None)
    assert view.entered.wait(10.0)
    for t in range(1, total):
        writer.put(TOPIC, TYPE, b'\0', t, [], None)
    view.release.set()  # the view was stuck on message 0 while all of them were queued
    line, failed = writer.finish({}, 'run.mcap')
    assert not failed and recording.recorded == list(range(total))  # every message, in order
    assert line.startswith(f'recording finished: {total} messages in run.mcap')
    # the view showed its first message and skipped the backlog until the queue was short
    assert view.shown[0] == 0 and len(view.shown) < total
    assert writer.rerun_skipped == total - len(view.shown) > 0
    assert f'skipped {writer.rerun_skipped} messages' in line and view.closed


def test_a_writer_that_keeps_up_shows_every_message() -> None:
    recording, view = CountingRecording(), StuckView()
    view.release.set()
    writer = RecordWriter(recording, view, lambda _line: None)
    for t in range(50):
        writer.put(TOPIC, TYPE, b'\0', t, [], None)
    while len(view.shown) < 50 and writer._worker.is_alive():
        threading.Event().wait(0.01)
    line, _ = writer.finish({}, 'run.mcap')
    assert view.shown == list(range(50)) and writer.rerun_skipped == 0
    assert line == 'recording finished: 50 messages in run.mcap'
