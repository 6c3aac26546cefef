"""Numbers of the closed-loop executor (paper Sect. 3.1, the local controller), with ranges.

No ROS import. The motion-planner node declares one ROS parameter per field of
:class:`ExecutionConfig` (same name, same range), so :data:`EXECUTION_RANGES` is the single place
where valid values are defined. Gains are K·dt per control tick, as in eq. (6).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from qtree_node_support.ranges import Range, setting_problem

from stpik_motion_planner.exceptions import InvalidConfig

EXECUTION_MODES = ('open_loop', 'closed_loop')
# name -> (lower, upper, description); every bound inclusive.
EXECUTION_RANGES: dict[str, Range] = {
    'control_rate_hz': (10.0, 1000.0, 'closed-loop control rate [Hz]'),
    'tracking_gain': (0.01, 0.5, 'EE error correction K·dt per control tick (eq. 6) [-]'),
    'execution_set_gain': (0.01, 0.5, 'set-based task gain K·dt per control tick [-]'),
    'execution_posture_gain': (0.0, 0.5, 'posture (planned joints) gain K·dt per tick [-]'),
    'max_tracking_error_m': (0.001, 0.5, 'EE position error that stops the execution [m]'),
    'max_tracking_error_rad': (0.01, 1.0, 'EE orientation error that stops it [rad]'),
    'slow_down_error_m': (
        0.0,
        0.5,
        'EE error above which the reference slows down; it stops '
        'halfway to max_tracking_error_m [m]',
    ),
    'settle_tolerance_m': (1e-4, 0.05, 'EE position error at which a segment is done [m]'),
    'settle_tolerance_rad': (1e-3, 0.5, 'EE orientation error at which it is done [rad]'),
    'settle_timeout_s': (
        0.01,
        60.0,
        'longest settling at the end of a segment, or stall of the '
        'reference, before the execution stops [s]',
    ),
    'max_lead_rad': (0.01, 1.0, 'largest reference lead over the measured joints [rad]'),
    'activation_slack_m': (
        0.0,
        0.1,
        'set-based distance tasks activate this far above the '
        "planner's failure margins while executing [m]",
    ),
    'margin_tolerance_m': (
        0.0,
        0.05,
        'a measured distance this far below a failure margin '
        'stops the execution (measurement noise) [m]',
    ),
    'joint_limit_slack_rad': (
        0.0,
        0.5,
        'joint-limit task activation inside the limits while executing [rad]',
    ),
}


@dataclass(kw_only=True)
class ExecutionConfig:
    """All tunable numbers of closed-loop execution; see :data:`EXECUTION_RANGES`."""

    control_rate_hz: float = 100.0
    tracking_gain: float = 0.15
    execution_set_gain: float = 0.15
    execution_posture_gain: float = 0.05
    max_tracking_error_m: float = 0.05
    max_tracking_error_rad: float = 0.3
    slow_down_error_m: float = 0.005
    settle_tolerance_m: float = 0.001  # 1 mm, well under the tests' 5 mm (#26)
    settle_tolerance_rad: float = 0.02
    settle_timeout_s: float = 3.0
    max_lead_rad: float = 0.2
    activation_slack_m: float = 0.002
    joint_limit_slack_rad: float = 0.01
    margin_tolerance_m: float = 0.002

    def __post_init__(self) -> None:
        for item in dataclasses.fields(self):
            check_execution_value(item.name, getattr(self, item.name))

    @property
    def period(self) -> float:
        """Control period dt = 1 / ``control_rate_hz`` [s]."""
        return 1.0 / self.control_rate_hz


def check_execution_value(name: str, value: object) -> None:
    """Check one :class:`ExecutionConfig` field value.

    Raises:
        InvalidConfig: unknown name, not a finite number, or out of range.
    """
    problem = setting_problem(EXECUTION_RANGES, name, value, kind='execution')
    if problem is not None:
        raise InvalidConfig(name, value, problem)


def check_mode(value: object) -> str:
    """The execution mode ``value`` if it is one of :data:`EXECUTION_MODES`.

    Raises:
        InvalidConfig: another value.
    """
    if value not in EXECUTION_MODES:
        raise InvalidConfig('execution_mode', value, f'must be one of {EXECUTION_MODES}')
    return str(value)
