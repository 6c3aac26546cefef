"""The ``jaco2_sim`` node's ROS interface: QoS profiles, parameters and their checks.

Declared and used by :mod:`jaco2_sim.sim_node`; the checks call
:meth:`~jaco2_sim.simulation.Simulation.check_parameter`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from jaco2_description.model import urdf_text
from qtree_node_support.parameters import range_descriptor
from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import ParameterUninitializedException
from rclpy.node import Node
from rclpy.parameter import Parameter

from jaco2_sim.disturbances import PARAMETER_FIELDS
from jaco2_sim.simulation import EXPECTED_ERRORS, Simulation

MAX_TRAJECTORY_POINTS_CAP = 100_000  # upper bound of max_trajectory_points (~0.9 s blocked)
# (name, default, (description, min, max)); robot_description (read-only URDF) is added on top.
PARAMETERS: list[tuple[str, Any, tuple[Any, ...]]] = [
    ('scenario', 's1', ('scenario name (s1, s2, s3) or YAML path',)),
    ('sim_rate_hz', 100.0, ('integration and /joint_states rate [Hz]', 1.0, 1000.0)),
    ('scene_rate_hz', 10.0, ('max /scene rate while an object moves [Hz]', 0.1, 100.0)),
    ('finger_angle_rad', 0.2, ('proximal finger joint angle [rad]', 0.0, 1.51)),
    ('initial_configuration', Parameter.Type.DOUBLE_ARRAY, ('7 arm angles [rad]; unset = home',)),
    (
        'max_trajectory_points',
        10_000,
        ('longer /joint_trajectory messages are rejected unread', 1, MAX_TRAJECTORY_POINTS_CAP),
    ),
    ('command_topic', '/joint_command', ('streamed sensor_msgs/JointState arm references',)),
    ('joint_offset_rad', [0.0] * 7, ('disturbance: servo offset per arm joint [rad]',)),
    ('command_latency_s', 0.0, ('disturbance: command latency [s]', 0.0, 2.0)),
    ('velocity_limit_scale', 1.0, ('disturbance: fraction of the velocity limits', 0.05, 1.0)),
    ('measurement_noise_rad', 0.0, ('disturbance: joint-state noise σ [rad]', 0.0, 0.1)),
    ('noise_seed', 0, ('seed of the measurement noise', 0, 2**31 - 1)),
    ('scene_events', '', ('test events (#32): YAML/JSON list, see jaco2_sim.scene_events',)),
]


def declare_parameters(node: Node) -> None:
    """Declare :data:`PARAMETERS` and the read-only ``robot_description`` on ``node``."""
    params = [(n, v, range_descriptor(*d)) for n, v, d in PARAMETERS]
    urdf = range_descriptor('URDF', read_only=True)
    node.declare_parameters('', [*params, ('robot_description', urdf_text(), urdf)])


def param(node: Node, name: str) -> Any:
    """The value of parameter ``name`` of ``node``; None when declared without a value."""
    try:
        return node.get_parameter(name).value
    except ParameterUninitializedException:
        return None


def apply_parameters(node: Node, core: Simulation, params: Sequence[Parameter]) -> None:
    """After a parameter change (or at start): reconfigure the disturbances if one of
    ``params`` is one, arm the ``scene_events``.
    """
    if any(p.name in PARAMETER_FIELDS for p in params):
        core.configure_disturbances(disturbance_values(node))
    for p in params:
        if p.name == 'scene_events':
            core.configure_events(p.value)
            if p.value.strip():
                node.get_logger().info(f'scene events armed: {len(core.events.events)}')


def log_events(node: Node, core: Simulation) -> None:
    """Log what the scene events did since the last call (#32)."""
    while core.event_log:
        node.get_logger().info(core.event_log.pop(0))


def disturbance_values(node: Node, params: Sequence[Parameter] = ()) -> dict[str, Any]:
    """The disturbance parameters of ``node``, with the changes in ``params`` applied."""
    values = {name: node.get_parameter(name).value for name in PARAMETER_FIELDS}
    return values | {p.name: p.value for p in params if p.name in PARAMETER_FIELDS}


def check_parameters(node: Node, core: Simulation, params: list[Parameter]) -> SetParametersResult:
    """The on-set-parameters answer: the first invalid value's reason, else success."""
    logger = node.get_logger()
    for p in params:
        try:
            core.check_parameter(p.name, p.value, disturbance_values(node, params))
        except (*EXPECTED_ERRORS, TypeError, ValueError) as err:
            text = str(err)  # scene_events messages name their field already
            reason = text if text.startswith(p.name) else f'{p.name}: {text}'
            return SetParametersResult(successful=False, reason=reason)
        except Exception as err:  # a bad value must not kill the node
            reason = f'{p.name}: unexpected {type(err).__name__}: {err}'
            logger.error(f'parameter rejected: {reason}')
            return SetParametersResult(successful=False, reason=reason)
    return SetParametersResult(successful=True)
