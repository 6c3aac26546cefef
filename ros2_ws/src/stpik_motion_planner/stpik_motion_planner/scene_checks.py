"""Validation of scenarios and relocation requests (no ROS import)."""

from __future__ import annotations

import math
from collections.abc import Sequence

from jaco2_sim.scene import Scenario

from stpik_motion_planner.exceptions import InvalidRequest
from stpik_motion_planner.result import Reason


def validate_scenario(scenario: Scenario) -> None:
    """Check that a scenario can be planned in.

    Raises:
        InvalidRequest: (``INVALID_SCENE``) no or several targets, duplicate ids, non-finite
            poses, non-positive sizes, a home configuration that is not 7 finite angles.
    """

    def bad(message: str) -> InvalidRequest:
        return InvalidRequest(Reason.INVALID_SCENE, f'invalid scene: {message}')

    ids = [o.id for o in scenario.objects]
    if len(set(ids)) != len(ids):
        raise bad('duplicate object ids')
    if sum(o.role == 'target' for o in scenario.objects) != 1:
        raise bad('exactly one object must be the target')
    for o in scenario.objects:
        numbers = [*o.position, o.yaw, o.radius, o.height, *o.size]
        if not all(math.isfinite(v) for v in numbers):
            raise bad(f'object {o.id!r} has a non-finite pose or size')
        if o.shape == 'cylinder' and not (o.radius > 0 and o.height > 0):
            raise bad(f'cylinder {o.id!r} needs radius > 0 and height > 0')
        if o.shape == 'box' and not all(v > 0 for v in o.size):
            raise bad(f'box {o.id!r} needs positive sizes')
        if o.shape not in ('cylinder', 'box'):
            raise bad(f'object {o.id!r} has unknown shape {o.shape!r}')
    numbers = [*scenario.drop_zone_center, *scenario.drop_zone_size]
    if not all(math.isfinite(v) for v in numbers) or min(scenario.drop_zone_size) <= 0:
        raise bad('drop zone must be finite with positive size')
    if len(scenario.home) != 7 or not all(math.isfinite(v) for v in scenario.home):
        raise bad('home must be 7 finite joint angles')


def validate_request(scenario: Scenario, object_id: object, relocated: Sequence[object]) -> None:
    """Check one relocation request against the scenario.

    Raises:
        InvalidRequest: ``INVALID_REQUEST`` (empty, non-string or duplicate ids, a static object,
            the target among the relocated), ``UNKNOWN_OBJECT``, ``ALREADY_RELOCATED``.
    """
    if not isinstance(object_id, str) or not object_id.strip():
        raise InvalidRequest(Reason.INVALID_REQUEST, 'object_id must be a non-empty string')
    if any(not isinstance(r, str) or not r.strip() for r in relocated):
        raise InvalidRequest(Reason.INVALID_REQUEST, 'relocated_ids must be non-empty strings')
    if len(set(relocated)) != len(relocated):
        raise InvalidRequest(
            Reason.INVALID_REQUEST, f'duplicate ids in relocated_ids: {sorted(relocated)}'
        )
    known = {o.id: o for o in scenario.objects}
    for name in [object_id, *relocated]:
        if name not in known:
            raise InvalidRequest(
                Reason.UNKNOWN_OBJECT, f'unknown object {name!r} in scene {scenario.name!r}'
            )
        if known[name].role == 'static':
            raise InvalidRequest(Reason.INVALID_REQUEST, f'{name!r} is static, it cannot move')
    if object_id in relocated:
        raise InvalidRequest(Reason.ALREADY_RELOCATED, f'{object_id!r} is already relocated')
    target = scenario.target.id
    if target in relocated:
        raise InvalidRequest(
            Reason.INVALID_REQUEST,
            f'the target {target!r} cannot be among relocated_ids (relocating it ends the task)',
        )
