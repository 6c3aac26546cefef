"""ROS 2 node ``recorder``: every topic of the graph to one MCAP file (rosbag2 conventions).

Discovers topics periodically, subscribes with ``raw=True`` and the publishers' QoS (latched
topics transient-local), and queues the CDR bytes to a worker thread that writes them unchanged
and derives ``/tf``, ``/tf_static`` and ``/scene_markers`` (:mod:`qtree_recorder.recording`), so
the arm and scene show when the log is opened in Foxglove or Rerun. Optionally feeds the live
Rerun view. SIGINT finishes the file (summary + ``rosbag2`` record) and exits 0.
"""

from __future__ import annotations

import math
import queue
import sys
import threading
import time
from datetime import datetime
from pathlib import Path

from qtree_msgs.msg import Scene
from qtree_node_support.lifecycle import run_node
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from qtree_recorder import graph_topics
from qtree_recorder.exceptions import RecorderError
from qtree_recorder.mcap_log import McapLog
from qtree_recorder.qos import QosProfileData
from qtree_recorder.recording import DEFAULT_TF_RATE_HZ, Recording
from qtree_recorder.rerun_feed import RerunFeed

SUBSCRIPTION_DEPTH = 1000  # [messages] queue per recorded topic: a training bursts episodes
IDLE_WAIT_S = 0.2  # [s] worker wake-up period when no message arrives


# (name, default, description, read-only: only read at start)
PARAMETERS = [
    ('output_dir', 'runs', 'Directory of the MCAP files (created if missing).', True),
    ('scenario', '', 'Scenario name, stored in the run metadata and the file name.', True),
    ('run_metadata', '{}', 'JSON object: policy, seed, parameters of the run.', True),
    ('file_name', '', 'MCAP file name; default qtree_<YYYYmmdd-HHMMSS>_<scenario>.mcap.', True),
    ('discovery_period_s', 0.5, 'Period of topic discovery [s], > 0.', True),
    (
        'tf_rate_hz',
        DEFAULT_TF_RATE_HZ,
        'Largest /tf rate from /joint_states [Hz]; 0 = all.',
        False,
    ),
    ('rerun_mode', 'off', 'Live Rerun view: off, save (to rrd_path) or spawn a viewer.', True),
    ('rrd_path', '', 'Rerun .rrd file of rerun_mode save (default: beside the MCAP).', True),
]


class RecorderNode(Node):
    """Records the qtree-tamp graph; see the module docstring."""

    def __init__(self) -> None:
        super().__init__('recorder')
        for name, default, description, read_only in PARAMETERS:
            self.declare_parameter(
                name, default, ParameterDescriptor(description=description, read_only=read_only)
            )
        p = {name: self.get_parameter(name).value for name, *_ in PARAMETERS}
        self.add_on_set_parameters_callback(self._on_set_parameters)
        log = self.get_logger()
        try:
            metadata = graph_topics.parse_run_metadata(p['run_metadata'])
        except ValueError as err:
            log.error(f'{err}; stored as raw text')
            metadata = {'raw': p['run_metadata']}
        tf_rate = p['tf_rate_hz']
        if not (math.isfinite(tf_rate) and tf_rate >= 0):
            log.error(f'tf_rate_hz must be >= 0, got {tf_rate}; using {DEFAULT_TF_RATE_HZ}')
            tf_rate = DEFAULT_TF_RATE_HZ
        period = p['discovery_period_s'] if p['discovery_period_s'] > 0 else 0.5
        name = p['file_name'] or graph_topics.default_file_name(p['scenario'], datetime.now())
        self.path = Path(p['output_dir']).expanduser() / name
        self._custom = {'scenario': p['scenario'], 'run_metadata': p['run_metadata']}
        self.recording: Recording | None = None
        try:
            self.recording = Recording(McapLog(self.path), tf_rate_hz=tf_rate, warn=log.warning)
            record = graph_topics.run_metadata_record(
                p['scenario'], metadata, graph_topics.package_versions(), time.time_ns()
            )
            self.recording.log.add_metadata('qtree_run', record)
        except RecorderError as err:
            log.error(f'not recording: {err}')
        rrd = p['rrd_path'] or str(self.path.with_suffix('.rrd'))
        self.rerun = RerunFeed(p['rerun_mode'], rrd, log.error)
        self._queue: queue.Queue = queue.Queue()
        self._recorded: dict[str, object] = {}
        self._errors = 0
        self._worker = threading.Thread(target=self._work, name='mcap_writer', daemon=True)
        self._worker.start()
        self._discover()
        self._timer = self.create_timer(period, self._discover)
        if self.recording is not None:
            log.info(f'recording to {self.path}')
        log.info('recorder ready')

    def _on_set_parameters(self, params: list) -> SetParametersResult:
        for param in params:
            if param.name == 'tf_rate_hz':
                value = param.value
                if not isinstance(value, float) or not math.isfinite(value) or value < 0:
                    return SetParametersResult(
                        successful=False, reason=f'tf_rate_hz must be a float >= 0, got {value}'
                    )
                if self.recording is not None:
                    self.recording.set_tf_rate(value)
        return SetParametersResult(successful=True)

    def _discover(self) -> None:
        for topic, types in self.get_topic_names_and_types():
            if topic in self._recorded or not graph_topics.should_record(topic):
                continue
            infos = self.get_publishers_info_by_topic(topic)
            if not infos:
                continue  # wait for a publisher: its QoS decides ours
            type_name = types[0]
            try:
                msg_class = graph_topics.load_message_class(type_name)
            except (ImportError, AttributeError, ValueError) as err:
                self.get_logger().error(f'cannot record {topic} ({type_name}): {err}')
                self._recorded[topic] = None
                continue
            offers = tuple(QosProfileData.from_rclpy(i.qos_profile) for i in infos)
            hashes = [str(i.topic_type_hash) for i in infos]
            type_hash = next((h for h in hashes if h.startswith('RIHS01_')), '')
            reliability, durability = graph_topics.subscription_policy(offers)
            qos = QoSProfile(
                history=HistoryPolicy.KEEP_LAST, depth=SUBSCRIPTION_DEPTH,
                reliability=ReliabilityPolicy[reliability.upper()],
                durability=DurabilityPolicy[durability.upper()])  # fmt: skip

            def callback(raw: bytes, t=topic, n=type_name, o=offers, h=type_hash) -> None:
                self._queue.put((t, n, raw, time.time_ns(), o, h))

            self._recorded[topic] = self.create_subscription(
                msg_class, topic, callback, qos, raw=True)  # fmt: skip
            self.get_logger().info(f'recording {topic} [{type_name}] {reliability} {durability}')

    def _work(self) -> None:
        while True:
            try:
                item = self._queue.get(timeout=IDLE_WAIT_S)
            except queue.Empty:
                self._guard(lambda: self.recording and self.recording.tick())
                continue
            if item is None:
                return
            self._guard(lambda item=item: self._process(*item))

    def _guard(self, action) -> None:
        try:
            action()
        except Exception as err:  # a bad message or a full disk must never stop the writer
            self._errors += 1
            if self._errors <= 5 or self._errors % 1000 == 0:  # throttled
                kind = '' if isinstance(err, RecorderError) else f'{type(err).__name__}: '
                self.get_logger().error(f'recording error #{self._errors}: {kind}{err}')

    def _process(self, topic, type_name, raw, t_ns, offers, type_hash) -> None:
        rec = self.recording
        if rec is not None:
            rec.record(topic, type_name, raw, t_ns, offers, type_hash)
        if type_name == 'sensor_msgs/msg/JointState':
            msg = deserialize_message(raw, JointState)
            if rec is not None:
                rec.on_joint_state(msg.name, msg.position, t_ns)
        elif topic == '/robot_description' and type_name == 'std_msgs/msg/String':
            msg = deserialize_message(raw, String)
            if rec is not None:
                rec.on_robot_description(msg.data, t_ns)
        elif type_name == 'qtree_msgs/msg/Scene':
            msg = deserialize_message(raw, Scene)
            if rec is not None:
                rec.on_scene(msg, t_ns)
        else:
            self.rerun.on_raw(topic, type_name, raw, t_ns)
            return
        self.rerun.on_decoded(topic, msg, t_ns)

    def _say(self, text: str, error: bool = False) -> None:
        """Log through rclpy while the context lives, else to stderr (after SIGINT)."""
        if self.context.ok():
            (self.get_logger().error if error else self.get_logger().info)(text)
        else:
            print(f'[{"ERROR" if error else "INFO"}] [recorder]: {text}', file=sys.stderr)

    def finish(self) -> None:
        """Stop the worker after it wrote everything queued, then finish the file."""
        self._queue.put(None)
        self._worker.join(timeout=30.0)
        if self.recording is not None:
            try:
                stats = self.recording.close(self._custom)
                self._say(f'recording finished: {stats.message_count} messages in {self.path}')
            except RecorderError as err:
                self._say(f'{err} (data up to the last chunk stays readable)', error=True)
        self.rerun.close()


def main(args: list[str] | None = None) -> None:
    """Record until SIGINT/SIGTERM, finish the file, exit 0."""
    sys.exit(run_node(RecorderNode, args=args, cleanup=RecorderNode.finish))


if __name__ == '__main__':
    main()
