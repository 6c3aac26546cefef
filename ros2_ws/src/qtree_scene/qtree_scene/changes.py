"""What changed between two scenes: objects moved, added, removed or reshaped (no ROS import).

Shared by the motion planner (a scene change under a running execution stops the arm with
``SCENE_CHANGED``, #32) and the task planner (a change between two relocations makes it re-plan
the rest of the retrieval). Both compare the objects standing in the clutter, by id, leaving out
the ones they expect to move (the carried object, the objects relocated so far).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping
from typing import Any

from qtree_node_support.text import quote

from qtree_scene.message import scenario_from_msg
from qtree_scene.scene import ObjectSpec

POSITION_TOLERANCE_M = 1e-3  # a smaller displacement is not a change [m]
YAW_TOLERANCE_RAD = 1e-2  # a smaller rotation about z is not a change (boxes only) [rad]
STATUS_IN_CLUTTER = 0  # ObjectState.STATUS_IN_CLUTTER
STATUS_RELOCATED = 2  # ObjectState.STATUS_RELOCATED


def _objects_where(msg: Any, keep: Callable[[ObjectSpec, int], bool]) -> dict[str, ObjectSpec]:
    """The objects of a decoded ``qtree_msgs/Scene``, by id, as they are now, for which
    ``keep(spec, status)`` holds (``status``: the object's ``ObjectState`` status).

    Raises:
        ScenarioError: a malformed message (see :func:`~qtree_scene.message.scenario_from_msg`).
    """
    specs = scenario_from_msg(msg).objects
    return {
        spec.id: spec
        for spec, obj in zip(specs, msg.objects, strict=True)
        if keep(spec, obj.status)
    }


def clutter_objects(msg: Any, ignore: Collection[str] = ()) -> dict[str, ObjectSpec]:
    """The objects of a decoded ``qtree_msgs/Scene`` that stand IN_CLUTTER, by id, as they are
    now (current pose), without the ids in ``ignore``.

    Raises:
        ScenarioError: a malformed message (see :func:`~qtree_scene.message.scenario_from_msg`).
    """
    return _objects_where(
        msg, lambda spec, status: status == STATUS_IN_CLUTTER and spec.id not in ignore
    )


def standing_objects(
    msg: Any, moving: str, left_out: Collection[str] = ()
) -> dict[str, ObjectSpec]:
    """The objects of a decoded ``qtree_msgs/Scene`` an arm relocating ``moving`` must clear,
    by id, as they stand now: those IN_CLUTTER but the ids in ``left_out`` (e.g. the request's
    relocated ones), and those already RELOCATED onto their drop slots (#29 point 5: the closed
    loop left them out); never ``moving`` itself (carried, it is part of the arm).

    Raises:
        ScenarioError: a malformed message (see :func:`~qtree_scene.message.scenario_from_msg`).
    """

    def keep(spec: ObjectSpec, status: int) -> bool:
        if spec.id == moving:
            return False
        return (
            status == STATUS_IN_CLUTTER and spec.id not in left_out
        ) or status == STATUS_RELOCATED

    return _objects_where(msg, keep)


def scene_changes(
    before: Mapping[str, ObjectSpec],
    after: Mapping[str, ObjectSpec],
    position_tolerance_m: float = POSITION_TOLERANCE_M,
    yaw_tolerance_rad: float = YAW_TOLERANCE_RAD,
) -> list[str]:
    """One line per changed object, in the order of ``before`` then the added ones.

    Args:
        before: objects by id (e.g. :func:`clutter_objects` at the start of an execution).
        after: the same ids now.
        position_tolerance_m: a centre moved by less is unchanged [m].
        yaw_tolerance_rad: a box turned by less about z is unchanged [rad] (a cylinder's yaw
            does not change its geometry).

    Returns:
        e.g. ``["'O5' moved 0.153 m", "'X1' added", "'O4' removed"]``; empty when unchanged.
    """
    changes = []
    for object_id, old in before.items():
        new = after.get(object_id)
        if new is None:
            changes.append(f'{quote(object_id)} removed')
        elif _shape(old) != _shape(new) or old.role != new.role:
            changes.append(f'{quote(object_id)} changed shape or role')
        else:
            moved = math.dist(old.position, new.position)
            turn = abs(math.remainder(new.yaw - old.yaw, 2 * math.pi))
            if moved > position_tolerance_m:
                changes.append(f'{quote(object_id)} moved {moved:.3f} m')
            elif old.shape == 'box' and turn > yaw_tolerance_rad:
                changes.append(f'{quote(object_id)} turned {turn:.3f} rad')
    changes += [f'{quote(object_id)} added' for object_id in after if object_id not in before]
    return changes


def changes_under_relocation(
    before: Mapping[str, ObjectSpec],
    after: Mapping[str, ObjectSpec],
    object_id: str,
    in_scene: bool = True,
) -> list[str]:
    """:func:`scene_changes` while ``object_id`` is being relocated: the object itself is
    watched too while it stands in the clutter (the hand is on its way to a grasp planned for
    where it was), and left out once it has left the clutter grasped (carried: the grasp then
    says so). An object gone from the scene altogether was removed, grasped or not.

    Args:
        before: the clutter at the start of the relocation (:func:`clutter_objects`, nothing
            ignored).
        after: the clutter now.
        object_id: the object being relocated.
        in_scene: whether ``object_id`` is still in the scene message under any status
            (grasped, relocated); False when perception or a scene event removed it.
    """
    if object_id not in after and in_scene:
        before = {i: o for i, o in before.items() if i != object_id}
    return scene_changes(before, after)


def changed_ids(changes: list[str]) -> list[str]:
    """The object ids named by :func:`scene_changes` lines, in order."""
    return [line.split("'")[1] for line in changes if line.startswith("'")]


def _shape(obj: ObjectSpec) -> tuple:
    size = tuple(round(v, 6) for v in obj.size)
    return obj.shape, round(obj.radius, 6), round(obj.height, 6), size
