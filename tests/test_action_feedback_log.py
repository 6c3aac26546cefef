"""Action feedback recorded from the hidden topic decodes in replay, like every other channel.

rosbag2-style logs name the type ``qtree_msgs/action/RetrieveTarget_FeedbackMessage``; the
``mcap_ros2`` parser used by ``replay.py`` rejects that name, so the reader rewrites it.
"""

from __future__ import annotations

from pathlib import Path

from qtree_msgs.action import RetrieveTarget
from qtree_recorder.mcap_log import McapLog
from qtree_recorder.mcap_reader import open_run
from rclpy.serialization import serialize_message

TYPE = 'qtree_msgs/action/RetrieveTarget_FeedbackMessage'
TOPIC = '/retrieve_target/_action/feedback'


def test_feedback_channel_decodes(tmp_path: Path) -> None:
    path = tmp_path / 'feedback.mcap'
    log = McapLog(path)
    for episode in (10, 20, 30):
        message = RetrieveTarget.Impl.FeedbackMessage()
        message.goal_id.uuid = list(range(16))
        message.feedback.episode = episode
        message.feedback.best_sequence = ['O2', 'T']
        log.write(TOPIC, TYPE, serialize_message(message), episode * 1_000_000)
    log.close()

    run = open_run(path)
    assert run.topics[TOPIC].type == TYPE  # the recorded type name is kept
    decoded = list(run.messages([TOPIC]))
    assert [m.message.feedback.episode for m in decoded] == [10, 20, 30]
    assert list(decoded[0].message.feedback.best_sequence) == ['O2', 'T']
    assert list(decoded[0].message.goal_id.uuid) == list(range(16))
    assert not run.warnings
