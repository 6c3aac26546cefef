"""The ``motion_planner`` node's ROS interface: QoS of /scene, parameters and their checks."""

from __future__ import annotations

import dataclasses

from qtree_node_support.parameters import range_descriptor
from rcl_interfaces.msg import ParameterDescriptor, ParameterType, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from stpik_motion_planner.config import INTEGER_FIELDS, RANGES, PlannerConfig, check_value
from stpik_motion_planner.exceptions import InvalidConfig, MotionPlannerError
from stpik_motion_planner.grasps import GRASP_FAMILIES, check_families

EXTRA = {  # name: (default, low, high, description)
    'execution_timeout_s': (
        30.0,
        0.1,
        600.0,
        "open loop: time beyond a segment's duration; closed loop: longest stall [s]",
    ),
    'goal_tolerance_rad': (0.02, 1e-4, 0.5, 'joint error at which a segment is reached [rad]'),
    'joint_state_timeout_s': (  # 3 s: a loaded 2-core demo once saw a 1.1 s callback gap
        3.0,
        0.05,
        60.0,
        'longest /joint_states silence during execution before EXECUTION_FAILED [s]',
    ),
    'scene_wait_s': (
        5.0,
        0.0,
        600.0,
        'longest wait of a request for a first /scene, or for the scene its scene_name names, '
        'before NO_SCENE [s]',
    ),
    'request_timeout_s': (
        10.0,
        0.0,
        600.0,
        'longest wait of a request for the busy planner before PLANNER_BUSY; the planning itself '
        'is bounded by time_limit_s [s]',
    ),
}


FAMILIES = 'grasp_families'  # string array parameter: PlannerConfig.grasp_families (#30)


def declare_parameters(node: Node) -> None:
    """Declare the planner's :data:`~stpik_motion_planner.config.RANGES`, ``grasp_families``
    and :data:`EXTRA`.
    """
    defaults = PlannerConfig()
    for name, (low, high, text) in RANGES.items():
        desc = range_descriptor(text, low, high, integer=name in INTEGER_FIELDS)
        node.declare_parameter(name, getattr(defaults, name), desc)
    node.declare_parameter(
        FAMILIES,
        list(defaults.grasp_families),
        ParameterDescriptor(
            type=ParameterType.PARAMETER_STRING_ARRAY,
            description=f'grasp families tried in this order, of {list(GRASP_FAMILIES)}; '
            "['side'] is the paper's setting",
        ),
    )
    for name, (value, low, high, text) in EXTRA.items():
        node.declare_parameter(name, value, range_descriptor(text, low, high, integer=False))


def planner_config(node: Node) -> PlannerConfig:
    """The node's current planner parameters."""
    values = {n: node.get_parameter(n).value for n in RANGES}
    return PlannerConfig(**values, grasp_families=tuple(node.get_parameter(FAMILIES).value))


def check_parameters(
    params: list[Parameter], current: PlannerConfig
) -> tuple[SetParametersResult, PlannerConfig | None]:
    """The on-set-parameters answer, and the new planner config (None: nothing to rebuild)."""
    try:
        for p in params:
            if p.name in RANGES:
                check_value(p.name, p.value)
        changes = {p.name: p.value for p in params if p.name in RANGES}
        for p in params:
            if p.name == FAMILIES:
                try:
                    changes[FAMILIES] = check_families(list(p.value or []))
                except ValueError as err:
                    raise InvalidConfig(FAMILIES, p.value, str(err)) from None
        config = dataclasses.replace(current, **changes)
    except (MotionPlannerError, TypeError) as err:
        return SetParametersResult(successful=False, reason=str(err)), None
    return SetParametersResult(successful=True), config if changes else None
