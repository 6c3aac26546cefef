"""In-process execution of planned relocations on the simulator's integrator (for
``scripts/bench_execution.py`` and tests): open loop (the whole trajectory, as the motion
planner's ``open_loop`` mode streams it) or closed loop (the STPIK controller of
:mod:`stpik_motion_planner.closed_loop` at the control rate), at simulated time, with the
disturbances of :mod:`jaco2_sim.disturbances`. No ROS.

One tick: measure (noise) → controller step → command queued (latency) → due commands applied
→ integrator step (offset, velocity-limit scale). The metrics use the TRUE joint angles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from jaco2_description.model import ARM_JOINTS, Jaco2Model
from jaco2_sim.disturbances import CommandDelay, Disturbances, MeasurementNoise
from jaco2_sim.integrator import JointIntegrator
from jaco2_sim.world import World
from qtree_scene.scene import Scenario
from stpik_motion_planner.closed_loop import (
    ClosedLoopController,
    ExecutionStopped,
    PlannedMotion,
    segments,
)
from stpik_motion_planner.collision import SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.execution_config import ExecutionConfig
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.result import PlanResult
from stpik_motion_planner.stpik import Stpik

from qtree_benchmarks.motion.verification import placed_objects

CLEARANCE_RANGE_M = 0.05  # clearances are measured exactly up to this distance [m]
FAR_M = 0.03  # beyond this clearance the distance query runs every SPARSE_TICKS ticks [m]
SPARSE_TICKS = 4  # at < 0.4 m/s and 100 Hz: < 16 mm, so a close approach is never missed
SETTLE_EXTRA_S = 10.0  # simulated time allowed beyond the plan's duration [s]
DISTURBANCES: dict[str, Disturbances] = {
    'none': Disturbances(),
    'offset_0.05rad_j2': Disturbances(joint_offset_rad=(0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0)),
    'latency_50ms': Disturbances(latency_s=0.05),
    'velocity_0.7x': Disturbances(velocity_limit_scale=0.7),
    'noise_1mrad': Disturbances(noise_rad=0.001, noise_seed=7),
}


@dataclass
class Execution:
    """Metrics of one executed relocation.

    Attributes:
        completed: True when every segment finished (the object released, the arm back).
        failure: why not ('' when completed).
        errors_m: EE position error per tick vs the reference of that tick [m].
        placement_error_m: object centre at the release vs the planned one [m] (NaN if never
            released): the arm's placement, not the sim's standing of the object on its drop
            slot afterwards (up to ``qtree_scene.placement.SNAP_RADIUS_M``, a modelling step).
        duration_s: simulated time to complete (or to the stop) [s].
        step_s: wall time of each controller step [s] (empty in open loop).
        step_cpu_s: thread CPU time of each controller step [s] (empty in open loop).
        min_clearance_m: smallest robot (and carried object) to scene distance [m].
        min_clearance_pair: the two bodies of that distance (``'attached / O3'``).
        ee_ref: reference EE positions per tick [m], shape (T, 3).
        ee_actual: actual EE positions per tick [m], shape (T, 3).
    """

    completed: bool = False
    failure: str = ''
    errors_m: list[float] = field(default_factory=list)
    placement_error_m: float = math.nan
    duration_s: float = 0.0
    step_s: list[float] = field(default_factory=list)
    step_cpu_s: list[float] = field(default_factory=list)
    min_clearance_m: float = math.inf
    min_clearance_pair: str = ''
    ee_ref: list[np.ndarray] = field(default_factory=list)
    ee_actual: list[np.ndarray] = field(default_factory=list)


class Executor:
    """Executes one feasible relocation plan on a fresh integrator."""

    def __init__(
        self,
        scenario: Scenario,
        relocated: list[str],
        object_id: str,
        result: PlanResult,
        disturbances: Disturbances,
        robot: Jaco2Model | None = None,
        planner_config: PlannerConfig | None = None,
        config: ExecutionConfig | None = None,
    ) -> None:
        self.robot = robot if robot is not None else Jaco2Model()
        self.config = config if config is not None else ExecutionConfig()
        self.planner_config = planner_config if planner_config is not None else PlannerConfig()
        self.result, self.object_id, self.scenario = result, object_id, scenario
        removed = set(relocated) | {object_id}
        # The relocated objects stand on their drop slots 0 … len(relocated)−1, in order, and
        # the arm must clear them too (#29 point 5: they were left out of the checked scene).
        placed, _ = placed_objects(scenario, list(relocated))
        self.scene = SceneWorld([*(o for o in scenario.objects if o.id not in removed), *placed])
        self.world = World(scenario)
        self.sim = JointIntegrator(
            self.robot.limits, self.config.control_rate_hz, result.joint_trajectory[0]
        )
        self.sim.disturb(disturbances.joint_offset_rad, disturbances.velocity_limit_scale)
        self.delay = CommandDelay(disturbances.latency_s)
        self.noise = MeasurementNoise(disturbances.noise_rad, disturbances.noise_seed)
        self.motion = PlannedMotion(result.times, result.joint_trajectory, self.robot)
        self.monitor = Stpik(
            self.robot, self.planner_config.replace(obstacle_activation_m=CLEARANCE_RANGE_M)
        )
        self.out = Execution()
        self.max_ticks = int((result.times[-1] + SETTLE_EXTRA_S) * self.config.control_rate_hz)
        self.ticks = 0
        self._clearance = 0.0  # last measured clearance [m]
        self._released_at: np.ndarray | None = None  # object centre when released [m] (3,)

    def planned_placement(self) -> np.ndarray:
        """Where the plan releases the object: x_d(release) · x_d(grasp)⁻¹ · object [m] (3,)."""
        r = self.result
        grasp = self.motion.ee_of(r.joint_trajectory[r.grasp_index])
        release = self.motion.ee_of(r.joint_trajectory[r.release_index])
        obj = self.world.state(self.object_id).pose
        return (release * grasp.actInv(obj)).translation

    def run(self, mode: str) -> Execution:
        """Execute in ``mode`` (``'open_loop'`` or ``'closed_loop'``); never raises on a stop."""
        planned = self.planned_placement()
        try:
            if mode == 'closed_loop':
                self._closed_loop()
            else:
                self._open_loop()
            self.out.completed = True
        except ExecutionStopped as err:
            self.out.failure = str(err)
        self.out.duration_s = self.sim.time
        if self._released_at is not None:
            self.out.placement_error_m = float(np.linalg.norm(self._released_at - planned))
        return self.out

    def _tick(self, ee_ref: pin.SE3) -> None:
        """Apply the due commands, advance the integrator, record the metrics at the new state."""
        self.ticks += 1
        if self.ticks > self.max_ticks:
            raise ExecutionStopped('settle', f'not finished within {self.max_ticks} ticks')
        for command in self.delay.due(self.sim.time):
            if isinstance(command, tuple):
                self.sim.set_reference(ARM_JOINTS, *command)
            else:
                self.sim.set_point(ARM_JOINTS, command)
        self.sim.step()
        q = np.array(self.sim.q)
        world_ee = self.motion.ee_of(q)
        self.world.update(world_ee)
        self.out.errors_m.append(float(np.linalg.norm(ee_ref.translation - world_ee.translation)))
        self.out.ee_ref.append(ee_ref.translation.copy())
        self.out.ee_actual.append(world_ee.translation.copy())
        # Far from everything (>= FAR_M) no point of the arm can close FAR_M - margin within
        # SPARSE_TICKS ticks, so the distance query runs every tick only when close.
        if self._clearance >= FAR_M and self.ticks % SPARSE_TICKS:
            return
        k = self.monitor.kinematics(q, self.scene)
        pair = min(k.scene_pairs, key=lambda p: p.distance, default=None)
        nearest = CLEARANCE_RANGE_M if pair is None else pair.distance
        self._clearance = nearest
        if nearest < self.out.min_clearance_m:
            self.out.min_clearance_m = nearest
            self.out.min_clearance_pair = '' if pair is None else f'{pair.name_a} / {pair.name_b}'

    def _grasp_or_release(self, attach: bool | None, controller: ClosedLoopController | None):
        q = np.array(self.sim.q)
        world_ee = self.motion.ee_of(q)
        if attach is True:
            self.world.attach(self.object_id, world_ee)
            obj = self.scenario.object(self.object_id)
            pose = self.world.state(self.object_id).pose
            self.monitor.bodies.attach(  # exact (#29) but its bottom against the table
                obj,
                world_ee.actInv(pose),
                self.planner_config.obstacle_min_distance_m + 0.002,
                settle_top_m=0.0,
                settle_vs_static_only=True,
            )
            if controller is not None:
                controller.attach(obj, pose, self.noise.measure(q))
        elif attach is False:  # where the arm let go, before the sim stands it on its slot
            self._released_at = self.world.state(self.object_id).pose.translation.copy()
            self.world.detach(self.object_id, 'relocated')
            self.monitor.bodies.detach()
            if controller is not None:
                controller.detach()

    def _closed_loop(self) -> None:
        controller = ClosedLoopController(self.robot, self.scene, self.planner_config, self.config)
        q_ref = np.array(self.result.joint_trajectory[0])
        for start, end, attach in segments(self.result):
            controller.begin(self.motion, start, end, q_ref)
            while controller.phase != 'done':
                tick = controller.step(self.noise.measure(self.sim.q))
                self.out.step_s.append(tick.step_s)
                self.out.step_cpu_s.append(tick.step_cpu_s)
                self.delay.push(self.sim.time, tick.q_ref)
                self._tick(self.motion.ee_at(tick.target_time))
            last = controller.q_ref  # set by begin()
            q_ref = q_ref if last is None else last
            self._grasp_or_release(attach, controller)

    def _open_loop(self) -> None:
        r = self.result
        for start, end, attach in segments(r):
            times = r.times[start : end + 1] - r.times[start]
            self.delay.push(self.sim.time, (times[1:], r.joint_trajectory[start + 1 : end + 1]))
            sent = self.sim.time
            applied = False
            while True:
                applied = applied or self.sim.active
                elapsed = self.sim.time + self.sim.period - sent  # at the state after the step
                ee_ref = self.motion.ee_at(r.times[start] + min(elapsed, times[-1]))
                self._tick(ee_ref)
                if applied and not self.sim.active:
                    break
            self._grasp_or_release(attach, None)


def summary(mode: str, disturbance: str, label: str, run: Execution) -> dict:
    """One ``rows[]`` object of ``execution.json`` (lengths in mm, step times in µs)."""
    errors = np.asarray(run.errors_m) * 1e3
    steps = np.asarray(run.step_s) * 1e6
    cpu = np.asarray(run.step_cpu_s) * 1e6
    return {
        'mode': mode,
        'disturbance': disturbance,
        'relocation': label,
        'completed': run.completed,
        'failure': run.failure,
        'rms_error_mm': _round(float(np.sqrt(np.mean(errors**2))) if errors.size else math.nan),
        'max_error_mm': _round(float(errors.max()) if errors.size else math.nan),
        'placement_error_mm': _round(run.placement_error_m * 1e3),
        'min_clearance_mm': _round(run.min_clearance_m * 1e3),
        'min_clearance_pair': run.min_clearance_pair,
        'time_to_complete_s': _round(run.duration_s),
        'step_median_us': _round(float(np.median(steps)) if steps.size else math.nan),
        'step_p99_us': _round(float(np.percentile(steps, 99)) if steps.size else math.nan),
        'step_cpu_median_us': _round(float(np.median(cpu)) if cpu.size else math.nan),
        'step_cpu_p99_us': _round(float(np.percentile(cpu, 99)) if cpu.size else math.nan),
        'ticks': len(run.errors_m),
    }


def _round(value: float) -> float | None:
    return None if not math.isfinite(value) else round(value, 2)


def optimal_relocations(scenario: Scenario, planner: MotionPlanner) -> list[tuple[list[str], str]]:
    """(relocated before, object) of each relocation of the exact optimal sequence."""
    from qtree_task_planner.exact import solve_exact
    from qtree_task_planner.oracle import MotionPlannerOracle

    oracle = MotionPlannerOracle(scenario, planner=planner)
    obstacles = tuple(o.id for o in scenario.obstacles)
    solution = solve_exact(obstacles, scenario.target.id, oracle)
    order = list(solution.sequence)
    return [(order[:i], object_id) for i, object_id in enumerate(order)]


def aggregate(runs: list[dict]) -> list[dict]:
    """One ``rows[]`` object per (mode, disturbance) over its relocations (worst cases)."""
    out = []
    keys = sorted({(r['mode'], r['disturbance']) for r in runs}, key=_row_order)
    for mode, disturbance in keys:
        group = [r for r in runs if (r['mode'], r['disturbance']) == (mode, disturbance)]
        done = [r for r in group if r['completed']]

        def values(key: str, rows: list[dict] = group) -> list[float]:
            return [r[key] for r in rows if r[key] is not None]

        rms = values('rms_error_mm')
        ticks = [r['ticks'] for r in group if r['rms_error_mm'] is not None]
        overall_rms = math.sqrt(
            sum(v**2 * n for v, n in zip(rms, ticks, strict=True)) / sum(ticks)
        )
        out.append(
            {
                'mode': mode,
                'disturbance': disturbance,
                'relocations': len(group),
                'completed': len(done),
                'rms_error_mm': round(overall_rms, 2),
                'max_error_mm': max(values('max_error_mm'), default=None),
                'placement_error_mm': max(values('placement_error_mm', done), default=None),
                'mean_placement_error_mm': _mean(values('placement_error_mm', done)),
                'min_clearance_mm': min(values('min_clearance_mm'), default=None),
                'time_to_complete_s': round(sum(values('time_to_complete_s', done)), 2),
                'step_median_us': _median(values('step_median_us')),
                'step_p99_us': max(values('step_p99_us'), default=None),
                'step_cpu_p99_us': max(values('step_cpu_p99_us'), default=None),
                'failures': [r['failure'] for r in group if r['failure']][:3],
            }
        )
    return out


def _row_order(key: tuple[str, str]) -> tuple[int, int]:
    names = list(DISTURBANCES)
    return (names.index(key[1]) if key[1] in names else 99, key[0] != 'open_loop')


def _mean(values: list[float]) -> float | None:
    return round(float(np.mean(values)), 2) if values else None


def _median(values: list[float]) -> float | None:
    return round(float(np.median(values)), 2) if values else None
