"""python-fcl worlds: the scene objects and the arm's links, with broad-phase distance queries.

No ROS import. Every query goes through ``fcl.DynamicAABBTreeCollisionManager``; the Python
callback only sees pairs whose bounding boxes are closer than the query threshold, so a query
where nothing is near costs one broad-phase traversal in C++.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import fcl
import numpy as np
import pinocchio as pin
from qtree_scene.scene import ObjectSpec

_REQUEST = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)
# Links of the 7-DoF Jaco² (short names) in the groups whose cross pairs are all non-adjacent.
_PROXIMAL = ('link_base', 'link_1', 'link_2', 'link_3')
_DISTAL = ('link_5', 'link_6', 'link_7', 'finger', 'attached')
_FOREARM_PROXIMAL = ('link_base', 'link_1', 'link_2')
_HAND = ('link_7', 'finger', 'attached')
_WRIST = ('link_4', 'link_5')
# Links never checked against the scene: the base stands on the table, link_1 turns above it.
_NOT_VS_SCENE = ('link_base', 'link_1')


@dataclass(frozen=True)
class Proximity:
    """One close pair found by a distance query.

    Attributes:
        name_a: robot collision body (link name or ``'attached'``).
        name_b: other body (scene object id or link name).
        distance: signed distance [m] (≤ 0: contact).
        point_a: closest point on ``name_a`` in the world frame [m], shape (3,).
        point_b: closest point on ``name_b`` in the world frame [m], shape (3,).
    """

    name_a: str
    name_b: str
    distance: float
    point_a: np.ndarray
    point_b: np.ndarray


def object_geometry(obj: ObjectSpec, inflate: float = 0.0) -> fcl.CollisionGeometry:
    """python-fcl geometry of a scene object, grown by ``inflate`` [m] on every side."""
    if obj.shape == 'cylinder':
        return fcl.Cylinder(obj.radius + inflate, obj.height + 2 * inflate)
    return fcl.Box(*(np.asarray(obj.size, dtype=float) + 2 * inflate))


def object_transform(obj: ObjectSpec) -> fcl.Transform:
    """World placement of a scene object (yaw about z)."""
    c, s = np.cos(obj.yaw), np.sin(obj.yaw)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return fcl.Transform(rotation, np.asarray(obj.position, dtype=float))


class _Collector:
    """Callback data: keeps every pair closer than ``threshold`` [m]."""

    def __init__(self, names: dict[int, str], threshold: float) -> None:
        self.names = names
        self.threshold = threshold
        self.found: list[Proximity] = []


def _collect(o1: fcl.CollisionObject, o2: fcl.CollisionObject, data: _Collector):
    result = fcl.DistanceResult()
    distance = fcl.distance(o1, o2, _REQUEST, result)
    if distance < data.threshold:
        a, b = data.names[id(result.o1)], data.names[id(result.o2)]
        pa, pb = result.nearest_points
        data.found.append(Proximity(a, b, distance, pa, pb))
    return False, data.threshold


class SceneWorld:
    """The scene objects (all roles) as one broad-phase manager.

    Attributes:
        objects: the objects in the manager, by id.
    """

    def __init__(self, objects: Iterable[ObjectSpec]) -> None:
        self.objects = {obj.id: obj for obj in objects}
        self._names: dict[int, str] = {}
        self._keep: list[fcl.CollisionObject] = []
        self.manager = fcl.DynamicAABBTreeCollisionManager()
        for obj in self.objects.values():
            geometry = object_geometry(obj)
            self._names[id(geometry)] = obj.id
            self._keep.append(fcl.CollisionObject(geometry, object_transform(obj)))
        if self._keep:
            self.manager.registerObjects(self._keep)
        self.manager.setup()

    @property
    def names(self) -> dict[int, str]:
        """Object id by ``id()`` of its fcl geometry."""
        return self._names

    def clearance(
        self, body: fcl.CollisionObject, geometry: fcl.CollisionGeometry, threshold: float
    ) -> list[Proximity]:
        """Scene objects closer than ``threshold`` [m] to ``body`` (whose geometry is given).

        The probe is reported as ``name_a='probe'``.
        """
        if not self._keep:
            return []
        data = _Collector({**self._names, id(geometry): 'probe'}, threshold)
        self.manager.distance(body, data, _collect)
        return [_probe_first(p) for p in data.found]


def _probe_first(p: Proximity) -> Proximity:
    if p.name_b == 'probe':
        return Proximity(p.name_b, p.name_a, p.distance, p.point_b, p.point_a)
    return p


class RobotBodies:
    """The arm's collision primitives (from the Pinocchio ``GeometryModel``) as fcl objects.

    Self-hit queries run on one broad-phase manager of every body and keep exactly the pairs of
    ``self_pairs`` (``Jaco2Model.self_collision_pairs``), plus the carried object against every
    link but the hand that holds it (link 7, fingers). The managers are built once and updated
    after each :meth:`place`.
    """

    def __init__(
        self,
        geometry_model: pin.GeometryModel,
        link_names: list[str],
        self_pairs: Iterable[tuple[int, int]] | None = None,
    ) -> None:
        """Args:
        geometry_model: the robot's collision geometry.
        link_names: link of each geometry (index = geometry index).
        self_pairs: geometry index pairs checked for self-hits (default: the cross pairs of
            the module's link groups, the previous behaviour).
        """
        self.link_names = list(link_names)
        if self_pairs is None:
            groups = ((_DISTAL, _PROXIMAL), (('link_4',), _FOREARM_PROXIMAL), (_HAND, _WRIST))
            short = [_short(n) for n in self.link_names]
            self_pairs = [
                (i, j)
                for i in range(len(short))
                for j in range(i + 1, len(short))
                if any(
                    (short[i] in a and short[j] in b) or (short[i] in b and short[j] in a)
                    for a, b in groups
                )
            ]
        self._allowed = {
            frozenset((self.link_names[i], self.link_names[j])) for i, j in self_pairs
        }
        self._allowed |= {
            frozenset(('attached', n)) for n in self.link_names if _short(n) not in _HAND
        }
        self.names: dict[int, str] = {}
        self.bodies: list[fcl.CollisionObject] = []
        self._geometries: list[fcl.CollisionGeometry] = []
        self._transforms: list[fcl.Transform] = []
        for name, g in zip(self.link_names, geometry_model.geometryObjects, strict=True):
            geometry = _fcl_geometry(g.geometry)
            self.names[id(geometry)] = name
            self._geometries.append(geometry)
            self._transforms.append(fcl.Transform())
            self.bodies.append(fcl.CollisionObject(geometry, fcl.Transform()))
        # Bounding sphere of each body about its centre (the geometry frame's origin) [m].
        self._radii = np.array([_sphere_radius(g) for g in self._geometries])
        self._centres = np.zeros((len(self.bodies) + 1, 3))  # last row: the carried object
        self.attached: fcl.CollisionObject | None = None
        self.attached_radius = 0.0  # bounding radius of the carried object [m]
        self._attached_offset = pin.SE3.Identity()
        self._attached_transform = fcl.Transform()
        self._build_managers()

    def _group(self, keys: tuple[str, ...]) -> list[fcl.CollisionObject]:
        out = [b for n, b in zip(self.link_names, self.bodies, strict=True) if _short(n) in keys]
        if 'attached' in keys and self.attached is not None:
            out.append(self.attached)
        return out

    def _build_managers(self) -> None:
        # The self-hit pairs as index arrays into [*bodies, attached] (pair order: first body,
        # then partner, ascending): no distance is computed for adjacent or rigid pairs, and a
        # bounding-sphere test in numpy skips the far ones before any fcl call.
        names = [*self.link_names, 'attached']
        present = [*([True] * len(self.bodies)), self.attached is not None]
        pairs = [
            (i, j)
            for i in range(len(names))
            for j in range(i + 1, len(names))
            if present[i] and present[j] and frozenset((names[i], names[j])) in self._allowed
        ]
        self._pair_a = np.array([i for i, _ in pairs], dtype=int)
        self._pair_b = np.array([j for _, j in pairs], dtype=int)
        self._pair_names = [(names[i], names[j]) for i, j in pairs]
        self._objects = [*self.bodies, self.attached]
        self._all_radii = np.r_[self._radii, self.attached_radius]
        keys = tuple(_short(n) for n in self.link_names if _short(n) not in _NOT_VS_SCENE)
        self._scene_manager = _manager(self._group((*keys, 'attached')))

    def attach(self, obj: ObjectSpec, transform_obj_to_ee: pin.SE3, settle_m: float = 0.0) -> None:
        """Carry ``obj`` rigidly at ``transform_obj_to_ee`` (its pose in the EE frame).

        Args:
            obj: the grasped object.
            transform_obj_to_ee: pose of the object in the EE frame.
            settle_m: the object's collision body is this much shorter at each end [m], so
                that setting it down on the table is not a collision (sideways margins stay).
        """
        if obj.shape == 'cylinder':
            geometry = fcl.Cylinder(obj.radius, max(obj.height - 2 * settle_m, 1e-3))
        else:
            sx, sy, sz = obj.size
            geometry = fcl.Box(sx, sy, max(sz - 2 * settle_m, 1e-3))
        self.names[id(geometry)] = 'attached'
        self._attached_geometry = geometry
        height = obj.height if obj.shape == 'cylinder' else obj.size[2]
        across = obj.radius if obj.shape == 'cylinder' else 0.5 * math.hypot(*obj.size[:2])
        self.attached_radius = math.hypot(across, height / 2)
        self.attached = fcl.CollisionObject(geometry, fcl.Transform())
        self._attached_offset = transform_obj_to_ee
        self._build_managers()

    def detach(self) -> None:
        """Stop carrying the attached object."""
        if self.attached is not None:
            self.attached = None
            self._build_managers()

    def place(self, oMg: list[pin.SE3], world_ee: pin.SE3) -> None:
        """Move the bodies to the geometry placements ``oMg`` and the EE pose ``world_ee``."""
        centres = self._centres
        for index, (body, tf, placement) in enumerate(
            zip(self.bodies, self._transforms, oMg, strict=True)
        ):
            translation = placement.translation
            tf.setRotation(placement.rotation)
            tf.setTranslation(translation)
            body.setTransform(tf)
            centres[index] = translation
        if self.attached is not None:
            world_obj = world_ee * self._attached_offset
            tf = self._attached_transform
            tf.setRotation(world_obj.rotation)
            tf.setTranslation(world_obj.translation)
            self.attached.setTransform(tf)
            centres[-1] = world_obj.translation
        self._scene_manager.update()

    def self_proximities(self, threshold: float) -> list[Proximity]:
        """Pairs of the self-hit list closer than ``threshold`` [m].

        A pair whose bounding spheres are ``threshold`` apart or more cannot be closer, so only
        the others reach ``fcl.distance`` (the result is the same set as a query of every pair).
        """
        a, b = self._pair_a, self._pair_b
        if a.size == 0:
            return []
        gap = np.linalg.norm(self._centres[a] - self._centres[b], axis=1)
        gap -= self._all_radii[a] + self._all_radii[b]
        found: list[Proximity] = []
        objects = self._objects
        for k in np.flatnonzero(gap < threshold):
            result = fcl.DistanceResult()
            distance = fcl.distance(objects[a[k]], objects[b[k]], _REQUEST, result)
            if distance < threshold:
                name_a, name_b = self._pair_names[k]
                pa, pb = result.nearest_points
                found.append(Proximity(name_a, name_b, distance, pa, pb))
        return found

    def scene_proximities(self, scene: SceneWorld, threshold: float) -> list[Proximity]:
        """(body, scene object) pairs closer than ``threshold`` [m]; the base is skipped."""
        if not scene.objects:
            return []
        data = _Collector({**self.names, **scene.names}, threshold)
        self._scene_manager.distance(scene.manager, data, _collect)
        return [_robot_first(p, scene) for p in data.found]


def _manager(bodies: list[fcl.CollisionObject]) -> fcl.DynamicAABBTreeCollisionManager:
    manager = fcl.DynamicAABBTreeCollisionManager()
    if bodies:
        manager.registerObjects(bodies)
    manager.setup()
    return manager


def _robot_first(p: Proximity, scene: SceneWorld) -> Proximity:
    if p.name_a in scene.objects and p.name_b not in scene.objects:
        return Proximity(p.name_b, p.name_a, p.distance, p.point_b, p.point_a)
    return p


def _short(link: str) -> str:
    short = link.removeprefix('j2s7s300_')
    return 'finger' if short.startswith('link_finger') else short


def _sphere_radius(geometry: fcl.CollisionGeometry) -> float:
    """Radius [m] of the sphere about an fcl primitive's centre that contains it."""
    if isinstance(geometry, fcl.Cylinder):
        return math.hypot(geometry.radius, geometry.lz / 2)
    if isinstance(geometry, fcl.Box):
        return 0.5 * float(np.linalg.norm(geometry.side))
    return float(geometry.radius)


def _fcl_geometry(geometry: object) -> fcl.CollisionGeometry:
    if hasattr(geometry, 'halfLength'):
        return fcl.Cylinder(float(geometry.radius), 2.0 * float(geometry.halfLength))
    if hasattr(geometry, 'halfSide'):
        return fcl.Box(*(2.0 * np.asarray(geometry.halfSide)))
    if hasattr(geometry, 'radius'):
        return fcl.Sphere(float(geometry.radius))
    raise TypeError(f'unsupported collision geometry {type(geometry).__name__}')
