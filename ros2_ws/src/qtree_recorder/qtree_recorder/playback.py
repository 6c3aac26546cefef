"""Republish a recorded run on a live ROS 2 graph like ``ros2 bag play`` (replay.py --publish).

CDR bytes unchanged, original timing scaled by a rate, QoS adapted from the recorded
``offered_qos_profiles`` (transient local where recorded so). Topics whose type has no Python
typesupport (e.g. tf2_msgs) are skipped with a warning. rclpy is imported only when publishing.
"""

from __future__ import annotations

import importlib
import logging
import time
from typing import Any

import yaml

from qtree_recorder.mcap_reader import McapRun, ReplayError

LINGER_S = 0.5  # time the publishers stay up after the last message [s]
_LOG = logging.getLogger('replay.py')


def message_class(type_name: str) -> Any:
    """The Python message class of ``pkg/msg/Type``, or None without typesupport."""
    package, _, name = type_name.partition('/')
    namespace, _, name = name.rpartition('/')
    try:
        return getattr(importlib.import_module(f'{package}.{namespace or "msg"}'), name)
    except (ImportError, AttributeError):
        return None


def qos_profile(offered: str) -> Any:
    """An rclpy QoS profile adapted to the recorded offers (as ``ros2 bag play`` does).

    Reliable if every recorded publisher was reliable, transient local if every one was; depth
    is the largest recorded depth (10 when nothing was recorded).
    """
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    try:
        profiles = yaml.safe_load(offered or '[]') or []
    except yaml.YAMLError:
        profiles = []
    profiles = [p for p in profiles if isinstance(p, dict)] if isinstance(profiles, list) else []

    def policy(item: dict[str, Any], key: str, enum: Any) -> Any:
        value = item.get(key)
        try:
            return enum(value) if isinstance(value, int) else enum.get_from_short_key(str(value))
        except (KeyError, ValueError):
            return None

    reliable = all(
        policy(p, 'reliability', ReliabilityPolicy) == ReliabilityPolicy.RELIABLE for p in profiles
    )
    latched = bool(profiles) and all(
        policy(p, 'durability', DurabilityPolicy) == DurabilityPolicy.TRANSIENT_LOCAL
        for p in profiles
    )
    depth = max((int(p.get('depth', 0) or 0) for p in profiles), default=0) or 10
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth if latched else max(depth, 10),
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )


def publish(run: McapRun, *, rate: float, topics: list[str] | None, wait_s: float) -> int:
    """Republish ``run`` with its original timing scaled by ``rate``; return messages sent."""
    import rclpy

    selected = list(run.topics) if not topics else []
    for name in topics or []:
        if name in run.topics:
            selected.append(name)
        else:
            _LOG.warning('topic %s is not in the log; skipped', name)
    rclpy.init()
    try:
        node = rclpy.create_node('qtree_replay')
        publishers = {}
        for name in selected:
            info = run.topics[name]
            cls = message_class(info.type)
            if cls is None:
                _LOG.warning('no Python typesupport for %s; %s skipped', info.type, name)
                continue
            publishers[name] = node.create_publisher(cls, name, qos_profile(info.qos_profiles))
        if not publishers:
            raise ReplayError(f'{run.path}: nothing to publish')
        deadline = time.monotonic() + wait_s
        while time.monotonic() < deadline and not any(
            p.get_subscription_count() for p in publishers.values()
        ):
            time.sleep(0.02)
        sent = _play(run, publishers, rate)
        time.sleep(LINGER_S)
        print(f'published {sent} messages on {len(publishers)} topics')
        node.destroy_node()
        return sent
    finally:
        rclpy.try_shutdown()


def _play(run: McapRun, publishers: dict[str, Any], rate: float) -> int:
    start_wall = time.monotonic()
    start_log: int | None = None
    sent = 0
    for raw in run.raw_messages(publishers):
        start_log = raw.log_time_ns if start_log is None else start_log
        delay = start_wall + (raw.log_time_ns - start_log) * 1e-9 / rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        publishers[raw.topic].publish(raw.data)
        sent += 1
    return sent
