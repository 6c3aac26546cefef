"""QoS profiles as plain data, serialised the way rosbag2 (Jazzy, metadata version 9) does.

rosbag2 stores the QoS each recorded publisher offered as a YAML list in the MCAP channel
metadata ``offered_qos_profiles`` (and, as a string, in the ``rosbag2`` metadata record), with
policy names in lower case and durations as ``{sec, nsec}``; an infinite duration is
``{sec: 9223372036, nsec: 854775807}``. No ROS import: the node converts rclpy's ``QoSProfile``
with :func:`QosProfileData.from_rclpy`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import yaml

INFINITE_NS = 2**63 - 1  # RMW_DURATION_INFINITE [ns]
_NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class QosProfileData:
    """One QoS profile (the fields of ``rmw_qos_profile_t`` rosbag2 records).

    Attributes:
        history: ``'keep_last'``, ``'keep_all'``, ``'system_default'`` or ``'unknown'``.
        depth: history depth [messages].
        reliability: ``'reliable'``, ``'best_effort'``, ``'system_default'``...
        durability: ``'volatile'``, ``'transient_local'``, ``'system_default'``...
        deadline_ns: deadline [ns]; ``INFINITE_NS`` for none.
        lifespan_ns: lifespan [ns]; ``INFINITE_NS`` for none.
        liveliness: ``'automatic'``, ``'manual_by_topic'``, ``'system_default'``...
        liveliness_lease_duration_ns: lease [ns]; ``INFINITE_NS`` for none.
        avoid_ros_namespace_conventions: as in rmw.
    """

    history: str = 'keep_last'
    depth: int = 10
    reliability: str = 'reliable'
    durability: str = 'volatile'
    deadline_ns: int = INFINITE_NS
    lifespan_ns: int = INFINITE_NS
    liveliness: str = 'automatic'
    liveliness_lease_duration_ns: int = INFINITE_NS
    avoid_ros_namespace_conventions: bool = False

    @classmethod
    def transient_local(cls) -> QosProfileData:
        """The latched profile of ``/scene``, ``/robot_description``, ``/qtree``, ``/tf_static``.

        RELIABLE, TRANSIENT_LOCAL, KEEP_LAST depth 1.
        """
        return cls(depth=1, durability='transient_local')

    @classmethod
    def from_rclpy(cls, profile: Any) -> QosProfileData:
        """Convert an ``rclpy.qos.QoSProfile`` (duck-typed: enum ``.name``, ``Duration``)."""

        def name(policy: Any) -> str:
            text = getattr(policy, 'name', str(policy)).lower()
            return 'unknown' if text == 'unknown' else text

        def nanoseconds(duration: Any) -> int:
            value = int(getattr(duration, 'nanoseconds', duration))
            return INFINITE_NS if value <= 0 or value >= INFINITE_NS else value

        return cls(
            history=name(profile.history),
            depth=int(profile.depth),
            reliability=name(profile.reliability),
            durability=name(profile.durability),
            deadline_ns=nanoseconds(profile.deadline),
            lifespan_ns=nanoseconds(profile.lifespan),
            liveliness=name(profile.liveliness),
            liveliness_lease_duration_ns=nanoseconds(profile.liveliness_lease_duration),
            avoid_ros_namespace_conventions=bool(profile.avoid_ros_namespace_conventions),
        )

    def to_dict(self) -> dict[str, Any]:
        """The mapping rosbag2 writes for this profile (key order as rosbag2)."""
        fields = asdict(self)

        def duration(ns: int) -> dict[str, int]:
            return {'sec': ns // _NS_PER_S, 'nsec': ns % _NS_PER_S}

        return {
            'history': fields['history'],
            'depth': fields['depth'],
            'reliability': fields['reliability'],
            'durability': fields['durability'],
            'deadline': duration(self.deadline_ns),
            'lifespan': duration(self.lifespan_ns),
            'liveliness': fields['liveliness'],
            'liveliness_lease_duration': duration(self.liveliness_lease_duration_ns),
            'avoid_ros_namespace_conventions': fields['avoid_ros_namespace_conventions'],
        }


def qos_yaml(profiles: Sequence[QosProfileData]) -> str:
    """Serialise profiles as rosbag2's ``offered_qos_profiles`` YAML (``'[]'`` when empty)."""
    if not profiles:
        return '[]'
    text = yaml.safe_dump(
        [p.to_dict() for p in profiles], sort_keys=False, default_flow_style=False
    )
    return text.rstrip('\n')


def parse_qos_yaml(text: str) -> list[QosProfileData]:
    """Inverse of :func:`qos_yaml` (for tests and replay).

    Raises:
        ValueError: the text is not a YAML list of profiles.
    """
    data = yaml.safe_load(text) or []
    if not isinstance(data, list):
        raise ValueError(f'offered_qos_profiles is not a YAML list: {text[:80]!r}')

    def ns(value: dict[str, int]) -> int:
        return int(value['sec']) * _NS_PER_S + int(value['nsec'])

    return [
        QosProfileData(
            history=str(item['history']),
            depth=int(item['depth']),
            reliability=str(item['reliability']),
            durability=str(item['durability']),
            deadline_ns=ns(item['deadline']),
            lifespan_ns=ns(item['lifespan']),
            liveliness=str(item['liveliness']),
            liveliness_lease_duration_ns=ns(item['liveliness_lease_duration']),
            avoid_ros_namespace_conventions=bool(item['avoid_ros_namespace_conventions']),
        )
        for item in data
    ]
