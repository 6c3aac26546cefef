"""ROS 2 node ``recorder``: every topic of the graph to one MCAP file (rosbag2 conventions).

Discovers topics periodically, subscribes with ``raw=True`` and the publishers' QoS (latched
topics transient-local), and queues the CDR bytes to a worker thread that writes them unchanged
and derives ``/tf``, ``/tf_static``, ``/scene_markers`` (:mod:`qtree_recorder.recording`) for
Foxglove and Rerun; optionally feeds the live Rerun view. SIGINT finishes the file and exits 0.
"""

from __future__ import annotations

import sys
import time
from datetime import datetime
from pathlib import Path
from typing import Any

from qtree_node_support.lifecycle import run_node
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from qtree_recorder import graph_topics
from qtree_recorder.exceptions import RecorderError
from qtree_recorder.mcap_log import McapLog
from qtree_recorder.qos import QosProfileData
from qtree_recorder.recording import DEFAULT_TF_RATE_HZ, Recording
from qtree_recorder.rerun_feed import RerunFeed
from qtree_recorder.writer import RecordWriter

SUBSCRIPTION_DEPTH = 1000  # [messages] queue per recorded topic: a training bursts episodes


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
        metadata, tf_rate, period = graph_topics.start_settings(p, log.error)
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
        self.writer = RecordWriter(self.recording, self.rerun, log.error)
        self._recorded: dict[str, object] = {}
        self._discover()
        self._timer = self.create_timer(period, self._discover)
        if self.recording is not None:
            log.info(f'recording to {self.path}')
        log.info('recorder ready')

    def _on_set_parameters(self, params: list) -> SetParametersResult:
        for param in params:
            if param.name == 'tf_rate_hz':
                if problem := graph_topics.tf_rate_problem(param.value):
                    return SetParametersResult(successful=False, reason=problem)
                if self.recording is not None:
                    self.recording.set_tf_rate(param.value)
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
                self.writer.put(t, n, raw, time.time_ns(), o, h)

            self._recorded[topic] = self.create_subscription(
                msg_class, topic, callback, qos, raw=True)  # fmt: skip
            self.get_logger().info(f'recording {topic} [{type_name}] {reliability} {durability}')

    def finish(self) -> None:
        """Stop the writer after it wrote everything queued, then finish the file."""
        line, failed = self.writer.finish(self._custom, self.path)
        if not line:
            return
        if self.context.ok():  # log through rclpy while the context lives, else to stderr
            if failed:
                self.get_logger().error(line)
            else:
                self.get_logger().info(line)
        else:
            print(f'[{"ERROR" if failed else "INFO"}] [recorder]: {line}', file=sys.stderr)


def run(args: list[str] | None = None, **options: Any) -> int:
    """Record until SIGINT/SIGTERM, finish the file: 0."""
    return run_node(RecorderNode, args=args, cleanup=RecorderNode.finish, **options)


def main(args: list[str] | None = None) -> None:
    """The console script: :func:`run`, its code as the exit status."""
    sys.exit(run(args))


if __name__ == '__main__':
    main()
