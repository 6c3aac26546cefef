"""Kinova Jaco² j2s7s300 model: URDF → Pinocchio (kinematics) and python-fcl (collision). No ROS.

The URDF (``urdf/j2s7s300.urdf``, installed to ``share/jaco2_description/urdf/``) follows
KINOVA_FACTS.md; its joints 1, 3, 5 and 7 are
``continuous`` as in kinova-ros. Pinocchio turns a continuous joint into a unit-circle joint with
nq = 2 (cos θ, sin θ) and nv = 1, which breaks the plain ``q ∈ ℝ^7`` arithmetic of the STPIK
planner (eq. 6 integrates q̇ ∈ ℝ^7 into q). The loader therefore rewrites every continuous joint
as a revolute joint with limits ±4π [rad] before building the Pinocchio model, so that nq == nv.
±4π is far beyond any motion from Kinova's Home (q1 = 4.71, q7 = 4.88): the STPIK planner treats
these joints as unbounded (no limit task, no limit check) and the simulator's integrator, which
clamps at these limits, then never clamps a planned motion.

Two models are offered:

* :class:`Jaco2Model`: the 7-DoF planning model, finger joints locked (``pin.buildReducedModel``),
  with its collision geometry as a Pinocchio ``GeometryModel`` and as python-fcl objects.
* :func:`full_model` / :func:`link_placements`: the model with every finger joint, for /tf.
"""

from __future__ import annotations

import functools
import math
import pathlib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import pinocchio as pin

from jaco2_description.exceptions import ModelError

PREFIX = 'j2s7s300_'
ARM_JOINTS: tuple[str, ...] = tuple(f'{PREFIX}joint_{i}' for i in range(1, 8))
FINGER_JOINTS: tuple[str, ...] = tuple(f'{PREFIX}joint_finger_{i}' for i in (1, 2, 3)) + tuple(
    f'{PREFIX}joint_finger_tip_{i}' for i in (1, 2, 3)
)
BASE_LINK = f'{PREFIX}link_base'
EE_FRAME = f'{PREFIX}end_effector'
# MoveIt SRDF "Home" [rad]; EE ≈ (0.266, -0.212, 0.503) m.
HOME = np.array([4.71, 2.84, 0.0, 0.75, 4.62, 4.48, 4.88])
CANDLE = np.full(7, math.pi)  # "Vertical": arm straight up [rad]
CONTINUOUS_LIMIT = 4.0 * math.pi  # limits given to continuous joints [rad]
FINGER_MAX = 1.51  # proximal finger upper limit [rad]
FINGER_OPEN = 0.2  # MoveIt "Open" [rad]
# Widest object the open hand closes on: inner faces of the open fingertips are ±0.046 m from the
# EE origin (URDF, fingers at FINGER_OPEN), minus 5 mm clearance on each side [m].
HAND_OPENING_M = 0.082


URDF_NAME = 'j2s7s300.urdf'


def urdf_path() -> pathlib.Path:
    """Path of the j2s7s300 URDF: ``share/jaco2_description/urdf/`` if installed, else the source.

    The installed path is found through the ament index (``ament_index_python``, plain Python,
    no rclpy); without an index (a bare checkout on ``PYTHONPATH``) the file beside the package.
    """
    try:
        from ament_index_python.packages import get_package_share_directory

        share = pathlib.Path(get_package_share_directory('jaco2_description'))
        installed = share / 'urdf' / URDF_NAME
        if installed.is_file():
            return installed
    except (ImportError, LookupError, ValueError):
        pass
    return pathlib.Path(__file__).resolve().parent.parent / 'urdf' / URDF_NAME


@functools.cache
def urdf_text() -> str:
    """The j2s7s300 URDF as text (continuous joints kept ``continuous``)."""
    return urdf_path().read_text(encoding='utf-8')


def planning_urdf(text: str) -> str:
    """Rewrite every ``continuous`` joint as ``revolute`` with limits ±4π (see module docstring).

    Args:
        text: URDF XML text.

    Returns:
        The rewritten URDF XML text.
    """
    root = ET.fromstring(text)
    for joint in root.iter('joint'):
        if joint.get('type') != 'continuous':
            continue
        joint.set('type', 'revolute')
        limit = joint.find('limit')
        if limit is None:
            limit = ET.SubElement(joint, 'limit', effort='0', velocity='0')
        limit.set('lower', repr(-CONTINUOUS_LIMIT))
        limit.set('upper', repr(CONTINUOUS_LIMIT))
    return ET.tostring(root, encoding='unicode')


@dataclass(frozen=True)
class JointLimits:
    """Arm joint limits.

    Attributes:
        lower: lower position limits [rad], shape (7,).
        upper: upper position limits [rad], shape (7,).
        velocity: velocity limits [rad/s], shape (7,), all > 0.
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray


@functools.cache
def _full_models() -> tuple[pin.Model, pin.GeometryModel, pin.GeometryModel]:
    text = planning_urdf(urdf_text())
    model = pin.buildModelFromXML(text)
    collision = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.COLLISION)
    visual = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.VISUAL)
    return model, collision, visual


def full_model() -> pin.Model:
    """Pinocchio model with all 13 joints (7 arm + 6 finger), nq == nv == 13. A fresh copy."""
    return pin.Model(_full_models()[0])


@functools.cache
def link_parents() -> dict[str, str]:
    """Parent link of every non-root link of the URDF: ``{child_link: parent_link}``."""
    root = ET.fromstring(urdf_text())
    return {_joint_link(j, 'child'): _joint_link(j, 'parent') for j in root.iter('joint')}


def _joint_link(joint: ET.Element, tag: str) -> str:
    """The ``link`` attribute of a URDF joint's ``<parent>`` or ``<child>`` (``tag``)."""
    element = joint.find(tag)
    link = None if element is None else element.get('link')
    if link is None:
        raise ModelError(f'joint {joint.get("name")!r} has no <{tag} link=...>')
    return link


@functools.cache
def continuous_joints() -> tuple[bool, ...]:
    """Per arm joint (in :data:`ARM_JOINTS` order): True when the URDF joint is continuous."""
    root = ET.fromstring(urdf_text())
    kinds = {j.get('name'): j.get('type') for j in root.iter('joint')}
    return tuple(kinds.get(name) == 'continuous' for name in ARM_JOINTS)


@functools.cache
def arm_limits() -> JointLimits:
    """Limits of the 7 arm joints as the planning model sees them (continuous → ±4π)."""
    model = _full_models()[0]
    idx = [model.joints[model.getJointId(n)].idx_q for n in ARM_JOINTS]
    return JointLimits(
        lower=np.array(model.lowerPositionLimit[idx]),
        upper=np.array(model.upperPositionLimit[idx]),
        velocity=np.array(model.velocityLimit[idx]),
    )


def link_placements(q_all: dict[str, float]) -> dict[str, pin.SE3]:
    """Placement of every link relative to its parent link (what /tf carries).

    Args:
        q_all: joint angles [rad] by joint name; missing joints are taken as 0. Values of joints
            not in the model are ignored (e.g. other robots in one JointState).

    Returns:
        ``{child_link: transform_child_to_parent}`` for every link but the root ``link_base``
        (see :func:`link_parents` for the parent of each).

    Raises:
        ModelError: a value is not finite.
    """
    model = _full_models()[0]
    q = np.zeros(model.nq)
    for name, value in q_all.items():
        if not model.existJointName(name):
            continue
        if not math.isfinite(value):
            raise ModelError(f'joint {name!r}: value {value} is not finite')
        q[model.joints[model.getJointId(name)].idx_q] = value
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    placements = {}
    for child, parent in link_parents().items():
        world_child = data.oMf[model.getFrameId(child, pin.BODY)]
        world_parent = data.oMf[model.getFrameId(parent, pin.BODY)]
        placements[child] = world_parent.actInv(world_child)
    return placements


def _to_fcl_geometry(geometry: Any) -> fcl.CollisionGeometry:
    """python-fcl copy of a coal primitive (cylinder or box)."""
    if hasattr(geometry, 'halfLength'):
        return fcl.Cylinder(float(geometry.radius), 2.0 * float(geometry.halfLength))
    if hasattr(geometry, 'halfSide'):
        return fcl.Box(*(2.0 * np.asarray(geometry.halfSide)))
    raise ModelError(f'unsupported collision geometry {type(geometry).__name__}')


class Jaco2Model:
    """7-DoF planning model of the Jaco² with the hand's finger joints locked.

    Attributes:
        finger_angle: angle the proximal finger joints are locked at [rad] (tips at 0).
        model: Pinocchio model, nq == nv == 7 (joints in :data:`ARM_JOINTS` order).
        data: Pinocchio data of ``model``, updated by :meth:`forward`.
        geometry_model: collision geometry (one primitive per link, fingers on joint 7).
        geometry_data: placements of ``geometry_model`` (``oMg``), updated by :meth:`forward`.
        limits: arm joint limits.
        collision_links: link name of each collision geometry, index = geometry index.
        self_collision_pairs: geometry index pairs ``(i, j)``, i < j, checked for self-collision:
            all pairs except parent/child links and pairs rigidly fixed to each other in the
            reduced model (same parent joint, e.g. the locked fingers and the hand).
    """

    def __init__(self, finger_angle: float = FINGER_OPEN) -> None:
        """Build the reduced model.

        Args:
            finger_angle: proximal finger joint angle [rad], in [0, 1.51].

        Raises:
            ModelError: ``finger_angle`` outside [0, 1.51] or not finite.
        """
        if not (math.isfinite(finger_angle) and 0.0 <= finger_angle <= FINGER_MAX):
            raise ModelError(f'finger_angle {finger_angle} rad outside [0, {FINGER_MAX}]')
        self.finger_angle = float(finger_angle)
        full, collision, _ = _full_models()
        q_ref = pin.neutral(full)
        locked = []
        for name in FINGER_JOINTS:
            joint_id = full.getJointId(name)
            locked.append(joint_id)
            if 'tip' not in name:
                q_ref[full.joints[joint_id].idx_q] = self.finger_angle
        self.model, self.geometry_model = pin.buildReducedModel(full, collision, locked, q_ref)
        names = tuple(self.model.names)[1:]
        if names != ARM_JOINTS or self.model.nq != 7 or self.model.nv != 7:
            raise ModelError(f'reduced model has joints {names}, expected {ARM_JOINTS}')
        self.data = self.model.createData()
        self.geometry_data = pin.GeometryData(self.geometry_model)
        self.limits = JointLimits(
            lower=np.array(self.model.lowerPositionLimit),
            upper=np.array(self.model.upperPositionLimit),
            velocity=np.array(self.model.velocityLimit),
        )
        self.collision_links = [
            self.model.frames[g.parentFrame].name for g in self.geometry_model.geometryObjects
        ]
        parents = link_parents()
        joints = [g.parentJoint for g in self.geometry_model.geometryObjects]
        self.self_collision_pairs = [
            (i, j)
            for i, a in enumerate(self.collision_links)
            for j, b in enumerate(self.collision_links)
            if i < j and joints[i] != joints[j] and parents.get(a) != b and parents.get(b) != a
        ]
        self._ee_id = self.frame_id(EE_FRAME)
        self._fcl: list[tuple[str, fcl.CollisionObject]] | None = None

    def frame_id(self, frame: str) -> int:
        """Pinocchio index of ``frame``.

        Raises:
            ModelError: no frame of that name.
        """
        if not self.model.existFrame(frame):
            raise ModelError(f'unknown frame {frame!r}')
        return self.model.getFrameId(frame)

    def check_q(self, q: np.ndarray) -> np.ndarray:
        """``q`` as a float array of shape (7,) [rad].

        Raises:
            ModelError: wrong shape or a non-finite value.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (7,):
            raise ModelError(f'q must have shape (7,), got {q.shape}')
        if not np.all(np.isfinite(q)):
            raise ModelError(f'q has non-finite values: {q}')
        return q

    def forward(self, q: np.ndarray) -> None:
        """Forward kinematics: joint, frame and collision placements at ``q`` [rad], shape (7,)."""
        q = self.check_q(q)
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        pin.updateGeometryPlacements(
            self.model, self.data, self.geometry_model, self.geometry_data
        )

    def ee_pose(self, q: np.ndarray) -> pin.SE3:
        """End-effector pose in the base frame (``transform_ee_to_base``) at ``q`` [rad] (7,)."""
        self.forward(q)
        return pin.SE3(self.data.oMf[self._ee_id])

    def frame_jacobian(self, q: np.ndarray, frame: str = EE_FRAME) -> np.ndarray:
        """Jacobian of ``frame``, rows (v [m/s], ω [rad/s]) in LOCAL_WORLD_ALIGNED axes.

        Args:
            q: joint angles [rad], shape (7,).
            frame: frame name.

        Returns:
            J with [v; ω] = J q̇, shape (6, 7).
        """
        q = self.check_q(q)
        return pin.computeFrameJacobian(
            self.model, self.data, q, self.frame_id(frame), pin.LOCAL_WORLD_ALIGNED
        )

    def fcl_objects(self) -> list[tuple[str, fcl.CollisionObject]]:
        """One python-fcl object per collision geometry, as ``(link_name, object)``.

        Built once; the same objects are returned on every call, index = geometry index (the
        indices of :attr:`self_collision_pairs`). Their transforms are set by :meth:`update_fcl`.
        """
        if self._fcl is None:
            self._fcl = [
                (link, fcl.CollisionObject(_to_fcl_geometry(g.geometry), fcl.Transform()))
                for link, g in zip(
                    self.collision_links, self.geometry_model.geometryObjects, strict=True
                )
            ]
        return self._fcl

    def update_fcl(self, q: np.ndarray) -> None:
        """Run :meth:`forward` at ``q`` [rad] (7,) and move the python-fcl objects there."""
        self.forward(q)
        for (_, obj), placement in zip(self.fcl_objects(), self.geometry_data.oMg, strict=True):
            obj.setTransform(
                fcl.Transform(np.array(placement.rotation), np.array(placement.translation))
            )

    def self_collision_distances(self, q: np.ndarray) -> np.ndarray:
        """FCL distance [m] of each :attr:`self_collision_pairs` pair at ``q`` (≤ 0: contact)."""
        self.update_fcl(q)
        objects = self.fcl_objects()
        request = fcl.DistanceRequest()
        out = np.empty(len(self.self_collision_pairs))
        for k, (i, j) in enumerate(self.self_collision_pairs):
            out[k] = fcl.distance(objects[i][1], objects[j][1], request, fcl.DistanceResult())
        return out
