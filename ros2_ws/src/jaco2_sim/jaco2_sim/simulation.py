"""The simulated arm and its world, as the ``jaco2_sim`` node's callbacks use them (no ROS).

:class:`Simulation` owns the robot model, the scenario, the :class:`~jaco2_sim.world.World` and
the :class:`~jaco2_sim.integrator.JointIntegrator`; the node converts messages and calls it.

Limits and failure behaviour:

* ``/joint_trajectory``: at most ``max_trajectory_points`` points (default 10 000, range 1 to
  100 000). The sim runs on one executor thread, so a message blocks /joint_states while it is
  handled: 10 000 points take about 0.08 s (0.07 s of it rclpy deserialisation), 100 000 about
  0.9 s and 35 MB. The subscription is raw: the point count is read from the CDR bytes first, and
  a longer trajectory is rejected (warning naming the limit) without being deserialised; the arm
  keeps its current motion. Any other bad trajectory is rejected with a warning too.
* ``~/reset_scene``, ``~/set_scene`` and the ``scenario`` parameter: a bad scenario or scene gives
  ``success=false`` / ``successful=false`` with the :class:`~jaco2_sim.exceptions.ScenarioError`
  text (file or ``SetScene``, field, problem); the current scene is kept. Any unexpected
  exception is answered the same way and logged as an error: the node never dies from a request.
* ``scene_events`` (#32, off by default): objects moved, added or removed at a time or when the
  hand comes near, grasps refused on a given attempt (:mod:`jaco2_sim.scene_events`); checked
  against the current scene when set (``successful=false`` naming the field).
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from jaco2_description.model import FINGER_JOINTS, Jaco2Model
from qtree_node_support.text import clip, quote
from qtree_scene.message import STATUS_CODES
from qtree_scene.scenario import load_scenario
from qtree_scene.scene import Scenario

from jaco2_sim.disturbances import PARAMETER_FIELDS, DisturbedDrive, from_parameters
from jaco2_sim.exceptions import Jaco2SimError, ModelError, ScenarioError, WorldError
from jaco2_sim.integrator import JointIntegrator
from jaco2_sim.scene_events import SceneEvent, SceneEvents, check_scene, parse_events, placed
from jaco2_sim.world import World

MAX_MESSAGE_CHARS = 1000  # longest answer message [characters]
ATTACH_DISTANCE_WARN = 0.25  # attach farther than this from the EE origin is suspicious [m]
EXPECTED_ERRORS = (Jaco2SimError, ModelError, ScenarioError)
STATUS_NAMES = {code: name for name, code in STATUS_CODES.items()}  # ObjectState.STATUS_*


class Simulation:
    """Arm, scene and grasp state of the simulator.

    Attributes:
        robot: kinematic model (fingers fixed at ``finger_angle`` [rad]).
        scenario: the current scene; ``world`` its object poses and statuses.
        sim: the joint integrator (arm configuration [rad], reference trajectory).
        drive: commands to ``sim`` and its measurement, with the configured disturbances.
        fingers: finger joint angles published with the arm, shape (6,) [rad].
    """

    def __init__(
        self,
        scenario: str,
        rate_hz: float,
        finger_angle: float,
        q0: Sequence[float] | None = None,
        disturbances: dict[str, Any] | None = None,
    ) -> None:
        """Load ``scenario`` (name or YAML path); the arm starts at ``q0`` or the scenario home.

        ``disturbances``: the :data:`~jaco2_sim.disturbances.PARAMETER_FIELDS` values (none: off).

        Raises:
            ScenarioError, ModelError, Jaco2SimError: a bad scenario, angle or configuration.
        """
        self.robot = Jaco2Model(finger_angle)
        self.scenario = load_scenario(scenario)
        self.world = World(self.scenario)
        start = self.scenario.home if q0 is None else q0
        self.sim = JointIntegrator(self.robot.limits, rate_hz, np.asarray(start, dtype=float))
        self.drive = DisturbedDrive(self.sim, from_parameters(disturbances or {}))
        self.fingers = np.zeros(len(FINGER_JOINTS))
        self.fingers[:3] = self.robot.finger_angle
        self._scene_version = -1
        self._last_scene_s = 0.0
        self.references_reached = 0  # streamed references reached (closed loop) [count]
        self.events = SceneEvents()  # scene events (#32): none unless the parameter is set
        self.event_log: list[str] = []  # what the events did since the node last read it
        # The node steps on one thread and loads scenes on another (#18): parsing a file stays
        # outside this lock, only the swap and the motion commands take it.
        self.lock = threading.Lock()

    def check_parameter(self, name: str, value: Any, disturbances: dict[str, Any]) -> None:
        """Raise if ``value`` is not valid for parameter ``name`` (checked before it is set).

        ``disturbances``: every disturbance parameter's value with this change applied.

        Raises:
            Jaco2SimError: ``finger_angle_rad`` cannot change after start.
            ScenarioError, ModelError, TypeError, ValueError: a bad scenario or configuration.
        """
        if name in PARAMETER_FIELDS:
            from_parameters(disturbances)
        elif name == 'scenario':
            load_scenario(value)
        elif name == 'initial_configuration' and value is not None:
            JointIntegrator(self.robot.limits, q0=np.asarray(value, dtype=float))
        elif name == 'finger_angle_rad':
            raise Jaco2SimError('fixed at start')
        elif name == 'scene_events':
            with self.lock:
                clutter = self._clutter_scenario()
            parse_events(value, clutter)

    def configure_events(self, text: str) -> None:
        """Arm the ``scene_events`` of ``text`` (checked before) from now on."""
        with self.lock:
            self.events = SceneEvents(parse_events(text, self._clutter_scenario()))
            self.events.arm(self.sim.time)

    def _clutter_scenario(self) -> Scenario:
        return dataclasses.replace(self.world.scenario, objects=tuple(self.world.clutter()))

    def install(self, scenario: Scenario) -> None:
        """Make ``scenario`` the scene and teleport home; on any exception nothing has changed."""
        world = World(scenario)
        with self.lock:
            self.sim.reset(np.asarray(scenario.home))
            self.drive.delay.clear()
            self.scenario, self.world = scenario, world
            self.events.arm(self.sim.time)  # the events act on the new scene from now on

    def load(self, name: str) -> None:
        """Load scenario ``name`` (installed name or YAML path) with :meth:`install`."""
        self.install(load_scenario(name))

    def reset_scene(self, name: str) -> str:
        """Reload ``name``, or the current scenario if '' (a SetScene one from memory)."""
        if name or self.scenario.source:
            self.load(name or self.scenario.source)
        else:  # a scene given by SetScene: back to its initial state
            self.install(self.scenario)
        return f'scenario {quote(self.scenario.name)} loaded'

    def set_scene(self, scenario: Scenario) -> str:
        """Install a scene given as a message (already validated)."""
        self.install(scenario)
        return f'scene {quote(scenario.name)} set ({len(scenario.objects)} objects)'

    def joint_state(self) -> tuple[Any, Any, Any]:
        """(measured arm angles [rad] (7,), velocities [rad/s] (7,), finger angles [rad] (6,))."""
        return self.drive.measured(), self.sim.velocity, self.fingers

    def command_point(self, names: list[str], positions: list[float]) -> str:
        """Follow a streamed joint reference (closed-loop execution); '' or why it is rejected."""
        try:
            with self.lock:
                self.drive.command('point', names, positions)
        except (Jaco2SimError, ValueError) as err:
            return str(err)
        return ''

    def configure_disturbances(self, values: dict[str, Any]) -> None:
        """Apply new disturbance parameter values (checked before)."""
        self.drive.configure(from_parameters(values))

    def step(self) -> tuple[bool, list[str]]:
        """One period: delayed commands applied, the arm moves, the held object follows.

        Returns:
            (a whole trajectory ended, why delayed commands were rejected). The end of a
            streamed reference (closed loop, one per control tick) is counted in
            :attr:`references_reached` instead: it is not an event a user acts on (#26).
        """
        with self.lock:
            errors = self.drive.apply_due()
            reached = self.sim.step()
            finished = reached and self.drive.applied_kind == 'trajectory'
            self.references_reached += reached and not finished
            if self.world.attached_id is not None:
                self.world.update(self.robot.ee_pose(self.sim.q))
            self._fire_events()
        return finished, errors

    def _fire_events(self) -> None:
        """Apply the scene events due now (under the lock); each line goes to :attr:`event_log`."""
        if not self.events.events:
            return
        hand = self.robot.ee_pose(self.sim.q).translation if self.events.watches_hand else None

        def centre(object_id: str) -> np.ndarray | None:
            state = self.world.objects.get(object_id)
            return None if state is None else state.pose.translation

        for event in self.events.due(self.sim.time, hand, centre):
            try:
                self._apply_event(event)
                self.event_log.append(f'scene event {event.describe()}')
            except Jaco2SimError as err:  # the world changed since the events were set
                self.event_log.append(f'scene event {event.field} skipped: {err}')

    def _apply_event(self, event: SceneEvent) -> None:
        world = self.world
        if event.kind == 'remove':
            world.remove(event.object_id)
            return
        if event.kind == 'add' and event.spec is not None:
            spec = event.spec
        elif event.xy is None:
            raise Jaco2SimError(
                f'scene event {event.field}: no position for {quote(event.object_id)}'
            )
        else:
            state = world.state(event.object_id)
            if state.status != 'in_clutter':
                raise Jaco2SimError(f'{quote(event.object_id)} is {state.status}')
            spec = placed(state.spec, event.xy, event.yaw)
        others = [o for o in world.clutter() if o.id != spec.id]
        check_scene(world.scenario, [*others, spec], f'{event.field}.xy')
        world.place(spec)

    def scene_due(self, now_s: float, rate_hz: float) -> bool:
        """Whether the world changed and the last /scene is older than ``1 / rate_hz`` [s]."""
        changed = self.world.version != self._scene_version
        return changed and now_s - self._last_scene_s >= 1.0 / rate_hz

    def scene_published(self, now_s: float) -> None:
        """Note that the current world was published at ``now_s`` [s]."""
        self._scene_version, self._last_scene_s = self.world.version, now_s

    def follow(
        self, names: list[str], times: Any, positions: Any, velocities: Any
    ) -> tuple[str, str]:
        """Follow a trajectory (empty: stop); log lines ``(warning or '', info)``.

        Args:
            names: joint names of the columns.
            times: time from start of each point [s], shape (N,).
            positions: joint angles of each point [rad], N rows.
            velocities: joint velocities of each point [rad/s], N rows, or None.

        Raises:
            Jaco2SimError, ModelError: a bad trajectory (the arm keeps its current motion).
        """
        with self.lock:
            if len(times) == 0:
                self.drive.delay.clear()
                self.sim.cancel()
                return '', 'empty trajectory: stopping'
            clamped = self.drive.command('trajectory', names, times, positions, velocities)
        warning = 'trajectory beyond the joint limits: clamped to them' if clamped else ''
        return warning, f'following a trajectory of {len(times)} points'

    def grasp(self, object_id: str, attach: bool, status_code: int) -> tuple[str, str]:
        """Attach (``attach``) or release ``object_id``: (answer message, warning or '').

        Args:
            object_id: the object grasped or released.
            attach: True to attach it to the hand, False to release it.
            status_code: ObjectState.STATUS_* of the object after a release.

        Raises:
            WorldError: unknown or static object, another one held, not held, bad status.
        """
        with self.lock:
            if attach:
                return self.attach(object_id)
            status = STATUS_NAMES.get(status_code, f'code {status_code}')
            return self.release(object_id, status), ''

    def attach(self, object_id: str) -> tuple[str, str]:
        """Grasp ``object_id`` where it is: (answer message, warning or '').

        Raises:
            WorldError: as :meth:`World.attach`, or a ``grasp_failure`` scene event refuses it.
        """
        refused = self.events.refuse_grasp(object_id)
        if refused is not None:
            attempt = self.events.attempts[object_id]
            raise WorldError(
                f'grasp of {quote(object_id)} failed (attempt {attempt}, {refused.field})'
            )
        distance = self.world.attach(object_id, self.robot.ee_pose(self.sim.q))
        warning = ''
        if distance > ATTACH_DISTANCE_WARN:
            warning = f'attached {quote(object_id)} {distance:.3f} m from the EE'
        return f'{quote(object_id)} attached', warning

    def release(self, object_id: str, status: str) -> str:
        """Release ``object_id`` with ``status`` (``'relocated'`` or ``'in_clutter'``)."""
        self.world.detach(object_id, status)
        return f'{quote(object_id)} released ({status})'


def answer(response: Any, change: Callable[[], str], label: str, prefix: str, logger: Any) -> Any:
    """Fill ``response.success``/``message`` from ``change()``; never raises.

    Args:
        response: a service response with ``success`` and ``message``.
        change: the action; returns the success message (or ``(message, warning to log)``),
            raises on a rejected request.
        label: service name for the log (``reset_scene``).
        prefix: start of the message of an unexpected error (the quoted file, ``SetScene``).
        logger: the node's logger (``warning``, ``error``).
    """
    try:
        done = change()
        message, warning = done if isinstance(done, tuple) else (done, '')
        response.success, response.message = True, message
        if warning:
            logger.warning(warning)
    except EXPECTED_ERRORS as err:
        response.success, response.message = False, clip(str(err), MAX_MESSAGE_CHARS)
        logger.warning(f'{label} rejected: {response.message}')
    except Exception as err:  # a bad request must not kill the node
        response.success = False
        unexpected = f'{prefix}: unexpected {type(err).__name__}: {err}'
        response.message = clip(unexpected, MAX_MESSAGE_CHARS)
        logger.error(f'{label} failed: {response.message}')
    return response
