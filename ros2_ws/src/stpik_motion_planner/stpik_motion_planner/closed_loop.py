"""The paper's local controller (Sect. 3.1, Figure 2): STPIK in the loop while the arm executes.

No ROS import. At each control tick :meth:`ClosedLoopController.step` takes the measured joint
angles q_m, the planned end-effector reference x_d(t) (the forward kinematics of the planned
joint trajectory, linear between samples, see :class:`PlannedMotion`) and runs ONE step of
eq. (6) with the same set-based hierarchy as the planner's check (joint limits, self-hit,
obstacles against the live scene, EE pose, posture), through the planner's own
:meth:`~stpik_motion_planner.stpik.Stpik.solve`. The plan was checked with the planner's wide
activation bands and may pass inside them, so while executing the distance tasks activate at the
planner's failure margins + ``activation_slack_m`` and the joint-limit task
``joint_limit_slack_rad`` inside the limits. The EE task's error is

    K σ̃ = [x_d(t + dt) ⊖ x_d(t)] + K·dt (x_d(t) ⊖ x(q_m))          (feed-forward + correction)

and the posture task's is Δq_d + K·dt (q_d(t) − q_m) with Δq_d = q_d(t + dt) − q_d(t), so the
redundancy follows the plan (also through joint-space transits near singularities). The joint
step is integrated on the streamed reference, q_r ← q_r + q̇ dt. The step is computed at the
predicted arm, q_r + offset (a Smith predictor, :class:`.arm_observer.ArmObserver`: the offset is
the measured arm minus the reference it was following, found across the round trip), so a
constant actuator offset is rejected without correcting against a measurement that is a round
trip old (that loop overshot and oscillated on a loaded machine, #26); x(q_m) in the correction
above is that prediction, and the tracking error checked is the measured arm against the plan
at the time the measurement shows. The set-based checks stay on the measured arm. The
reference stays within the joint limits and within ``max_lead_rad`` of q_m (anti wind-up).
When the arm lags (error above ``slow_down_error_m``) the reference time slows down, and stops
halfway to ``max_tracking_error_m``, so a slow or late arm follows the path instead of cutting
corners.

It stops with :class:`ExecutionStopped` (and a message naming why) when the measured state is
unusable, a set-based task cannot hold its set (a measured distance at or below the planner's
failure margin, a joint beyond its limit), or the EE error exceeds ``max_tracking_error_m`` /
``_rad`` (naming the set-based task that held the arm back, e.g. an object moved into the path).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from jaco2_description.model import ARM_JOINTS, EE_FRAME, Jaco2Model
from qtree_scene.scene import ObjectSpec

from stpik_motion_planner.arm_observer import ArmObserver
from stpik_motion_planner.collision import Proximity, SceneWorld
from stpik_motion_planner.config import PlannerConfig
from stpik_motion_planner.exceptions import MotionPlannerError
from stpik_motion_planner.execution_config import ExecutionConfig
from stpik_motion_planner.result import PlanResult, Reason
from stpik_motion_planner.stpik import Stpik
from stpik_motion_planner.tasks import EePoseTask, Kinematics, PostureTask, TaskRows
from stpik_motion_planner.tasks.ee_pose_task import pose_error

# A segment is done once the EE error, averaged over this long [s], is within the settle
# tolerance (#26): done at the first tick within it, the hand of a lagging arm (50 ms latency)
# went on to the leading reference and came to rest 5-9 mm from the plan. Averaged, not every
# tick: with 1 mrad measurement noise the measured error is 0.6-1.2 mm at rest, so "every tick
# of 0.2 s within 1 mm" never held and every segment ended on settle_timeout_s (0 of 15 done).
SETTLE_HOLD_S = 0.2
# ... and no error of that window further than this from the window's mean [m]: the arm is at
# rest (a hand passing through the plan at 5 cm/s spreads ±5 mm over the window; noise ~1 mm).
SETTLE_SPREAD_M = 0.003
# The carried object's collision body is this much shorter at its bottom against static bodies
# [m]: the plan sets it down ON the table (the planner shortens it by its margin + 2 mm), so the
# executor leaves room for a few mm of overshoot there. Against every other object, and at its
# top and sides, it is checked at its true size (#29: 20 mm short at both ends against
# everything, the carried bottom went 7.5 mm into an object standing on the drop slot).
SETTLE_M = 0.02


# The streamed reference leads the measured arm (up to max_lead_rad); where it takes the arm (the
# reference plus the arm's offset, :class:`.arm_observer.ArmObserver`) is checked against
# penetration (#29 point 5).
REFERENCE_CLEARANCE_M = 0.0  # penetrating, it is a command into an object [m]
STALL_RATE = 0.05  # reference time advancing slower than this share of real time: stalled


class ExecutionStopped(MotionPlannerError):  # noqa: N818
    """The closed loop stopped the arm; ``cause`` says which check failed.

    Attributes:
        cause: ``'joint_state'``, ``'joint_limits'``, ``'self_hit'``, ``'obstacles'``,
            ``'tracking'`` or ``'settle'``.
    """

    reason = Reason.EXECUTION_FAILED

    def __init__(self, cause: str, message: str) -> None:
        self.cause = cause
        super().__init__(message)


def segments(result: PlanResult) -> list[tuple[int, int, bool | None]]:
    """The executed segments of a plan: (first sample, last sample, attach after it).

    ``True``: attach the object at the end (grasp), ``False``: release it, ``None``: nothing.
    """
    g, r = result.grasp_index, result.release_index
    return [(0, g, True), (g, r, False), (r, len(result.times) - 1, None)]


def measured_q(names: Sequence[str], positions: Sequence[float]) -> np.ndarray:
    """The 7 arm angles [rad] of a joint state, in :data:`ARM_JOINTS` order.

    Finger joints may be present; any other name, a missing arm joint, a length mismatch or a
    non-finite value is refused.

    Raises:
        ExecutionStopped: (``cause='joint_state'``) the state is unusable, with why.
    """
    names = list(names)
    if len(names) != len(positions):
        raise ExecutionStopped(
            'joint_state', f'joint state has {len(names)} names but {len(positions)} positions'
        )
    missing = [n for n in ARM_JOINTS if n not in names]
    if missing:
        raise ExecutionStopped('joint_state', f'joint state misses arm joints {missing}')
    extra = [n for n in names if n not in ARM_JOINTS and 'finger' not in n]
    if extra:
        raise ExecutionStopped('joint_state', f'joint state has unknown joints {extra[:5]}')
    if len(set(names)) != len(names):
        raise ExecutionStopped('joint_state', 'joint state names a joint twice')
    q = np.array([positions[names.index(n)] for n in ARM_JOINTS], dtype=float)
    if not np.all(np.isfinite(q)):
        raise ExecutionStopped('joint_state', f'joint state has non-finite arm angles {q}')
    return q


def _set_lost(task: str, pair: Proximity, margin_m: float) -> str:
    """Why ``task`` (``'self_hit'`` or ``'obstacles'``) cannot hold its set at ``pair``."""
    gap = f'{pair.distance * 1e3:.1f} mm'
    if task == 'self_hit':
        where = f'self-hit task cannot hold its set: {pair.name_a} and {pair.name_b} {gap} apart'
    else:
        where = f'obstacle task cannot hold its set: {pair.name_a} {gap} from {pair.name_b!r}'
    return f'{where} (margin {margin_m * 1e3:.1f} mm)'


class PlannedMotion:
    """The planned motion, time-parametrised: q_d(t) linear between samples, x_d(t) = FK(q_d(t)).

    Attributes:
        times: time of each sample from the start [s], shape (N,), increasing.
        joints: planned joint angles [rad], shape (N, 7).
    """

    def __init__(self, times: np.ndarray, joints: np.ndarray, robot: Jaco2Model) -> None:
        self.times = np.asarray(times, dtype=float)
        self.joints = np.asarray(joints, dtype=float)
        self._model = robot.model
        self._data = robot.model.createData()
        self._frame = robot.model.getFrameId(EE_FRAME)
        self._cache: list[tuple[float, pin.SE3]] = [(np.nan, pin.SE3.Identity())] * 4

    def joints_at(self, t: float) -> np.ndarray:
        """q_d(t) [rad] (7,), held at the ends."""
        times = self.times
        if t <= times[0]:
            return self.joints[0].copy()
        if t >= times[-1]:
            return self.joints[-1].copy()
        k = int(np.searchsorted(times, t, side='right')) - 1
        s = (t - times[k]) / (times[k + 1] - times[k])
        return (1 - s) * self.joints[k] + s * self.joints[k + 1]

    def ee_at(self, t: float) -> pin.SE3:
        """x_d(t): the EE pose (world frame) at the planned joints of time ``t`` [s].

        The last four answers are kept: a control tick asks for x_d(t + dt) and for the plan time
        its measurement shows, the next tick for x_d(t).
        """
        for cached_t, pose in self._cache:
            if cached_t == t:
                return pose
        pose = self.ee_of(self.joints_at(t))
        self._cache = [*self._cache[1:], (t, pose)]
        return pose

    def ee_of(self, q: np.ndarray) -> pin.SE3:
        """EE pose (world frame) at joint angles ``q`` [rad] (7,)."""
        pin.framesForwardKinematics(self._model, self._data, q)
        return pin.SE3(self._data.oMf[self._frame])


class FeedforwardEeTask(EePoseTask):
    """EE pose task of the controller: rows (J_ee, feed-forward + K·dt (x_d ⊖ x))."""

    name = 'ee_pose'

    def __init__(self, gain: float) -> None:
        super().__init__(gain=gain)
        self.feedforward = np.zeros(6)

    def compute(self, k: Kinematics) -> TaskRows:
        """Rows (J_ee (6, 7), Δx_d + K σ̃ (6,))."""
        rows = super().compute(k)
        return TaskRows(rows.jacobian, rows.error + self.feedforward, rows.labels)


class FeedforwardPostureTask(PostureTask):
    """Posture task of the controller: rows (I, Δq_d + K·dt (q_d − q)), the planned joints."""

    name = 'posture'

    def __init__(self, gain: float) -> None:
        super().__init__(np.zeros(7), gain)
        self.feedforward = np.zeros(7)

    def compute(self, k: Kinematics) -> TaskRows:
        """Rows (I (7, 7), Δq_d + K (q_d − q) (7,))."""
        rows = super().compute(k)
        return TaskRows(rows.jacobian, rows.error + self.feedforward, rows.labels)


@dataclass(frozen=True)
class ControlTick:
    """What one control tick measured and commanded.

    Attributes:
        plan_time: time along the plan of the reference [s].
        q_ref: streamed joint reference [rad], shape (7,).
        q_meas: measured joints [rad], shape (7,).
        ee_ref: reference EE pose x_d, xyz [m] + quaternion xyzw, shape (7,).
        ee_meas: EE pose at q_meas, same layout.
        error_m: |position error| [m].
        error_rad: |orientation error| [rad].
        clearance_m: smallest measured robot-scene distance below the obstacle activation
            distance [m], inf when nothing is that close.
        active: set-based tasks in the hierarchy this tick.
        phase: ``'tracking'``, ``'settling'`` or ``'done'``.
        step_s: wall time of the step [s].
        step_cpu_s: CPU time of the calling thread in the step [s] (wall time minus
            preemption on a shared machine).
        target_time: plan time the streamed reference aims at (one tick ahead) [s].
    """

    plan_time: float
    q_ref: np.ndarray
    q_meas: np.ndarray
    ee_ref: np.ndarray
    ee_meas: np.ndarray
    error_m: float
    error_rad: float
    clearance_m: float
    active: tuple[str, ...]
    phase: str
    step_s: float
    step_cpu_s: float
    target_time: float


class ClosedLoopController:
    """One STPIK step per control tick along a segment of a :class:`PlannedMotion`.

    Owns its own :class:`Stpik` (the planner may plan concurrently). Not thread-safe: one
    caller at a time (the node's control timer).

    Attributes:
        config: execution settings.
        q_ref: last streamed reference [rad] (7,), None before :meth:`begin`.
        phase: ``'idle'``, ``'tracking'``, ``'settling'`` or ``'done'``.
    """

    def __init__(
        self,
        robot: Jaco2Model,
        scene: SceneWorld,
        planner_config: PlannerConfig | None = None,
        config: ExecutionConfig | None = None,
    ) -> None:
        self.config = config if config is not None else ExecutionConfig()
        c = self.config
        base = planner_config if planner_config is not None else PlannerConfig()
        self.margins = base
        # The plan was checked with the planner's wide activation bands (and may pass inside
        # them); while executing, the set-based tasks guard the failure margins (+ a slack).
        self.stpik = Stpik(
            robot,
            base.replace(
                set_gain=c.execution_set_gain,
                posture_gain=c.execution_posture_gain,
                obstacle_activation_m=base.obstacle_min_distance_m + c.activation_slack_m,
                self_activation_m=base.self_min_distance_m + c.activation_slack_m,
                joint_limit_activation_rad=c.joint_limit_slack_rad,
            ),
        )
        self.ee_task = FeedforwardEeTask(c.tracking_gain)
        self.posture_task = FeedforwardPostureTask(c.execution_posture_gain)
        # The hierarchy of Stpik.solve, with feed-forward terms in the two equality tasks.
        self.stpik.ee, self.stpik.posture = self.ee_task, self.posture_task
        self.scene = scene
        self.robot = robot
        self.step_limit = np.asarray(robot.limits.velocity, dtype=float) * c.period
        self.q_ref: np.ndarray | None = None
        self.phase = 'idle'
        self._motion: PlannedMotion | None = None
        self._t = self._t_end = 0.0
        self._settle_s = 0.0
        self._settle_window: list[np.ndarray] = []  # EE errors (6,) of the last SETTLE_HOLD_S
        self._stalled_s = 0.0
        self.worst_error_m = 0.0  # largest EE position error of the segment so far [m]
        self.worst_error_rad = 0.0  # largest EE orientation error of the segment so far [rad]
        self.ticks = 0  # control ticks of the segment so far
        self.observer = ArmObserver(c.period)  # latency, offset and predicted arm (#26)

    @property
    def plan_time(self) -> float:
        """Time along the plan of the current reference [s] (where a stopped arm is)."""
        return self._t

    def set_scene(self, scene: SceneWorld) -> None:
        """Replace the scene checked by the obstacle task (the live scene)."""
        self.scene = scene

    def attach(self, obj: ObjectSpec, world_obj: pin.SE3, q_meas: np.ndarray) -> None:
        """Carry ``obj`` (pose ``world_obj``) as grasped at the measured joints ``q_meas``."""
        world_ee = self.stpik.kinematics(np.asarray(q_meas, dtype=float), SceneWorld([]))
        self.stpik.bodies.attach(
            obj,
            world_ee.world_ee.actInv(world_obj),
            settle_m=SETTLE_M,
            settle_top_m=0.0,
            settle_vs_static_only=True,
        )

    def detach(self) -> None:
        """Stop carrying the attached object."""
        self.stpik.bodies.detach()

    def begin(self, motion: PlannedMotion, start: int, end: int, q_ref: np.ndarray) -> None:
        """Track samples ``start`` to ``end`` of ``motion``; the reference starts at ``q_ref``."""
        same_motion = motion is self._motion
        self._motion = motion
        self._t, self._t_end = float(motion.times[start]), float(motion.times[end])
        self.q_ref = np.array(q_ref, dtype=float)
        self.observer.start(self.q_ref, self._t, same_motion)
        self.phase = 'tracking'
        self._settle_s = 0.0
        self._settle_window = []
        self._stalled_s = 0.0
        self.worst_error_m = self.worst_error_rad = 0.0
        self.ticks = 0

    def step(self, q_meas: np.ndarray) -> ControlTick:
        """One control tick from the measured joints ``q_meas`` [rad] (7,).

        The reference time advances one control period per tick (times the slow-down rate), so
        a loop that ticks late moves the reference slower, never in larger jumps.

        Returns:
            The tick (stream ``tick.q_ref``).

        Raises:
            ExecutionStopped: the measured state is unusable, a set-based task cannot hold its
                set, the tracking error is too large, or the segment does not settle in time.
        """
        start, cpu_start = time.perf_counter(), time.thread_time()
        if self._motion is None or self.q_ref is None:
            raise ExecutionStopped('joint_state', 'step() before begin()')
        c = self.config
        q = np.array(q_meas, dtype=float)  # a copy: a read-only measurement reaches numba
        if q.shape != (7,) or not np.all(np.isfinite(q)):
            raise ExecutionStopped('joint_state', f'measured joints must be 7 finite angles: {q}')
        ee_ref = self._motion.ee_at(self._t)
        k = self.stpik.kinematics(q, self.scene)
        self._check_sets(k)  # safety on the measured arm
        # The tracking error is the arm's deviation from where the plan had it when it was
        # measured (the round trip of a loaded machine is not an error, #26) ...
        error = pose_error(self._motion.ee_at(self.observer.measured(q)), k.world_ee)
        # ... and the step corrects the predicted arm, which has no delay to oscillate on.
        q_pred = np.clip(self.observer.predicted(self.q_ref), self.stpik.lower, self.stpik.upper)
        k_pred = self.stpik.kinematics(q_pred, self.scene)
        error_m, error_rad = float(np.linalg.norm(error[:3])), float(np.linalg.norm(error[3:]))
        self.ticks += 1
        self.worst_error_m = max(self.worst_error_m, error_m)
        self.worst_error_rad = max(self.worst_error_rad, error_rad)
        rate = self._time_scale(error_m)
        dt = c.period * rate
        t_next = min(self._t + dt, self._t_end) if self.phase == 'tracking' else self._t_end
        ee_next = self._motion.ee_at(t_next)
        self.ee_task.target = ee_ref
        self.ee_task.feedforward = pose_error(ee_next, ee_ref)
        q_plan = self._motion.joints_at(self._t)
        self.posture_task.reference = q_plan
        self.posture_task.feedforward = self._motion.joints_at(t_next) - q_plan
        dq, active = self.stpik.solve(k_pred)
        if error_m > c.max_tracking_error_m or error_rad > c.max_tracking_error_rad:
            raise ExecutionStopped('tracking', self._lost_message(k, error_m, error_rad, active))
        # Stalled while the reference (nearly) stands still; moving again only pays the stall back
        # tick for tick, so a limit cycle (held by a set-based task, creeping on a few ticks)
        # still ends with a stop instead of resetting the count forever.
        if rate < STALL_RATE:
            self._stalled_s += c.period
        else:
            self._stalled_s = max(0.0, self._stalled_s - c.period)
        if self._stalled_s > c.settle_timeout_s:
            raise ExecutionStopped(
                'tracking',
                f'reference stalled for {self._stalled_s:.1f} s: '
                + self._lost_message(k, error_m, error_rad, active),
            )
        largest = float(np.max(np.abs(dq) / self.step_limit))
        if largest > 1.0:  # never ask for more than the velocity limits
            dq /= largest
        q_ref = np.clip(self.q_ref + dq, self.stpik.lower, self.stpik.upper)
        q_ref = np.clip(q_ref, q - c.max_lead_rad, q + c.max_lead_rad)
        # Where the arm goes: the reference plus the arm's offset from what it is sent.
        self._check_reference(self.observer.predicted(q_ref))  # up to max_lead_rad ahead (#29)
        self.q_ref = q_ref
        self.observer.sent(q_ref, t_next)
        plan_time = self._t
        self._advance(t_next, error)
        clearance = min((p.distance for p in k.scene_pairs), default=np.inf)
        return ControlTick(
            plan_time,
            self.q_ref.copy(),
            q.copy(),
            pin.SE3ToXYZQUAT(ee_ref),
            pin.SE3ToXYZQUAT(k.world_ee),
            error_m,
            error_rad,
            float(clearance),
            tuple(active),
            self.phase,
            time.perf_counter() - start,
            time.thread_time() - cpu_start,
            t_next,
        )

    def _time_scale(self, error_m: float) -> float:
        """Rate of the reference time [-]: 1 up to ``slow_down_error_m``, 0 halfway to the
        largest error (the arm lags: slow velocity limits, latency, a loaded machine).
        """
        c = self.config
        span = 0.5 * (c.max_tracking_error_m - c.slow_down_error_m)
        if error_m <= c.slow_down_error_m or span <= 0.0:
            return 1.0
        return max(0.0, 1.0 - (error_m - c.slow_down_error_m) / span)

    def _advance(self, t_next: float, error: np.ndarray) -> None:
        """Move the reference time to ``t_next`` [s]; settle on the EE ``error`` (6,) [m, rad]."""
        c = self.config
        self._t = t_next
        if self.phase == 'tracking' and self._t >= self._t_end:
            self.phase = 'settling'
        if self.phase != 'settling':
            return
        window = self._settle_window
        window.append(np.array(error, dtype=float))
        size = max(1, round(SETTLE_HOLD_S / c.period))
        del window[:-size]
        mean = np.mean(window, axis=0)
        mean_m, mean_rad = float(np.linalg.norm(mean[:3])), float(np.linalg.norm(mean[3:]))
        spread = max(float(np.linalg.norm(e[:3] - mean[:3])) for e in window)
        if (
            len(window) == size
            and mean_m <= c.settle_tolerance_m
            and mean_rad <= c.settle_tolerance_rad
            and spread <= SETTLE_SPREAD_M
        ):  # at rest on the plan, not passing through it
            self.phase = 'done'
            return
        self._settle_s += c.period
        if self._settle_s > c.settle_timeout_s:
            raise ExecutionStopped(
                'settle',
                f'the arm did not settle within settle_timeout_s={c.settle_timeout_s:g} s at the '
                f'end of the segment (EE error over the last {SETTLE_HOLD_S:g} s: mean '
                f'{mean_m * 1e3:.1f} mm, {mean_rad:.3f} rad, spread {spread * 1e3:.1f} mm)',
            )

    def _check_sets(self, k: Kinematics) -> None:
        """Stop when a measured set-based quantity is at or past the planner's failure margin."""
        m = self.margins
        outside = np.flatnonzero((k.q < self.stpik.lower - 1e-6) | (k.q > self.stpik.upper + 1e-6))
        if outside.size:
            j = int(outside[0])
            raise ExecutionStopped(
                'joint_limits',
                f'joint {j + 1} at {k.q[j]:.3f} rad is outside its limits '
                f'[{self.stpik.lower[j]:.3f}, {self.stpik.upper[j]:.3f}]',
            )
        tolerance = self.config.margin_tolerance_m
        for task, pairs, margin in (
            ('self_hit', k.self_pairs, m.self_min_distance_m),
            ('obstacles', k.scene_pairs, m.obstacle_min_distance_m),
        ):
            lost = next((p for p in pairs if p.distance <= margin - tolerance), None)
            if lost is not None:
                raise ExecutionStopped(task, _set_lost(task, lost, margin))

    def _check_reference(self, q_ref: np.ndarray) -> None:
        """Stop before streaming a reference that takes the arm to ``q_ref`` [rad] (7,) (the
        reference plus the arm's offset) where it penetrates an object or the arm itself
        (:data:`REFERENCE_CLEARANCE_M`).

        The measured arm is checked by :meth:`_check_sets`; the reference leads it by up to
        ``max_lead_rad``, so a reference inside an object would drive the arm there before the
        next measurement shows it (#29 point 5). Collision only: bodies placed at ``q_ref``,
        first hit ends the check; the kinematics of the next tick place them again.
        """
        stpik = self.stpik
        stpik.place_bodies(q_ref)
        bodies = stpik.bodies
        if not bodies.scene_clear(self.scene, REFERENCE_CLEARANCE_M):
            p = min(
                bodies.scene_proximities(self.scene, REFERENCE_CLEARANCE_M),
                key=lambda p: p.distance,
            )
            raise ExecutionStopped(
                'obstacles',
                f'the joint reference would drive {p.name_a} into {p.name_b!r} '
                f'(distance {p.distance * 1e3:.1f} mm): held before it',
            )
        if not bodies.self_clear(REFERENCE_CLEARANCE_M):
            p = min(bodies.self_proximities(REFERENCE_CLEARANCE_M), key=lambda p: p.distance)
            raise ExecutionStopped(
                'self_hit',
                f'the joint reference would drive {p.name_a} into {p.name_b} '
                f'(distance {p.distance * 1e3:.1f} mm): held before it',
            )

    def _lost_message(
        self, k: Kinematics, error_m: float, error_rad: float, active: list[str]
    ) -> str:
        c = self.config
        text = (
            f'EE error {error_m * 1e3:.1f} mm / {error_rad:.3f} rad beyond '
            f'max_tracking_error_m={c.max_tracking_error_m * 1e3:.0f} mm / '
            f'max_tracking_error_rad={c.max_tracking_error_rad:g} rad'
        )
        if 'obstacles' in active and k.scene_pairs:
            p = min(k.scene_pairs, key=lambda p: p.distance)
            return (
                f'{text}: the obstacle task held the arm back ({p.name_a} '
                f'{p.distance * 1e3:.1f} mm from {p.name_b!r}; an object on the path?)'
            )
        if 'self_hit' in active and k.self_pairs:
            p = min(k.self_pairs, key=lambda p: p.distance)
            return f'{text}: the self-hit task held the arm back ({p.name_a}/{p.name_b})'
        if 'joint_limits' in active:
            return f'{text}: the joint-limit task held the arm back'
        return text
