"""``/tf`` and ``/tf_static`` of the arm from joint states, with Pinocchio (no ROS import).

What Foxglove and Rerun need to draw the robot from a log: the URDF (``/robot_description``) plus
the transform of every link from its parent link (``tf2_msgs/msg/TFMessage``; the frame ids are
the URDF link names). Links under fixed joints go to ``/tf_static`` once, together with
``world`` → root link (identity: the world frame is the robot base frame); links under moving
joints go to ``/tf`` at every joint state (or at a lower rate chosen by the caller).

The model is built from the URDF text the log carries (``/robot_description``), so the frames
always match the geometry drawn. Continuous joints (nq = 2 in Pinocchio) are handled.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from qtree_recorder.exceptions import RobotModelError

WORLD_FRAME = 'world'


@dataclass(frozen=True)
class FrameTransform:
    """One parent → child transform (``geometry_msgs/Transform`` content).

    Attributes:
        parent: parent frame id.
        child: child frame id.
        translation: child origin in the parent frame [m], shape (3,).
        rotation: child orientation in the parent frame, quaternion (x, y, z, w), shape (4,).
    """

    parent: str
    child: str
    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]


def transform_from_se3(parent: str, child: str, placement: pin.SE3) -> FrameTransform:
    """A :class:`FrameTransform` from a Pinocchio placement ``transform_child_to_parent``."""
    quat = pin.Quaternion(placement.rotation)
    quat.normalize()
    t = placement.translation
    return FrameTransform(
        parent,
        child,
        (float(t[0]), float(t[1]), float(t[2])),
        (float(quat.x), float(quat.y), float(quat.z), float(quat.w)),
    )


class ArmFrames:
    """Parent → child link transforms of a URDF robot for given joint positions.

    Args:
        urdf_text: the robot description (URDF XML).
        world_frame: frame the root link is attached to (identity) in ``/tf_static``.

    Raises:
        RobotModelError: the URDF does not parse or has no links.
    """

    def __init__(self, urdf_text: str, world_frame: str = WORLD_FRAME) -> None:
        try:
            root = ET.fromstring(urdf_text)
            self._model = pin.buildModelFromXML(urdf_text)
        except (ET.ParseError, ValueError, RuntimeError) as err:
            raise RobotModelError(str(err).splitlines()[0] if str(err) else repr(err)) from None
        joints = list(root.iter('joint'))
        self._parents = {_joint_link(j, 'child'): _joint_link(j, 'parent') for j in joints}
        fixed = {_joint_link(j, 'child') for j in joints if j.get('type') == 'fixed'}
        links = [link.get('name', '') for link in root.iter('link')]
        roots = [name for name in links if name not in self._parents]
        if not links or len(roots) != 1:
            raise RobotModelError(f'expected one root link, found {roots or "none"}')
        self.root_link: str = roots[0]
        self.world_frame = world_frame
        self._data = self._model.createData()
        self._frame_ids: dict[str, int] = {}
        for name in links:
            if not self._model.existFrame(name, pin.BODY):
                raise RobotModelError(f'link {name!r} is not in the Pinocchio model')
            self._frame_ids[name] = self._model.getFrameId(name, pin.BODY)
        self.static_children = tuple(c for c in self._parents if c in fixed)
        self.moving_children = tuple(c for c in self._parents if c not in fixed)
        self._joint_slots: dict[str, tuple[int, int]] = {}
        for joint_id in range(1, self._model.njoints):
            joint = self._model.joints[joint_id]
            self._joint_slots[self._model.names[joint_id]] = (joint.idx_q, joint.nq)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Moving joints of the model, in model order."""
        return tuple(self._joint_slots)

    def configuration(self, names: Sequence[str], positions: Sequence[float]) -> np.ndarray:
        """Pinocchio configuration from a joint state; joints not given stay at 0 [rad].

        Names not in the model are ignored (e.g. another robot's joints).

        Raises:
            RobotModelError: lengths differ or a position is not finite.
        """
        if len(names) != len(positions):
            raise RobotModelError(f'{len(names)} joint names but {len(positions)} positions')
        q = pin.neutral(self._model)
        for name, value in zip(names, positions, strict=True):
            slot = self._joint_slots.get(name)
            if slot is None:
                continue
            value = float(value)
            if not math.isfinite(value):
                raise RobotModelError(f'joint {name!r}: position {value} is not finite')
            index, nq = slot
            if nq == 2:  # continuous joint: (cos, sin)
                q[index], q[index + 1] = math.cos(value), math.sin(value)
            else:
                q[index] = value
        return q

    def _placements(self, q: np.ndarray, children: Sequence[str]) -> list[FrameTransform]:
        pin.framesForwardKinematics(self._model, self._data, q)
        out = []
        for child in children:
            parent = self._parents[child]
            world_parent = self._data.oMf[self._frame_ids[parent]]
            world_child = self._data.oMf[self._frame_ids[child]]
            out.append(transform_from_se3(parent, child, world_parent.actInv(world_child)))
        return out

    def moving_transforms(
        self, names: Sequence[str], positions: Sequence[float]
    ) -> list[FrameTransform]:
        """Transforms of every link under a moving joint, for one joint state (``/tf``).

        Args:
            names: joint names of the state.
            positions: joint positions [rad], same length.

        Raises:
            RobotModelError: bad joint state.
        """
        return self._placements(self.configuration(names, positions), self.moving_children)

    def static_transforms(self) -> list[FrameTransform]:
        """``world`` → root link (identity) and every fixed joint's transform (``/tf_static``)."""
        identity = FrameTransform(self.world_frame, self.root_link, (0.0, 0.0, 0.0),
                                  (0.0, 0.0, 0.0, 1.0))  # fmt: skip
        q = pin.neutral(self._model)
        return [identity, *self._placements(q, self.static_children)]


def tf_message(transforms: Sequence[FrameTransform], stamp_ns: int) -> dict:
    """A ``tf2_msgs/msg/TFMessage`` as a dict for :class:`qtree_recorder.encoding.DynamicEncoder`.

    Args:
        transforms: the transforms.
        stamp_ns: header stamp of every transform [ns since epoch].
    """
    stamp = {'sec': stamp_ns // 1_000_000_000, 'nanosec': stamp_ns % 1_000_000_000}
    return {
        'transforms': [
            {
                'header': {'stamp': stamp, 'frame_id': t.parent},
                'child_frame_id': t.child,
                'transform': {
                    'translation': dict(zip('xyz', t.translation, strict=True)),
                    'rotation': dict(zip('xyzw', t.rotation, strict=True)),
                },
            }
            for t in transforms
        ]
    }


def pose_transform(
    parent: str, child: str, position: Sequence[float], orientation: Mapping[str, float]
) -> FrameTransform:
    """A transform from a pose (position [m], quaternion dict with x, y, z, w)."""
    x, y, z = (float(v) for v in position)
    quat = tuple(float(orientation[k]) for k in 'xyzw')
    norm = math.sqrt(sum(v * v for v in quat)) or 1.0
    return FrameTransform(parent, child, (x, y, z), tuple(v / norm for v in quat))  # type: ignore[arg-type]


def _joint_link(joint: ET.Element, tag: str) -> str:
    """The ``link`` attribute of a joint's ``<parent>`` or ``<child>`` (``tag``).

    Raises:
        RobotModelError: the element or its attribute is missing.
    """
    element = joint.find(tag)
    link = element.get('link') if element is not None else None
    if link is None:
        raise RobotModelError('a <joint> lacks its <parent> or <child>')
    return link
