"""One run's recording: raw topics plus the derived ``/tf``, ``/tf_static`` and ``/scene_markers``.

The node hands every received CDR message to :meth:`Recording.record` unchanged, and the decoded
``/robot_description``, ``/joint_states`` and ``/scene`` to the ``on_*`` methods, which write what
a viewer needs to draw the arm and the scene from the log alone (Foxglove and Rerun build the
robot from ``/robot_description`` + ``/tf``). No ROS import.

A URDF that does not parse stops the ``/tf`` writer with a clear message (``tf_error``); the rest
of the recording goes on.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from typing import Any

from qtree_recorder.definitions import DefinitionLibrary
from qtree_recorder.encoding import DynamicEncoder
from qtree_recorder.exceptions import EncodingError, RobotModelError
from qtree_recorder.markers import object_transforms, scene_markers
from qtree_recorder.mcap_log import LogStats, McapLog
from qtree_recorder.qos import QosProfileData
from qtree_recorder.tf_frames import ArmFrames, FrameTransform, tf_message

TF_TOPIC = '/tf'
TF_STATIC_TOPIC = '/tf_static'
MARKERS_TOPIC = '/scene_markers'
TF_TYPE = 'tf2_msgs/msg/TFMessage'
MARKERS_TYPE = 'visualization_msgs/msg/MarkerArray'
DERIVED_TOPICS = frozenset({TF_TOPIC, TF_STATIC_TOPIC, MARKERS_TOPIC})
TF_QOS = (QosProfileData(depth=100),)  # what tf2_ros' TransformBroadcaster offers
TF_STATIC_QOS = (QosProfileData.transient_local(),)
MARKERS_QOS = (QosProfileData(depth=10),)
DEFAULT_TF_RATE_HZ = 30.0  # [Hz] /tf from /joint_states (0 = every joint state)


class Recording:
    """Writes one run to an MCAP log: raw messages and the derived viewer topics.

    Args:
        log: the open MCAP log (owned: closed by :meth:`close`).
        tf_rate_hz: largest rate of ``/tf`` messages from joint states [Hz]; 0 = every state.
        warn: called with a message when something derived cannot be written (the raw
            recording is unaffected); defaults to this module's logger.

    Attributes:
        record: writes one received message unchanged: the log's :meth:`McapLog.write`.
    """

    def __init__(
        self,
        log: McapLog,
        *,
        tf_rate_hz: float = DEFAULT_TF_RATE_HZ,
        definitions: DefinitionLibrary | None = None,
        warn: Callable[[str], None] | None = None,
    ) -> None:
        self.log = log
        self.record = log.write
        self._encoder = DynamicEncoder(definitions)
        self._warn = warn or logging.getLogger(__name__).warning
        self._tf_period_ns = 0
        self.set_tf_rate(tf_rate_hz)
        self._tf_due_ns: int | None = None  # next /tf from a joint state is due at [ns]
        self._last_joint_state: tuple[list[str], list[float], int] | None = None
        self.frames: ArmFrames | None = None
        self.tf_error: str = ''
        self._warned: set[str] = set()

    def set_tf_rate(self, tf_rate_hz: float) -> None:
        """Change the largest ``/tf`` rate [Hz] (0 = every joint state).

        Raises:
            ValueError: negative or not finite.
        """
        if not math.isfinite(tf_rate_hz) or tf_rate_hz < 0:
            raise ValueError(f'tf_rate_hz must be finite and >= 0, got {tf_rate_hz}')
        self._tf_period_ns = int(1e9 / tf_rate_hz) if tf_rate_hz > 0 else 0

    def _warn_once(self, key: str, message: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            self._warn(message)

    def _write_tf(self, topic: str, transforms: Sequence[FrameTransform], t_ns: int) -> None:
        qos = TF_STATIC_QOS if topic == TF_STATIC_TOPIC else TF_QOS
        try:
            cdr = self._encoder.encode(TF_TYPE, tf_message(transforms, t_ns))
        except EncodingError as err:
            self._warn_once(f'encode {topic}', f'{topic} not written: {err}')
            return
        self.log.write(topic, TF_TYPE, cdr, t_ns, qos)

    def on_robot_description(self, urdf_text: str, t_ns: int) -> None:
        """Build the kinematic model, write ``/tf_static`` once (and ``/tf`` of the last state).

        A URDF that fails to parse disables ``/tf`` (``tf_error`` says why), once.
        """
        if self.frames is not None or self.tf_error:
            return
        try:
            self.frames = ArmFrames(urdf_text)
        except RobotModelError as err:
            self.tf_error = str(err)
            self._warn(f'/tf writer stopped: {err}; the rest of the recording goes on')
            return
        self._write_tf(TF_STATIC_TOPIC, self.frames.static_transforms(), t_ns)
        if self._last_joint_state is not None:
            names, positions, state_ns = self._last_joint_state
            self.on_joint_state(names, positions, max(state_ns, t_ns), force=True)

    def on_joint_state(
        self, names: Sequence[str], positions: Sequence[float], t_ns: int, force: bool = False
    ) -> bool:
        """Write ``/tf`` for one joint state (rate-limited); return True when written.

        Args:
            names: joint names.
            positions: joint positions [rad], same length.
            t_ns: log time of the joint state [ns since epoch].
            force: write even if the last ``/tf`` is more recent than the rate allows.
        """
        self._last_joint_state = (list(names), [float(p) for p in positions], t_ns)
        if self.frames is None:
            return False
        if not force and self._tf_due_ns is not None and t_ns < self._tf_due_ns:
            return False
        try:
            transforms = self.frames.moving_transforms(names, positions)
        except RobotModelError as err:
            self._warn_once(f'joint state {err}', f'/tf skipped for a joint state: {err}')
            return False
        self._write_tf(TF_TOPIC, transforms, t_ns)
        # A fixed cadence (due += period) keeps the mean rate at tf_rate_hz whatever the input
        # rate; after a gap longer than one period it restarts from this message.
        due = (self._tf_due_ns or t_ns) + self._tf_period_ns
        self._tf_due_ns = due if (due > t_ns and not force) else t_ns + self._tf_period_ns
        return True

    def on_scene(self, scene: Any, t_ns: int) -> None:
        """Write ``/scene_markers`` and the ``world`` → ``object/<id>`` frames of a Scene."""
        try:
            markers = self._encoder.encode(MARKERS_TYPE, scene_markers(scene, t_ns))
            transforms = object_transforms(scene)
        except (EncodingError, AttributeError, TypeError, ValueError) as err:
            self._warn_once(f'scene {type(err).__name__}', f'/scene_markers not written: {err}')
            return
        self.log.write(MARKERS_TOPIC, MARKERS_TYPE, markers, t_ns, MARKERS_QOS)
        if transforms:
            self._write_tf(TF_TOPIC, transforms, t_ns)

    def tick(self) -> None:
        """Flush the open chunk if it is old enough (call when idle)."""
        self.log.tick()

    def close(self, custom_data: dict[str, str] | None = None) -> LogStats:
        """Finish the file (summary and ``rosbag2`` record)."""
        return self.log.close(custom_data)
