"""Scenario files: YAML → validated :class:`~qtree_scene.scene.Scenario`, and a seeded generator.

World frame = robot base frame (``j2s7s300_link_base`` at the origin, z up). The table is a static
box whose top face is at z = 0; every object stands on it (centre z = height / 2).

YAML schema (lengths [m], angles [rad]; unknown keys are errors)::

    name: s1                        # required, non-empty string
    description: free text          # optional
    home: [4.71, 2.84, 0.0, 0.75, 4.62, 4.48, 4.88]   # optional, 7 arm angles within limits
    robot_keepout_radius: 0.2       # optional (default 0.2): no footprint within this radius of
                                    #   the base axis (x = y = 0)
    table:                          # required, becomes the static box object 'table'
      center_xy: [0.35, 0.0]        # centre of the table top
      size: [1.2, 1.4, 0.05]        # full edges x, y, z (> 0); top face at z = 0
    drop_zone:                      # required: where relocated objects are placed
      center_xy: [0.0, 0.5]         # on the table: centre z = size[2] / 2
      size: [0.3, 0.3, 0.3]
    objects:                        # required, non-empty list, ids unique (and not 'table')
      - id: T                       # required, non-empty string
        role: target                # target | obstacle | static; exactly one target
        shape: cylinder             # cylinder | box
        xy: [0.7, 0.0]              # footprint centre, inside the table top
        radius: 0.03                # cylinder only, > 0
        height: 0.15                # cylinder only, > 0
        size: [0.1, 0.1, 0.1]       # box only, each > 0
        yaw: 0.0                    # optional, default 0

Validation also rejects NaN/inf anywhere, objects whose footprints overlap each other or the
drop zone, and objects or a drop zone inside the robot keep-out disc. Every error is a
:class:`ScenarioError` naming the file, the field (``objects[2].radius``) and the problem, whatever
the type of the bad value (``shape: [cylinder]`` → "expected a string, got list"; a 400-digit
integer → "too large for a float"; ``true`` is not a number). Keys that are not plain names are
quoted in the field (``objects[0]['']``).
"""

from __future__ import annotations

import math
import pathlib
from typing import Any

import yaml
from jaco2_description.model import HOME, arm_limits

from qtree_scene.exceptions import ScenarioError
from qtree_scene.fields import Fail, brief, failer, number
from qtree_scene.footprint import Footprint, footprint_of, overlap
from qtree_scene.scene import ROLES, ObjectSpec, Scenario, role, vec3

TABLE_ID = 'table'
DEFAULT_KEEPOUT = 0.2  # [m]
MAX_OBJECTS = 500  # most objects of one scene, table included (validation is O(n²)) [-]
SCENARIO_DIR = pathlib.Path(__file__).resolve().parent / 'scenarios'
_TOP = {'name', 'description', 'home', 'robot_keepout_radius', 'table', 'drop_zone', 'objects'}
_BOX = {'center_xy', 'size'}
_OBJECT = {'id', 'role', 'shape', 'xy', 'radius', 'height', 'size', 'yaw'}
_SHAPE_KEYS = {'cylinder': {'radius', 'height'}, 'box': {'size'}}
MAX_SCENARIO_BYTES = 1_000_000  # largest scenario file (s3: 3 kB; 200 objects: ~40 kB) [bytes]
MAX_NAME_CHARS = 256  # longest scenario name or object id (= the motion planner's id limit)


def list_scenarios() -> list[str]:
    """Names of the installed scenarios (file stems), sorted, e.g. ``['s1', 's2', 's3']``."""
    return sorted(p.stem for p in SCENARIO_DIR.glob('*.yaml'))


def resolve_scenario(name_or_path: str) -> pathlib.Path:
    """File of an installed scenario name, or ``name_or_path`` itself if it is a file.

    Raises:
        ScenarioError: not a string, or neither an installed name nor an existing file.
    """
    if not isinstance(name_or_path, str):
        raise ScenarioError(brief(name_or_path), '', 'expected a scenario name or path string')
    if name_or_path in list_scenarios():
        return SCENARIO_DIR / f'{name_or_path}.yaml'
    try:
        path = pathlib.Path(name_or_path).expanduser()
        is_file = path.is_file()
    except (OSError, ValueError, RuntimeError):  # unknown ~user, NUL byte, name too long
        is_file = False
    if is_file:
        return path
    known = ', '.join(list_scenarios())
    raise ScenarioError(name_or_path, '', f'no such scenario or file (installed: {known})')


def load_scenario(name_or_path: str) -> Scenario:
    """Load and validate a scenario by installed name (``'s1'``) or YAML path.

    Raises:
        ScenarioError: unreadable file, bad YAML, or a schema / geometry violation.
    """
    path = resolve_scenario(name_or_path)
    try:
        size = path.stat().st_size
    except OSError as err:
        raise ScenarioError(str(path), '', f'cannot read YAML: {err}') from None
    if size > MAX_SCENARIO_BYTES:  # parsing 1.4 MB took ~1 s: the sim must keep publishing
        limit = f'{MAX_SCENARIO_BYTES / 1e6:g} MB'
        raise ScenarioError(str(path), '', f'file of {size / 1e6:.1f} MB, over the {limit} limit')
    try:
        data = yaml.safe_load(path.read_text(encoding='utf-8'))
    except (OSError, ValueError, yaml.YAMLError) as err:  # ValueError: not UTF-8, bad date
        raise ScenarioError(str(path), '', f'cannot read YAML: {err}') from None
    except RecursionError:
        raise ScenarioError(str(path), '', 'cannot read YAML: nested too deeply') from None
    return parse_scenario(data, source=str(path))


def parse_scenario(data: Any, source: str = '') -> Scenario:
    """Build and validate a scenario from the YAML mapping ``data`` (see module docstring).

    Raises:
        ScenarioError: schema or geometry violation.
    """
    fail = failer(source)
    if not isinstance(data, dict):
        fail('', f'top level must be a mapping, got {type(data).__name__}')
    _check_keys(data, _TOP, {'name', 'table', 'drop_zone', 'objects'}, '', fail)
    name = _string(data['name'], 'name', fail)
    table_xy = _vector(
        _get(data['table'], 'center_xy', 'table', _BOX, fail), 2, 'table.center_xy', fail
    )
    table_size = _vector(data['table']['size'], 3, 'table.size', fail, positive=True)
    zone_xy = _vector(
        _get(data['drop_zone'], 'center_xy', 'drop_zone', _BOX, fail),
        2,
        'drop_zone.center_xy',
        fail,
    )
    zone_size = _vector(data['drop_zone']['size'], 3, 'drop_zone.size', fail, positive=True)
    home = _vector(data.get('home', HOME.tolist()), 7, 'home', fail)
    keepout = number(
        data.get('robot_keepout_radius', DEFAULT_KEEPOUT), 'robot_keepout_radius', fail
    )
    if not isinstance(data['objects'], list) or not data['objects']:
        fail('objects', 'must be a non-empty list')
    check_object_count(len(data['objects']) + 1, fail)  # + the table
    objects = [_parse_object(o, f'objects[{i}]', fail) for i, o in enumerate(data['objects'])]
    description = data.get('description')
    description = '' if description is None else description  # `description:` left empty
    table = ObjectSpec(
        id=TABLE_ID,
        role='static',
        shape='box',
        position=(table_xy[0], table_xy[1], -table_size[2] / 2),
        size=vec3(table_size),
    )
    scenario = Scenario(
        name=name,
        objects=(*objects, table),
        drop_zone_center=(zone_xy[0], zone_xy[1], zone_size[2] / 2),
        drop_zone_size=vec3(zone_size),
        home=tuple(home),
        description=_text(description, 'description', fail),
        source=source,
        robot_keepout_radius=keepout,
    )
    validate_scenario(scenario)
    return scenario


def check_object_count(count: int, fail: Fail) -> None:
    """Fail (field ``objects``) when a scene has more than :data:`MAX_OBJECTS` objects."""
    if count > MAX_OBJECTS:
        fail('objects', f'{count} objects, at most {MAX_OBJECTS} are accepted (table included)')


def validate_scenario(
    scenario: Scenario,
    source: str | None = None,
    position_field: str = 'xy',
    allow_no_target: bool = False,
    check_layout: bool = True,
) -> None:
    """Check the geometry and roles of a scenario built in code, from a file or from a message.

    Args:
        scenario: the scenario; ``scenario.objects[i]`` is reported as ``objects[i]``.
        source: prefix of the error messages (default: the scenario's file, else its name).
        position_field: name of an object's position field in the input the scenario came from
            (``xy`` in YAML files, ``pose.position`` in a Scene message).
        allow_no_target: accept a scene without a target (the clutter while the target is
            held or after it was relocated: scene events, #32); two targets stay refused.
        check_layout: also check the layout (object count, every object and the drop zone on
            the table, outside the robot's keep-out, no overlaps). False: only what planning
            needs (ids, roles, finite poses, sizes, drop zone, home), for the motion planner,
            which also plans in scenes built in code to test it (touching rings, no free
            table, more than :data:`MAX_OBJECTS` objects); every scene from a file or a
            message has passed the full check before it reaches the planner.

    Raises:
        ScenarioError: see the module docstring for the rules.
    """
    fail = failer(scenario.source or scenario.name if source is None else source)
    if check_layout:
        check_object_count(len(scenario.objects), fail)
    movable = [(i, o) for i, o in enumerate(scenario.objects) if o.id != TABLE_ID]
    seen: dict[str, int] = {}
    for i, obj in enumerate(scenario.objects):
        if obj.id in seen:
            fail(f'objects[{i}].id', f'duplicate id {obj.id!r} (also objects[{seen[obj.id]}])')
        seen[obj.id] = i
    for i, obj in enumerate(scenario.objects):  # scenarios built in code skip the parsers
        _check_numbers(obj, f'objects[{i}]', fail)
    targets = [f'objects[{i}]' for i, o in movable if o.role == 'target']
    if len(targets) != 1 and not (allow_no_target and not targets):
        fail('objects', f'exactly one object must have role target, found {len(targets)}')
    if TABLE_ID not in seen:
        fail('table', 'missing')
    if not all(math.isfinite(v) for v in scenario.drop_zone_center):
        fail('drop_zone.center_xy', f'must be finite, got {scenario.drop_zone_center}')
    if not all(math.isfinite(v) and v > 0 for v in scenario.drop_zone_size):
        fail('drop_zone.size', f'must be positive and finite, got {scenario.drop_zone_size}')
    if not (math.isfinite(scenario.robot_keepout_radius) and scenario.robot_keepout_radius >= 0):
        fail('robot_keepout_radius', f'must be ≥ 0, got {scenario.robot_keepout_radius}')
    limits = arm_limits()
    if len(scenario.home) != len(limits.lower):
        fail('home', f'must be {len(limits.lower)} joint angles, got {len(scenario.home)}')
    for k, (value, lo, hi) in enumerate(
        zip(scenario.home, limits.lower, limits.upper, strict=True)
    ):
        if not (math.isfinite(value) and lo <= value <= hi):
            fail(f'home[{k}]', f'{value} rad outside the joint limits [{lo:.4f}, {hi:.4f}]')
    if check_layout:
        _check_layout(scenario, movable, position_field, fail)


def _check_layout(
    scenario: Scenario, movable: list[tuple[int, ObjectSpec]], position_field: str, fail: Fail
) -> None:
    """The drop zone and every object on the table, outside the keep-out, not overlapping."""
    table_fp = footprint_of(scenario.object(TABLE_ID))
    zone = Footprint(
        center=scenario.drop_zone_center[:2],
        half_size=(scenario.drop_zone_size[0] / 2, scenario.drop_zone_size[1] / 2),
    )
    _check_on_table_and_clear(
        zone, 'drop_zone', 'the drop zone', table_fp, scenario.robot_keepout_radius, fail
    )
    footprints: list[tuple[int, Footprint]] = []
    for i, obj in movable:
        fp = footprint_of(obj)
        _check_on_table_and_clear(
            fp, f'objects[{i}]', repr(obj.id), table_fp, scenario.robot_keepout_radius, fail
        )
        if overlap(fp, zone):
            fail(f'objects[{i}].{position_field}', f'{obj.id!r} overlaps the drop zone')
        for j, other in footprints:
            if overlap(fp, other):
                problem = f'{obj.id!r} overlaps {scenario.objects[j].id!r}'
                fail(f'objects[{i}].{position_field}', problem)
        footprints.append((i, fp))


def _check_numbers(obj: ObjectSpec, field: str, fail: Fail) -> None:
    """Finite pose, known shape, positive sizes [m] of one object."""
    if not all(math.isfinite(v) for v in (*obj.position, obj.yaw)):
        fail(f'{field}.pose', f'{obj.id!r} has a non-finite pose {(*obj.position, obj.yaw)}')
    if obj.shape == 'cylinder':
        if not (math.isfinite(obj.radius) and obj.radius > 0):
            fail(f'{field}.radius', f'{obj.id!r}: must be positive and finite, got {obj.radius}')
        if not (math.isfinite(obj.height) and obj.height > 0):
            fail(f'{field}.height', f'{obj.id!r}: must be positive and finite, got {obj.height}')
    elif obj.shape == 'box':
        if len(obj.size) != 3 or not all(math.isfinite(v) and v > 0 for v in obj.size):
            fail(f'{field}.size', f'{obj.id!r}: 3 positive finite sizes, got {obj.size}')
    else:
        fail(f'{field}.shape', f'{obj.id!r} has unknown shape {obj.shape!r}')


def _check_on_table_and_clear(
    fp: Footprint,
    field: str,
    name: str,
    table: Footprint,
    keepout: float,
    fail: Fail,
) -> None:
    if table.distance_to_point(fp.center) > 0.0:
        fail(field, f'{name}: centre {fp.center} is not on the table')
    clearance = fp.distance_to_point((0.0, 0.0))
    if clearance < keepout:
        problem = (
            f'{name}: {clearance:.3f} m from the robot base axis, keep-out radius {keepout} m'
        )
        fail(field, problem)


def _parse_object(data: Any, field: str, fail: Fail) -> ObjectSpec:
    if not isinstance(data, dict):
        fail(field, f'must be a mapping, got {type(data).__name__}')
    _check_keys(data, _OBJECT, {'id', 'role', 'shape', 'xy'}, f'{field}.', fail)
    object_id = _string(data['id'], f'{field}.id', fail)
    if object_id == TABLE_ID:
        fail(f'{field}.id', f'{TABLE_ID!r} is reserved for the table')
    object_role = role(_choice(data['role'], ROLES, f'{field}.role', fail))
    shape = _choice(data['shape'], tuple(_SHAPE_KEYS), f'{field}.shape', fail)
    wrong = sorted((_SHAPE_KEYS['box'] | _SHAPE_KEYS['cylinder']) - _SHAPE_KEYS[shape] & set(data))
    if wrong:
        fail(f'{field}.{wrong[0]}', f'not allowed for a {shape}')
    for key in sorted(_SHAPE_KEYS[shape] - set(data)):
        fail(f'{field}.{key}', f'missing (required for a {shape})')
    xy = _vector(data['xy'], 2, f'{field}.xy', fail)
    yaw = number(data.get('yaw', 0.0), f'{field}.yaw', fail)
    if shape == 'cylinder':
        radius = number(data['radius'], f'{field}.radius', fail, positive=True)
        height = number(data['height'], f'{field}.height', fail, positive=True)
        position = (xy[0], xy[1], height / 2)
        return ObjectSpec(
            object_id, object_role, 'cylinder', position, yaw, radius=radius, height=height
        )
    size = _vector(data['size'], 3, f'{field}.size', fail, positive=True)
    position = (xy[0], xy[1], size[2] / 2)
    return ObjectSpec(object_id, object_role, 'box', position, yaw, size=vec3(size))


def _check_keys(data: dict, allowed: set, required: set, prefix: str, fail: Fail) -> None:
    for key in data:
        if key not in allowed:
            problem = f'unknown key {brief(key)} (allowed: {", ".join(sorted(allowed))})'
            fail(_key_field(prefix, key), problem)
    for key in sorted(required - set(data)):
        fail(f'{prefix}{key}', 'missing')


def _get(section: Any, key: str, name: str, allowed: set, fail: Fail) -> Any:
    if not isinstance(section, dict):
        fail(name, f'must be a mapping, got {type(section).__name__}')
    _check_keys(section, allowed, allowed, f'{name}.', fail)
    return section[key]


def _key_field(prefix: str, key: Any) -> str:
    """Field of ``key`` under ``prefix``: ``objects[0].mass``, or quoted: ``objects[0]['']``."""
    if isinstance(key, str) and key.isidentifier():
        return f'{prefix}{key}'
    return f'{prefix.removesuffix(".")}[{brief(key)}]'


def _vector(value: Any, n: int, field: str, fail: Fail, positive: bool = False) -> list[float]:
    if not isinstance(value, (list, tuple)):
        fail(field, f'must be a list of {n} numbers, got {type(value).__name__} {brief(value)}')
    if len(value) != n:
        fail(field, f'must be a list of {n} numbers, got {len(value)} items')
    return [number(v, f'{field}[{k}]', fail, positive) for k, v in enumerate(value)]


def _text(value: Any, field: str, fail: Fail) -> str:
    if not isinstance(value, str):
        fail(field, f'expected a string, got {type(value).__name__} {brief(value)}')
    return value


def _string(value: Any, field: str, fail: Fail) -> str:
    if not _text(value, field, fail).strip():
        fail(field, f'must be a non-empty string, got {brief(value)}')
    if len(value) > MAX_NAME_CHARS:  # names and ids are echoed in messages and /scene
        fail(field, f'at most {MAX_NAME_CHARS} characters, got {len(value)}: {brief(value)}')
    return value


def _choice(value: Any, choices: tuple[str, ...], field: str, fail: Fail) -> str:
    if _text(value, field, fail) not in choices:
        fail(field, f'must be one of {", ".join(choices)}, got {brief(value)}')
    return value


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The YAML mapping of ``scenario`` (inverse of :func:`parse_scenario`)."""
    table = scenario.object(TABLE_ID)
    objects = []
    for obj in scenario.objects:
        if obj.id == TABLE_ID:
            continue
        entry: dict[str, Any] = {'id': obj.id, 'role': obj.role, 'shape': obj.shape}
        entry['xy'] = [float(obj.position[0]), float(obj.position[1])]
        if obj.shape == 'cylinder':
            entry |= {'radius': float(obj.radius), 'height': float(obj.height)}
        else:
            entry['size'] = [float(v) for v in obj.size]
        if obj.yaw:
            entry['yaw'] = float(obj.yaw)
        objects.append(entry)
    return {
        'name': scenario.name,
        'description': scenario.description,
        'home': [float(v) for v in scenario.home],
        'robot_keepout_radius': float(scenario.robot_keepout_radius),
        'table': {
            'center_xy': [float(table.position[0]), float(table.position[1])],
            'size': [float(v) for v in table.size],
        },
        'drop_zone': {
            'center_xy': [float(v) for v in scenario.drop_zone_center[:2]],
            'size': [float(v) for v in scenario.drop_zone_size],
        },
        'objects': objects,
    }


def dump_scenario(scenario: Scenario) -> str:
    """YAML text of ``scenario``; :func:`parse_scenario` of it gives back an equal scenario."""
    return yaml.safe_dump(scenario_to_dict(scenario), sort_keys=False, default_flow_style=None)
