"""World state of the simulator: object poses and statuses, grasp attach/detach (no ROS).

An attached object keeps the pose it had relative to the end-effector at the moment of the
attach: transform_object_to_ee = ee_pose⁻¹ · object_pose, and after each EE motion
object_pose = ee_pose · transform_object_to_ee. A detached object stays where it is, except
that an object released as ``'relocated'`` near its drop slot (the k-th relocation, slot k of
:func:`qtree_scene.placement.drop_slots`) is stood upright on that slot: the planner plans later
motions against exactly those poses; an object released ``'in_clutter'`` (an execution undone,
#32) is stood upright on the table where it is. Scene events (#32) move, add or remove objects
in the clutter (:meth:`World.place`, :meth:`World.remove`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from qtree_node_support.text import quote
from qtree_scene.placement import settle_pose
from qtree_scene.scene import ObjectSpec, Scenario, Status, vec3

from jaco2_sim.exceptions import WorldError

RELEASE_STATUSES: tuple[Status, ...] = ('in_clutter', 'relocated')


def spec_pose(obj: ObjectSpec) -> pin.SE3:
    """Initial pose of a scenario object (transform_object_to_world): yaw about z, centre."""
    c, s = math.cos(obj.yaw), math.sin(obj.yaw)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return pin.SE3(rotation, np.array(obj.position, dtype=float))


@dataclass
class ObjectState:
    """Mutable state of one object.

    Attributes:
        spec: the scenario entry (shape, role, initial pose).
        pose: current transform_object_to_world.
        status: ``'in_clutter'``, ``'grasped'`` or ``'relocated'``.
    """

    spec: ObjectSpec
    pose: pin.SE3
    status: Status = 'in_clutter'


class World:
    """Objects of one scenario and the one object (at most) held by the hand.

    Attributes:
        scenario: the scenario this world was built from.
        objects: state of every object by id, in scenario order.
        attached_id: id of the held object, or None.
        version: incremented on every change (attach, detach, move, reset).
    """

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.objects: dict[str, ObjectState] = {}
        self.attached_id: str | None = None
        self.version = 0
        self._object_to_ee = pin.SE3.Identity()
        self.reset()

    def reset(self) -> None:
        """Every object back to its initial pose, status ``'in_clutter'``, nothing attached."""
        self.objects = {o.id: ObjectState(o, spec_pose(o)) for o in self.scenario.objects}
        self.attached_id = None
        self.version += 1

    def state(self, object_id: str) -> ObjectState:
        """State of ``object_id``.

        Raises:
            WorldError: unknown id.
        """
        try:
            return self.objects[object_id]
        except KeyError:
            known = ', '.join(self.objects)
            raise WorldError(f'unknown object {quote(object_id)} (known: {known})') from None

    def attach(self, object_id: str, ee_pose: pin.SE3) -> float:
        """Grasp ``object_id``: it keeps its current offset to the end-effector.

        Args:
            object_id: a target or obstacle id.
            ee_pose: current transform_ee_to_world.

        Returns:
            Distance from the EE frame origin to the object centre [m] (for plausibility logs).

        Raises:
            WorldError: unknown id, static object, or an object is already attached.
        """
        state = self.state(object_id)
        if self.attached_id is not None:
            raise WorldError(
                f'cannot attach {quote(object_id)}: {quote(self.attached_id)} is attached'
            )
        if state.spec.role == 'static':
            raise WorldError(f'cannot attach {quote(object_id)}: it is a static object')
        self._object_to_ee = ee_pose.actInv(state.pose)
        self.attached_id = object_id
        state.status = 'grasped'
        self.version += 1
        return float(np.linalg.norm(self._object_to_ee.translation))

    def update(self, ee_pose: pin.SE3) -> bool:
        """Move the attached object with the end-effector (transform_ee_to_world ``ee_pose``).

        Returns:
            True if an object moved.
        """
        if self.attached_id is None:
            return False
        state = self.objects[self.attached_id]
        new_pose = ee_pose * self._object_to_ee
        if new_pose.isApprox(state.pose, 1e-12):
            return False
        state.pose = new_pose
        self.version += 1
        return True

    def detach(self, object_id: str, status: str = 'relocated') -> None:
        """Release ``object_id`` where it is, with status ``'relocated'`` or ``'in_clutter'``.

        Raises:
            WorldError: unknown id, ``object_id`` not attached, or a bad status.
        """
        state = self.state(object_id)
        if self.attached_id != object_id:
            held = repr(self.attached_id) if self.attached_id else 'nothing'
            raise WorldError(f'cannot detach {quote(object_id)}: it is not attached ({held} is)')
        if status not in RELEASE_STATUSES:
            raise WorldError(
                f'release status must be one of {RELEASE_STATUSES}, got {quote(status)}'
            )
        if status == 'relocated':
            index = sum(other.status == 'relocated' for other in self.objects.values())
            yaw = math.atan2(state.pose.rotation[1, 0], state.pose.rotation[0, 0])
            settled = settle_pose(self.scenario, index, state.spec, state.pose.translation, yaw)
            if settled is not None:
                cos, sin = math.cos(settled[1]), math.sin(settled[1])
                rotation = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])
                state.pose = pin.SE3(rotation, settled[0])
        else:  # put back down (#32: an execution undone): upright on the table where it is
            spec, p = state.spec, state.pose.translation
            yaw = math.atan2(state.pose.rotation[1, 0], state.pose.rotation[0, 0])
            half = spec.height / 2 if spec.shape == 'cylinder' else spec.size[2] / 2
            state.pose = spec_pose(dataclasses.replace(spec, position=(p[0], p[1], half), yaw=yaw))
        state.status = status
        self.attached_id = None
        self.version += 1

    def place(self, spec: ObjectSpec) -> None:
        """Put ``spec`` in the clutter at its pose (a scene event, #32): an object moved, or a new
        one added to :attr:`scenario` (its status ``'in_clutter'``).

        Raises:
            WorldError: the object is held or relocated (only objects in the clutter move).
        """
        state = self.objects.get(spec.id)
        if state is not None and state.status != 'in_clutter':
            raise WorldError(f'{quote(spec.id)} is {state.status}, not in the clutter')
        if state is None:
            objects = (*self.scenario.objects, spec)
            self.scenario = dataclasses.replace(self.scenario, objects=objects)
        self.objects[spec.id] = ObjectState(spec, spec_pose(spec))
        self.version += 1

    def remove(self, object_id: str) -> None:
        """Take ``object_id`` out of the scene (a scene event, #32).

        Raises:
            WorldError: unknown id, or the object is held.
        """
        state = self.state(object_id)
        if self.attached_id == object_id:
            raise WorldError(f'{quote(object_id)} is held by the hand')
        del self.objects[state.spec.id]
        objects = tuple(o for o in self.scenario.objects if o.id != object_id)
        self.scenario = dataclasses.replace(self.scenario, objects=objects)
        self.version += 1

    def clutter(self) -> list[ObjectSpec]:
        """The objects in the clutter (and the table) at their current poses."""
        out = []
        for state in self.objects.values():
            if state.status == 'in_clutter':
                p, r = state.pose.translation, state.pose.rotation
                yaw = math.atan2(r[1, 0], r[0, 0])
                out.append(dataclasses.replace(state.spec, position=vec3(p), yaw=yaw))
        return out
