"""Scene events of the simulator, for testing execution in a changing world (#32; no ROS import).

Off by default, like the disturbances. The ``scene_events`` parameter is a YAML (or JSON) list;
each entry is one event:

* ``{kind: move, object: O5, xy: [0.7, 0.0], yaw: 0.0, <trigger>}``: the object (in the clutter)
  jumps to ``xy`` [m] (standing on the table), turned by ``yaw`` [rad] (default: unchanged).
* ``{kind: add, object: X1, shape: cylinder, radius: 0.03, height: 0.12, xy: [...], <trigger>}``
  (a box takes ``size: [x, y, z]`` [m]): a new obstacle appears.
* ``{kind: remove, object: O4, <trigger>}``: the object disappears from the scene.
* ``{kind: grasp_failure, object: O3, attempt: 1}``: the ``attempt``-th attach request for the
  object (1 = the first) is refused (AttachObject answers ``success=false``); the object stays.

``<trigger>`` is exactly one of ``at_s: 2.5`` (seconds of simulated time after the events were
set or the scene was installed [s]) or ``hand_within_m: 0.15`` (when the end-effector origin
comes within this distance of the centre of ``of``, default the event's own object [m]). Every
event fires once; events are re-armed when a scene is installed (``reset_scene``, ``set_scene``,
``scenario``) or the parameter is set again.

Bad values are refused with a message naming the field (``scene_events[1].xy: ...``); a move or an
add that would leave the scene invalid (overlapping objects, off the table, on the drop zone) is
refused when set, checked against the scene as the earlier events leave it. An event whose object
is no longer in the clutter when it fires (e.g. being carried) is skipped with a warning.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

import numpy as np
import yaml
from qtree_scene.exceptions import ScenarioError
from qtree_scene.fields import Fail, brief, number
from qtree_scene.scenario import validate_scenario
from qtree_scene.scene import ObjectSpec, Scenario, vec3

from jaco2_sim.exceptions import SceneEventError

KINDS = ('move', 'add', 'remove', 'grasp_failure')
KEYS = {
    'move': {'xy', 'yaw'},
    'add': {'xy', 'yaw', 'shape', 'radius', 'height', 'size'},
    'remove': set(),
    'grasp_failure': {'attempt'},
}
TRIGGERS = {'at_s', 'hand_within_m', 'of'}
MAX_EVENTS = 100  # longest event list accepted [-]
MAX_AT_S = 86_400.0  # latest event time accepted [s]
MAX_HAND_DISTANCE_M = 2.0  # largest trigger distance accepted [m]


@dataclass(frozen=True)
class SceneEvent:
    """One validated event (see the module docstring).

    Attributes:
        index: position in the ``scene_events`` list (named in messages).
        kind: one of :data:`KINDS`.
        object_id: the object moved, added, removed or not grasped.
        at_s: fire this long after arming [s]; None: by the hand distance.
        hand_within_m: fire when the EE origin is this close to ``near``'s centre [m].
        near: the object whose distance to the hand triggers.
        xy: new centre on the table [m] (move, add).
        yaw: new rotation about z [rad]; None keeps it (move).
        spec: the added object (add).
        attempt: the refused attach attempt, 1-based (grasp_failure).
    """

    index: int
    kind: str
    object_id: str
    at_s: float | None = None
    hand_within_m: float | None = None
    near: str = ''
    xy: tuple[float, float] | None = None
    yaw: float | None = None
    spec: ObjectSpec | None = None
    attempt: int = 0

    @property
    def field(self) -> str:
        """``scene_events[i]`` (the prefix of its messages)."""
        return f'scene_events[{self.index}]'

    def describe(self) -> str:
        """e.g. ``"scene_events[0]: move 'O5' to (0.700, 0.000)"``."""
        where = f' to ({self.xy[0]:.3f}, {self.xy[1]:.3f})' if self.xy else ''
        return f'{self.field}: {self.kind} {self.object_id!r}{where}'


def parse_events(text: str, scenario: Scenario) -> tuple[SceneEvent, ...]:
    """Validate the ``scene_events`` parameter against ``scenario`` (the current scene).

    Args:
        text: YAML or JSON list of event mappings; '' or whitespace: no events.
        scenario: the scene the events act on, in order.

    Raises:
        SceneEventError: the first bad field, named (``scene_events[2].attempt: ...``).
    """
    if not text.strip():
        return ()
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise SceneEventError(f'scene_events: not YAML/JSON: {err}') from None
    if not isinstance(data, list):
        raise SceneEventError(f'scene_events: a list of events expected, got {brief(data)}')
    if len(data) > MAX_EVENTS:
        raise SceneEventError(f'scene_events: at most {MAX_EVENTS} events, got {len(data)}')
    events, objects = [], {o.id: o for o in scenario.objects}
    for index, entry in enumerate(data):
        event = _parse_event(index, entry, objects)
        if event.kind in ('move', 'add'):
            objects = _check_placed(event, objects, scenario)
        elif event.kind == 'remove':
            objects = {k: v for k, v in objects.items() if k != event.object_id}
        events.append(event)
    return tuple(events)


def _parse_event(index: int, entry: Any, objects: dict[str, ObjectSpec]) -> SceneEvent:
    name = f'scene_events[{index}]'

    def fail(key: str, problem: str) -> NoReturn:
        raise SceneEventError(f'{name}.{key}: {problem}')

    if not isinstance(entry, dict):
        raise SceneEventError(f'{name}: a mapping expected, got {brief(entry)}')
    kind = entry.get('kind')
    if kind not in KINDS:
        fail('kind', f'must be one of {", ".join(KINDS)}, got {brief(kind)}')
    allowed = {'kind', 'object'} | KEYS[kind] | (TRIGGERS if kind != 'grasp_failure' else set())
    for key in entry:
        if key not in allowed:
            names = ', '.join(sorted(allowed))
            fail(str(key), f'unknown key for a {kind} event (allowed: {names})')
    object_id = entry.get('object')
    if not isinstance(object_id, str) or not object_id:
        fail('object', f'a non-empty id expected, got {brief(object_id)}')
    known = object_id in objects
    if kind == 'add' and known:
        fail('object', f'{object_id!r} is already in the scene')
    if kind != 'add' and not known:
        fail('object', f'unknown object {object_id!r} (known: {", ".join(objects)})')
    if kind != 'add' and objects[object_id].role == 'static':
        fail('object', f'{object_id!r} is a static object')
    fields: dict[str, Any] = {}
    if kind == 'grasp_failure':
        attempt = entry.get('attempt', 1)
        if isinstance(attempt, bool) or not isinstance(attempt, int) or attempt < 1:
            fail('attempt', f'a positive integer expected, got {brief(attempt)}')
        return SceneEvent(index, kind, object_id, attempt=attempt)
    fields.update(_trigger(entry, object_id, objects, fail))
    if kind in ('move', 'add'):
        if 'xy' not in entry:
            fail('xy', 'missing (the new centre [x, y] on the table [m])')
        fields['xy'] = tuple(_numbers(entry['xy'], 2, 'xy', fail))
        if 'yaw' in entry:
            fields['yaw'] = number(entry['yaw'], 'yaw', fail)
    if kind == 'add':
        fields['spec'] = _added_spec(object_id, entry, fields, fail)
    return SceneEvent(index, kind, object_id, **fields)


def _trigger(
    entry: dict, object_id: str, objects: dict[str, ObjectSpec], fail: Fail
) -> dict[str, Any]:
    has_time, has_hand = 'at_s' in entry, 'hand_within_m' in entry
    if has_time == has_hand:
        fail('at_s', 'exactly one of at_s [s] and hand_within_m [m] is needed')
    if has_time:
        if 'of' in entry:
            fail('of', 'only with hand_within_m')
        at_s = number(entry['at_s'], 'at_s', fail)
        if not 0.0 <= at_s <= MAX_AT_S:
            fail('at_s', f'must be in [0, {MAX_AT_S:g}] s, got {at_s}')
        return {'at_s': at_s}
    distance = number(entry['hand_within_m'], 'hand_within_m', fail)
    if not 0.0 < distance <= MAX_HAND_DISTANCE_M:
        fail('hand_within_m', f'must be in (0, {MAX_HAND_DISTANCE_M}] m, got {distance}')
    near = entry.get('of', object_id)
    if not isinstance(near, str) or (near not in objects and near != object_id):
        fail('of', f'unknown object {brief(near)}')
    return {'hand_within_m': distance, 'near': near}


def _added_spec(object_id: str, entry: dict, fields: dict[str, Any], fail: Fail) -> ObjectSpec:
    shape = entry.get('shape', 'cylinder')
    x, y = fields['xy']
    yaw = fields.get('yaw') or 0.0
    if shape == 'cylinder':
        radius = number(entry.get('radius'), 'radius', fail, positive=True)
        height = number(entry.get('height'), 'height', fail, positive=True)
        centre = (x, y, height / 2)
        return ObjectSpec(object_id, 'obstacle', 'cylinder', centre, yaw, radius, height)
    if shape == 'box':
        size = vec3(_numbers(entry.get('size'), 3, 'size', fail, positive=True))
        return ObjectSpec(object_id, 'obstacle', 'box', (x, y, size[2] / 2), yaw, size=size)
    fail('shape', f"must be 'cylinder' or 'box', got {brief(shape)}")


def placed(spec: ObjectSpec, xy: Sequence[float], yaw: float | None) -> ObjectSpec:
    """``spec`` standing on the table at ``xy`` [m], turned to ``yaw`` [rad] (None: as it is)."""
    half = spec.height / 2 if spec.shape == 'cylinder' else spec.size[2] / 2
    turned = spec.yaw if yaw is None else yaw
    return dataclasses.replace(spec, position=(float(xy[0]), float(xy[1]), half), yaw=turned)


def check_scene(scenario: Scenario, objects: Sequence[ObjectSpec], field: str) -> None:
    """Raise unless ``objects`` (the table and the objects in the clutter) form a valid scene.

    Raises:
        SceneEventError: overlap, off the table, on the drop zone (named after ``field``).
    """
    candidate = dataclasses.replace(scenario, objects=tuple(objects))
    try:
        validate_scenario(candidate, source=field, allow_no_target=True)  # T may be held
    except ScenarioError as err:  # 'field: objects[3].xy: problem' -> 'field: problem'
        problem = re.sub(r'^objects\[\d+\](\.[\w.]+)?: ', '', str(err).removeprefix(f'{field}: '))
        raise SceneEventError(f'{field}: {problem}') from None


def _check_placed(
    event: SceneEvent, objects: dict[str, ObjectSpec], scenario: Scenario
) -> dict[str, ObjectSpec]:
    """The objects after ``event`` (move or add), refused if the scene becomes invalid."""
    if event.kind == 'add':
        new = event.spec
    else:
        old, xy = objects.get(event.object_id), event.xy
        assert old is not None and xy is not None, 'checked by _parse_event'
        new = placed(old, xy, event.yaw)
    assert new is not None, 'an add event carries its spec'
    after = {**objects, event.object_id: new}
    check_scene(scenario, list(after.values()), f'{event.field}.xy')
    return after


class SceneEvents:
    """The armed events and what has fired; the simulation asks it every step and attach.

    Attributes:
        events: the validated events.
        fired: indices of the events that fired (or were skipped).
        attempts: attach requests so far, by object id [count].
    """

    def __init__(self, events: Sequence[SceneEvent] = ()) -> None:
        self.events = tuple(events)
        self.fired: set[int] = set()
        self.attempts: dict[str, int] = {}
        self.armed_at_s = 0.0

    def arm(self, now_s: float) -> None:
        """Start (again) at simulated time ``now_s`` [s]: nothing fired, no attempt counted."""
        self.fired.clear()
        self.attempts.clear()
        self.armed_at_s = now_s

    @property
    def watches_hand(self) -> bool:
        """Whether a pending event needs the hand position (to skip the FK otherwise)."""
        return any(e.hand_within_m is not None and e.index not in self.fired for e in self.events)

    def due(
        self, now_s: float, hand: np.ndarray | None, centre: Callable[[str], np.ndarray | None]
    ) -> list[SceneEvent]:
        """The scene events that fire now (marked fired).

        Args:
            now_s: simulated time [s].
            hand: EE origin in the world frame [m] (3,), or None when not computed.
            centre: current centre of an object by id [m] (3,), None when not in the scene.
        """
        out = []
        for event in self.events:
            if event.index in self.fired or event.kind == 'grasp_failure':
                continue
            if event.at_s is not None:
                fire = now_s - self.armed_at_s >= event.at_s - 1e-9
            else:
                c, within = centre(event.near), event.hand_within_m
                if hand is None or c is None or within is None:
                    fire = False
                else:
                    fire = float(np.linalg.norm(hand - c)) <= within
            if fire:
                self.fired.add(event.index)
                out.append(event)
        return out

    def refuse_grasp(self, object_id: str) -> SceneEvent | None:
        """Count one attach request for ``object_id``; the grasp_failure event refusing it."""
        attempt = self.attempts.get(object_id, 0) + 1
        self.attempts[object_id] = attempt
        for event in self.events:
            key = (event.kind, event.object_id, event.attempt)
            if key == ('grasp_failure', object_id, attempt):
                self.fired.add(event.index)
                return event
        return None


def _numbers(value: Any, n: int, key: str, fail: Fail, positive: bool = False) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        fail(key, f'{n} numbers expected, got {brief(value)}')
    return [number(v, key, fail, positive) for v in value]
