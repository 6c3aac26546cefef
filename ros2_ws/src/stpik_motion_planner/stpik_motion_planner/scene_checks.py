"""Validation of scenarios and relocation requests (no ROS import)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from qtree_node_support.text import quote
from qtree_scene.exceptions import ScenarioError
from qtree_scene.scenario import validate_scenario as check_scene
from qtree_scene.scene import Scenario

from stpik_motion_planner.exceptions import InvalidRequest
from stpik_motion_planner.result import Reason

MAX_RELOCATED_IDS = 256  # longest accepted relocated_ids list of a request [ids]
MAX_ID_CHARS = 256  # longest accepted object id [characters]
SHOWN_IDS = 5  # ids quoted in a message or log line before "… (N ids)"
SHOWN_ID_CHARS = 40  # characters of one id quoted in a message or log line


def format_id(name: object) -> str:
    """``repr(name)``, cut to :data:`SHOWN_ID_CHARS` characters with its length when longer."""
    return quote(name, SHOWN_ID_CHARS)


def format_ids(names: Sequence[object]) -> str:
    """The first :data:`SHOWN_IDS` ids of ``names`` (cut by :func:`format_id`), then the count.

    Short enough for a message or a log line whatever the request: at most about 500 characters.
    """
    shown = ', '.join(format_id(n) for n in names[:SHOWN_IDS])
    if len(names) > SHOWN_IDS:
        return f'[{shown}, … ({len(names)} ids)]'
    return f'[{shown}]'


def validate_scenario(scenario: Scenario) -> None:
    """Check that a scenario can be planned in: :func:`qtree_scene.scenario.validate_scenario`,
    the one validator of every scene (files, messages, code), answered as a planner error.

    Raises:
        InvalidRequest: (``INVALID_SCENE``) the scene validator's message (no or several
            targets, duplicate ids, non-finite poses, non-positive sizes, a home configuration
            outside the joint limits, ...).
    """
    try:
        check_scene(scenario, check_layout=False)  # a file's or message's scene passed all
    except ScenarioError as err:
        raise InvalidRequest(Reason.INVALID_SCENE, f'invalid scene: {err}') from None


def validate_request(scenario: Scenario, object_id: object, relocated: Sequence[object]) -> None:
    """Check one relocation request against the scenario, in O(len(relocated)).

    Messages quote at most :data:`SHOWN_IDS` ids, each cut to :data:`SHOWN_ID_CHARS` characters,
    so a huge request never gives a huge answer. An id that is not in the scene is
    ``UNKNOWN_OBJECT`` however long it is; a list of known ids longer than
    :data:`MAX_RELOCATED_IDS` (only possible with duplicates or a huge scene) is
    ``INVALID_REQUEST``.

    Raises:
        InvalidRequest: ``INVALID_REQUEST`` (empty, non-string or duplicate ids, more than
            :data:`MAX_RELOCATED_IDS` relocated ids, an id longer than :data:`MAX_ID_CHARS`, a
            static object, the target among the relocated), ``UNKNOWN_OBJECT``,
            ``ALREADY_RELOCATED``.
    """
    check_ids_given(object_id, relocated)
    known = {o.id: o for o in scenario.objects}
    for name in [object_id, *relocated]:
        if name not in known:
            raise InvalidRequest(
                Reason.UNKNOWN_OBJECT,
                f'unknown object {format_id(name)} in scene {format_id(scenario.name)}',
            )
        if known[name].role == 'static':
            raise InvalidRequest(
                Reason.INVALID_REQUEST, f'{format_id(name)} is static, it cannot move'
            )
    check_request_size(object_id, relocated)
    if len(set(relocated)) != len(relocated):
        counts = Counter(relocated)
        repeated = [name for name, count in counts.items() if count > 1]
        raise InvalidRequest(
            Reason.INVALID_REQUEST,
            f'duplicate ids in relocated_ids: {format_ids(repeated)} '
            f'({len(relocated)} ids, {len(counts)} distinct)',
        )
    if object_id in relocated:
        raise InvalidRequest(
            Reason.ALREADY_RELOCATED, f'{format_id(object_id)} is already relocated'
        )
    target = scenario.target.id
    if target in relocated:
        raise InvalidRequest(
            Reason.INVALID_REQUEST,
            f'the target {target!r} cannot be among relocated_ids (relocating it ends the task)',
        )


def check_ids_given(object_id: object, relocated: Sequence[object]) -> None:
    """The checks of a request that need no scene: every id a non-empty string.

    Raises:
        InvalidRequest: (``INVALID_REQUEST``) an empty or non-string id.
    """
    if not isinstance(object_id, str) or not object_id.strip():
        raise InvalidRequest(Reason.INVALID_REQUEST, 'object_id must be a non-empty string')
    if any(not isinstance(r, str) or not r.strip() for r in relocated):
        raise InvalidRequest(Reason.INVALID_REQUEST, 'relocated_ids must be non-empty strings')


def check_request_size(object_id: object, relocated: Sequence[object]) -> None:
    """Check the documented size limits of a request (O(1) per id, no scene needed).

    Raises:
        InvalidRequest: (``INVALID_REQUEST``) more than :data:`MAX_RELOCATED_IDS` relocated ids,
            or an id longer than :data:`MAX_ID_CHARS` characters.
    """
    if len(relocated) > MAX_RELOCATED_IDS:
        raise InvalidRequest(
            Reason.INVALID_REQUEST,
            f'relocated_ids has {len(relocated)} ids: at most {MAX_RELOCATED_IDS} are accepted',
        )
    for name in [object_id, *relocated]:
        if isinstance(name, str) and len(name) > MAX_ID_CHARS:
            raise InvalidRequest(
                Reason.INVALID_REQUEST,
                f'id {format_id(name)} is too long: at most {MAX_ID_CHARS} characters',
            )
