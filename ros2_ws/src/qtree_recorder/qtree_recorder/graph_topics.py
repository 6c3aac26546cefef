"""Which graph topics to record, with which QoS, and other pure helpers of the recorder node.

No ROS import: the node passes topic names, type names and offered QoS as plain data.
"""

from __future__ import annotations

import importlib
import json
import math
import platform
import re
from collections.abc import Sequence
from datetime import datetime
from importlib import metadata as importlib_metadata
from typing import Any

from qtree_recorder.qos import QosProfileData
from qtree_recorder.recording import DEFAULT_TF_RATE_HZ, DERIVED_TOPICS

# Hidden topics rosbag2 would skip but that carry the run's story: the action's feedback/status.
ALLOWED_HIDDEN_SUFFIXES = ('/_action/feedback', '/_action/status')
EXCLUDED_TOPICS = frozenset({'/parameter_events'}) | DERIVED_TOPICS
_SAFE = re.compile(r'[^A-Za-z0-9_.-]+')


def should_record(topic: str) -> bool:
    """True for every topic of the graph but parameter events, the topics the recorder derives
    itself (``/tf``, ``/tf_static``, ``/scene_markers``) and hidden topics other than an action's
    feedback and status.
    """
    if topic in EXCLUDED_TOPICS:
        return False
    hidden = any(part.startswith('_') for part in topic.split('/'))
    return not hidden or topic.endswith(ALLOWED_HIDDEN_SUFFIXES)


def subscription_policy(offers: Sequence[QosProfileData]) -> tuple[str, str]:
    """``(reliability, durability)`` to subscribe with, as rosbag2's ``adapt_request_to_offers``.

    Reliable only if every publisher offers reliable; transient-local only if every publisher
    offers it (then latched messages such as ``/scene`` and ``/robot_description`` arrive).
    """
    if not offers:
        return 'reliable', 'volatile'
    reliable = all(o.reliability == 'reliable' for o in offers)
    latched = all(o.durability == 'transient_local' for o in offers)
    return ('reliable' if reliable else 'best_effort'), (
        'transient_local' if latched else 'volatile'
    )


def python_type_path(type_name: str) -> tuple[str, tuple[str, ...]]:
    """Module and attribute chain of the Python class of a ROS type.

    ``sensor_msgs/msg/JointState`` → ``('sensor_msgs.msg', ('JointState',))``;
    ``pkg/action/X_FeedbackMessage`` → ``('pkg.action', ('X', 'Impl', 'FeedbackMessage'))``.

    Raises:
        ValueError: not ``pkg/ns/Type``.
    """
    parts = type_name.split('/')
    if len(parts) != 3 or not all(parts):
        raise ValueError(f'unexpected ROS type name {type_name!r}')
    package, namespace, name = parts
    if namespace == 'action':
        for suffix in ('_FeedbackMessage', '_SendGoal_Request', '_GetResult_Request'):
            if name.endswith(suffix):
                return f'{package}.action', (name.removesuffix(suffix), 'Impl', suffix[1:])
    return f'{package}.{namespace}', (name,)


def load_message_class(type_name: str) -> Any:
    """Import the Python message class of a ROS type (for raw subscriptions and decoding).

    Raises:
        ValueError: malformed type name.
        ImportError, AttributeError: the interface package or type is not installed.
    """
    module, chain = python_type_path(type_name)
    msg_class: Any = importlib.import_module(module)
    for attr in chain:
        msg_class = getattr(msg_class, attr)
    return msg_class


def default_file_name(scenario: str, now: datetime) -> str:
    """``qtree_<YYYYmmdd-HHMMSS>_<scenario>.mcap`` (scenario made file-name safe; may be empty)."""
    stem = f'qtree_{now:%Y%m%d-%H%M%S}'
    safe = _SAFE.sub('_', scenario).strip('_')
    return f'{stem}_{safe}.mcap' if safe else f'{stem}.mcap'


def parse_run_metadata(text: str) -> dict[str, Any]:
    """Parse the ``run_metadata`` parameter (a JSON object; empty text = ``{}``).

    Raises:
        ValueError: not JSON, or not an object.
    """
    if not text.strip():
        return {}
    try:
        value = json.loads(text)
    except json.JSONDecodeError as err:
        raise ValueError(f'run_metadata is not valid JSON ({err}): {text[:80]!r}') from None
    if not isinstance(value, dict):
        raise ValueError(f'run_metadata must be a JSON object, got {type(value).__name__}')
    return value


VERSIONED_PACKAGES = ('qtree_recorder', 'mcap', 'mcap-ros2-support', 'rerun-sdk', 'pin', 'numpy',
                      'ros-jazzy-rclpy')  # fmt: skip


def package_versions() -> dict[str, str]:
    """Installed versions of the packages a log depends on (``'unknown'`` when not found)."""
    versions = {'python': platform.python_version(), 'ros_distro': 'jazzy'}
    for name in VERSIONED_PACKAGES:
        try:
            versions[name] = importlib_metadata.version(name)
        except importlib_metadata.PackageNotFoundError:
            versions[name] = 'unknown'
    return versions


def run_metadata_record(scenario: str, metadata: dict[str, Any], versions: dict[str, str],
                        started_ns: int) -> dict[str, str]:  # fmt: skip
    """The ``qtree_run`` MCAP metadata record: scenario, policy, seed, parameters, versions."""
    return {
        'scenario': scenario,
        'policy': str(metadata.get('policy', '')),
        'seed': str(metadata.get('seed', '')),
        'parameters': json.dumps(metadata.get('parameters', {}), sort_keys=True, default=str),
        'run_metadata': json.dumps(metadata, sort_keys=True, default=str),
        'versions': json.dumps(versions, sort_keys=True),
        'started_ns': str(started_ns),
    }


def tf_rate_problem(value: Any) -> str:
    """Why ``value`` is not a valid ``tf_rate_hz`` (a float >= 0 [Hz]), '' when it is."""
    if isinstance(value, float) and math.isfinite(value) and value >= 0:
        return ''
    return f'tf_rate_hz must be a float >= 0, got {value}'


def start_settings(p: dict[str, Any], error: Any) -> tuple[dict[str, Any], float, float]:
    """``(run metadata, tf rate [Hz], discovery period [s])`` of the start-up parameters ``p``.

    A bad value is logged through ``error`` and replaced: metadata stored as raw text, the
    default /tf rate, a 0.5 s discovery period.
    """
    try:
        metadata = parse_run_metadata(p['run_metadata'])
    except ValueError as err:
        error(f'{err}; stored as raw text')
        metadata = {'raw': p['run_metadata']}
    tf_rate = p['tf_rate_hz']
    if tf_rate_problem(float(tf_rate)):
        error(f'tf_rate_hz must be >= 0, got {tf_rate}; using {DEFAULT_TF_RATE_HZ}')
        tf_rate = DEFAULT_TF_RATE_HZ
    period = p['discovery_period_s'] if p['discovery_period_s'] > 0 else 0.5
    return metadata, tf_rate, period
