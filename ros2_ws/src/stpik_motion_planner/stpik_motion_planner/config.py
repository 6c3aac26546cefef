"""Tunable numbers of the motion planner, with their ranges (no ROS import).

The node declares one ROS parameter per field of :class:`PlannerConfig` (same name, same range),
so :data:`RANGES` is the single place where valid values are defined.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from qtree_node_support.ranges import Range, setting_problem

from stpik_motion_planner.exceptions import InvalidConfig
from stpik_motion_planner.grasps import PAPER_GRASP_FAMILIES, check_families

# name -> (lower, upper, description); every bound inclusive.
RANGES: dict[str, Range] = {
    'position_tolerance_m': (1e-4, 0.1, 'EE position tracking tolerance [m]'),
    'orientation_tolerance_rad': (1e-3, 0.5, 'EE orientation tracking tolerance [rad]'),
    'ee_gain': (0.05, 1.0, 'EE task gain K·dt per STPIK iteration (eq. 6) [-]'),
    'set_gain': (0.05, 1.0, 'gain K·dt of activated set-based tasks [-]'),
    'posture_gain': (0.0, 1.0, 'gain K·dt of the lowest-priority posture task [-]'),
    'damping': (1e-6, 0.5, 'damping of the pseudo-inverse near singularities [-]'),
    'singular_threshold': (1e-4, 0.5, 'singular value below which damping starts [-]'),
    'joint_limit_activation_rad': (0.0, 0.5, 'joint-limit task activation margin [rad]'),
    'self_activation_m': (0.0, 0.2, 'self-hit task activation distance [m]'),
    'self_min_distance_m': (0.0, 0.1, 'self-hit failure distance [m]'),
    'obstacle_activation_m': (0.0, 0.2, 'obstacle task activation distance [m]'),
    'obstacle_min_distance_m': (0.0, 0.1, 'scene safety margin: failure distance [m]'),
    'step_m': (0.005, 0.2, 'Cartesian sample spacing along the path [m]'),
    'step_rad': (0.01, 1.0, 'Cartesian sample spacing in orientation [rad]'),
    'max_iterations': (1, 100, 'STPIK iterations per path sample [-]'),
    'max_joint_step_rad': (0.01, 1.0, 'largest joint change per STPIK iteration [rad]'),
    'time_limit_s': (1e-3, 600.0, 'planning time limit of one check [s]'),
    'sampling_time_s': (
        1e-3,
        10.0,
        'wall-time cap of the RRTConnect of a free-space segment (past it: TIMEOUT) [s]',
    ),
    'seed': (0, 2**31 - 1, 'seed of the sampling planner [-]'),
    'carry_tilt_limit_rad': (
        0.0,
        math.pi,
        'largest tilt of the carried object from upright during the carry (#29) [rad]',
    ),
    'approach_directions': (1, 64, 'approach yaws tried around the object [-]'),
    'approach_yaw_step_rad': (0.05, 1.6, 'yaw between consecutive approach directions [rad]'),
    'ik_restarts': (0, 50, 'random IK seeds tried after a failed pre-grasp / slot solve [-]'),
    'rrt_transit_s': (
        0.0,
        10.0,
        'wall-time cap of the RRTConnect of a colliding transit (past it: TIMEOUT), 0 = off [s]',
    ),
    'rrt_iterations': (
        0,
        100000,
        'RRTConnect iterations of a colliding joint transit, 0 = off [-]',
    ),
    'sampling_iterations': (1, 100000, 'RRTConnect iterations per free-space segment [-]'),
    'pregrasp_standoff_m': (0.02, 0.5, 'pre-grasp distance before the grasp [m]'),
    'grasp_depth_m': (-0.05, 0.05, 'EE origin beyond the object axis along the approach [m]'),
    'lift_clearance_m': (0.0, 0.5, 'carried object bottom above the tallest object [m]'),
    'retreat_m': (0.0, 0.5, 'retreat after release along -approach [m]'),
    'velocity_scale': (0.01, 1.0, 'fraction of the joint velocity limits used [-]'),
    'slot_spacing_m': (0.02, 0.5, 'distance between drop-zone slots [m]'),
}
INTEGER_FIELDS = frozenset(
    {
        'max_iterations',
        'seed',
        'approach_directions',
        'ik_restarts',
        'rrt_iterations',
        'sampling_iterations',
    }
)


@dataclass(kw_only=True)
class PlannerConfig:
    """All tunable numbers (see :data:`RANGES` for units and ranges) and the grasp families."""

    position_tolerance_m: float = 0.01
    orientation_tolerance_rad: float = 0.05
    ee_gain: float = 1.0
    set_gain: float = 0.5
    posture_gain: float = 0.1
    damping: float = 0.02
    singular_threshold: float = 0.02
    joint_limit_activation_rad: float = 0.1
    self_activation_m: float = 0.03
    self_min_distance_m: float = 0.005
    obstacle_activation_m: float = 0.025
    obstacle_min_distance_m: float = 0.005
    step_m: float = 0.04
    step_rad: float = 0.15
    max_iterations: int = 12  # the Cartesian step bound needs more, shorter steps near bodies
    max_joint_step_rad: float = 0.3
    time_limit_s: float = 5.0  # verification + Cartesian-bounded steps on a loaded 2-core machine
    sampling_time_s: float = 2.0  # a cap only: sampling_iterations bound the search (#29)
    sampling_iterations: int = 500
    seed: int = 0
    # ±1.6 rad around the azimuth: front-row objects (reach ≈ 0.4 m) are only reachable from
    # the side (approached radially, the wrist folds over the base and link 6 hits the object).
    # Every 0.2 rad: in clearable clutter the free approaches are narrow windows that a 0.4 rad
    # step misses (17 of 17 false "infeasible" answers of the 0.4 rad step were found at 0.2).
    approach_directions: int = 17
    approach_yaw_step_rad: float = 0.2
    # Fallbacks of .robust_stpik: another IK branch or a detour where the first one fails.
    ik_restarts: int = 5
    rrt_transit_s: float = 5.0  # a cap only: the iterations bound the search (#29)
    rrt_iterations: int = 1000
    pregrasp_standoff_m: float = 0.1
    grasp_depth_m: float = 0.0
    lift_clearance_m: float = 0.04
    # A cup or a bottle stays upright: a carry transit tilting it more is replaced by an
    # STPIK-tracked carry that holds the EE orientation (#29: up to 19.6° on s2 before).
    carry_tilt_limit_rad: float = math.radians(10.0)
    retreat_m: float = 0.1  # the hand ends ≥ 25 mm (activation) from the placed object
    velocity_scale: float = 0.5
    slot_spacing_m: float = 0.1
    # Grasp families tried, in this order (#30: 'top' for packed clutter); the paper's side
    # grasp alone by default, so the paper scenes and tables keep their meaning.
    grasp_families: tuple[str, ...] = PAPER_GRASP_FAMILIES

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Check every field against :data:`RANGES`.

        Raises:
            InvalidConfig: a value is not a finite number inside its range, or an activation
                threshold is below its failure distance.
        """
        for item in dataclasses.fields(self):
            if item.name != 'grasp_families':
                check_value(item.name, getattr(self, item.name))
        try:
            self.grasp_families = check_families(self.grasp_families)
        except ValueError as err:
            raise InvalidConfig('grasp_families', self.grasp_families, str(err)) from None
        if self.obstacle_activation_m < self.obstacle_min_distance_m:
            raise InvalidConfig(
                'obstacle_activation_m', self.obstacle_activation_m, 'below obstacle_min'
            )
        if self.self_activation_m < self.self_min_distance_m:
            raise InvalidConfig('self_activation_m', self.self_activation_m, 'below self_min')

    def replace(self, **changes: Any) -> PlannerConfig:
        """A validated copy with ``changes`` applied."""
        return dataclasses.replace(self, **changes)


def check_value(name: str, value: object) -> None:
    """Check one field value.

    Raises:
        InvalidConfig: unknown name, wrong type, not finite, or out of range.
    """
    problem = setting_problem(RANGES, name, value, kind='planner', integer_fields=INTEGER_FIELDS)
    if problem is not None:
        raise InvalidConfig(name, value, problem)
