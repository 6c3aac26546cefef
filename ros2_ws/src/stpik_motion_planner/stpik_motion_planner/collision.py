"""python-fcl worlds: the scene objects and the arm's links, with distance queries.

No ROS import. A probe against the scene (:meth:`SceneWorld.clearance`) goes through
``fcl.DynamicAABBTreeCollisionManager``; the sampler's probes (:meth:`SceneWorld.probe_hits`,
and the hand's parts together: :class:`ProbeSet`, :meth:`SceneWorld.cull_probes`) are culled
first by the lower bound of :func:`.kernels.scene_candidates`. The arm's queries
(:class:`RobotBodies`) bound every pair's distance from below in numpy first (bounding spheres,
a box around each scene object) and call ``fcl.distance`` only on the pairs that bound cannot
rule out, so they return exactly the pairs a query of every pair would, and a query where
nothing is near makes no fcl call.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol

import fcl
import numpy as np
import pinocchio as pin
from qtree_scene.scene import ObjectSpec

from stpik_motion_planner.kernels import replay_candidates, scene_candidates, self_candidates

_REQUEST = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)
_NO_DISTANCE = sys.float_info.max  # min_distance of an empty fcl.DistanceResult [m]
# Added to a probe's bounding radius before the cull of SceneWorld.probe_hits, so that rounding
# of the probe's placement can only let more objects through to fcl.distance [m].
PROBE_SLACK_M = 1e-6
# The result argument of the fcl.distance calls whose return value only is read: fcl.distance
# updates a result (nearest points, geometries converted to Python) only when its min_distance
# is larger than the pair's, never from -inf (#28: that update cost as much as a far pair).
_UNREAD = fcl.DistanceResult(-math.inf)
_PROBE_INDEX: dict[int, np.ndarray] = {}  # count -> the body indices 0 … count − 1 of a cull


def _probe_index(count: int) -> np.ndarray:
    """Indices 0 … ``count`` − 1 (int64, (count,)): the probes of a cull as bodies."""
    index = _PROBE_INDEX.get(count)
    if index is None:
        index = _PROBE_INDEX.setdefault(count, np.arange(count, dtype=np.int64))
    return index


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
        # Per object (manager order): centre [m] (O, 3), yaw cos/sin (O,), half extents [m]
        # (O, 3) of a box around it in its own frame, for the cheap lower bounds of
        # RobotBodies.scene_proximities.
        specs = list(self.objects.values())
        self.specs = specs  # the objects in manager order (index = object index of the culls)
        self.index_of = {obj: i for i, obj in enumerate(specs)}  # object -> its index
        # Logs of probe_hits: the sampler memo's lists, an answer's footprint (.footprint).
        self.recorders: list[QueryRecorder] = []
        self.ids = [obj.id for obj in specs]
        self.centres = np.array([obj.position for obj in specs], dtype=float).reshape(-1, 3)
        self.cos = np.array([math.cos(obj.yaw) for obj in specs], dtype=float)
        self.sin = np.array([math.sin(obj.yaw) for obj in specs], dtype=float)
        self.half = np.array([cull_half_extents(obj) for obj in specs], dtype=float).reshape(-1, 3)
        self.bodies = self._keep
        self._zero_rows = np.zeros(len(specs), dtype=np.int64)  # a probe query's rows (body 0)

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

    def probe_hits(
        self,
        body: fcl.CollisionObject,
        centre: np.ndarray,
        radius: float,
        threshold: float,
        geometry: fcl.CollisionGeometry | None = None,
    ) -> list[str]:
        """Ids of the objects closer than ``threshold`` [m] to ``body`` (placed), whose points
        all lie within ``radius`` [m] of ``centre`` [m] (3,) in the world frame. ``geometry``:
        the body's geometry, kept with its pose by the recorders (:mod:`.footprint`).

        The same set as the ids of :meth:`clearance` (#28: the broad-phase manager called a
        Python callback per object near the probe's AABB): the lower bound of
        :func:`.kernels.scene_candidates` (the sphere against a box around each object) rules
        the far objects out, the others get the ``fcl.distance(object, probe)`` the manager's
        callback computes, in the manager's argument order, so each distance is the same.
        One probe of :meth:`cull_probes` then :meth:`probe_result`.
        """
        centres = np.ascontiguousarray(centre, dtype=float).reshape(1, 3)
        radii = np.array([radius + PROBE_SLACK_M])
        _, objects = self._cull(centres, radii, threshold)
        probe = None if geometry is None or not self.recorders else (geometry, body.getTransform())
        return self._probe(centres, radii, 0, threshold, objects.tolist(), body, probe)

    def cull_probes(self, centres: np.ndarray, radii: np.ndarray, threshold: float) -> ProbeCull:
        """The cull of :meth:`probe_hits` for P probes in one :func:`.kernels.scene_candidates`
        call (#28: the hand's parts, one call per pose instead of one per part).

        The kernel bounds each (probe, object) pair on its own, so probe i's candidates are the
        objects, in the same order, that a cull of probe i alone lets through.

        Args:
            centres: the probes' bounding-sphere centres in the world frame [m] (P, 3),
                C-contiguous.
            radii: their radii, :data:`PROBE_SLACK_M` included [m] (P,).
            threshold: the probes' distance threshold [m].
        """
        rows, objects = self._cull(centres, radii, threshold)
        candidates: list[list[int]] = [[] for _ in range(len(radii))]
        for row, obj in zip(rows.tolist(), objects.tolist(), strict=True):
            candidates[row].append(obj)
        return ProbeCull(centres, radii, threshold, candidates)

    def probe_result(
        self,
        cull: ProbeCull,
        index: int,
        body: fcl.CollisionObject,
        probe: tuple[fcl.CollisionGeometry, fcl.Transform] | None,
    ) -> list[str]:
        """Ids of the objects closer than ``cull.threshold`` [m] to probe ``index`` of ``cull``
        (:meth:`cull_probes`), ``body`` (placed): what :meth:`probe_hits` of that probe alone
        gives, and logs the same query, with ``probe`` (its geometry and pose) if given: the log
        keeps the pose object itself, so the caller must not change it afterwards.
        """
        objects = cull.objects[index]
        return self._probe(cull.centres, cull.radii, index, cull.threshold, objects, body, probe)

    def _cull(
        self, centres: np.ndarray, radii: np.ndarray, threshold: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """:func:`.kernels.scene_candidates` of probes ``centres`` [m] (P, 3), ``radii`` [m]
        (P,) against every object (exclusive ``threshold`` [m]): (probe rows, object indices).
        """
        return scene_candidates(
            centres,
            radii,
            _probe_index(len(radii)),
            self.centres,
            self.cos,
            self.sin,
            self.half,
            threshold,
            False,
        )

    def _probe(
        self,
        centres: np.ndarray,
        radii: np.ndarray,
        index: int,
        threshold: float,
        objects: list[int],
        body: fcl.CollisionObject,
        probe: tuple[fcl.CollisionGeometry, fcl.Transform] | None,
    ) -> list[str]:
        """The narrow phase of probe ``index`` of a cull (centres [m] (P, 3), radii [m] (P,)):
        ``fcl.distance(object, body)`` of each candidate of ``objects``, in their order, in the
        manager's argument order; logs the query (one body: row ``index`` of the cull) to every
        recorder. Returns the ids of the objects closer than ``threshold`` [m].
        """
        keep = self._keep
        near = [o for o in objects if fcl.distance(keep[o], body, _REQUEST, _UNREAD) < threshold]
        if self.recorders:
            specs = self.specs
            query = SceneQuery(
                centres[index : index + 1],
                radii[index : index + 1],
                threshold,
                False,
                self._zero_rows[: len(objects)],
                tuple([specs[o] for o in objects]),
                hits=tuple([specs[o] for o in near]),
                probe=probe,
            )
            for log in self.recorders:
                log.append(query)
        ids = self.ids
        return [ids[o] for o in near]


class ProbeCull(NamedTuple):
    """The cull of P probes against one :class:`SceneWorld` (:meth:`SceneWorld.cull_probes`).

    Attributes:
        centres: the probes' bounding-sphere centres [m] (P, 3).
        radii: their radii, :data:`PROBE_SLACK_M` included [m] (P,).
        threshold: the probes' distance threshold [m].
        objects: per probe, the indices of the objects its cull lets through, ascending.
    """

    centres: np.ndarray
    radii: np.ndarray
    threshold: float
    objects: list[list[int]]


class ProbeSet:
    """Rigid probes moved together (the hand's parts at one EE pose), each a persistent fcl
    object with a bounding sphere in the probes' own frame, for :meth:`SceneWorld.cull_probes`.

    Attributes:
        names: the probes' names, in the order of the mapping given.
        geometries: their fcl geometries (P).
        bodies: their fcl objects, placed by :meth:`place` (P).
        radii: their bounding radii plus :data:`PROBE_SLACK_M` [m] (P,).
    """

    def __init__(
        self,
        geometries: Mapping[str, fcl.CollisionGeometry],
        spheres: Mapping[str, tuple[np.ndarray, float]],
    ) -> None:
        """Args:
        geometries: name -> geometry in the probes' frame.
        spheres: name -> bounding sphere in that frame: centre [m] (3,), radius [m].
        """
        self.names = list(geometries)
        self.geometries = [geometries[name] for name in self.names]
        self.bodies = [fcl.CollisionObject(g, fcl.Transform()) for g in self.geometries]
        self._centres = [spheres[name][0] for name in self.names]
        self.radii = np.array([spheres[name][1] + PROBE_SLACK_M for name in self.names])

    def __len__(self) -> int:
        return len(self.names)

    def place(
        self, rotation: np.ndarray, translation: np.ndarray, transform: fcl.Transform
    ) -> np.ndarray:
        """Place every probe at the pose ``transform`` (= ``rotation`` (3, 3), ``translation``
        [m] (3,)); returns the bounding spheres' world centres [m] (P, 3).

        Each centre is ``rotation @ centre + translation`` of its own (3,) centre, the
        arithmetic of a probe placed alone (so the culls see the same numbers).
        """
        centres = np.empty((len(self.names), 3))
        for i, (body, centre) in enumerate(zip(self.bodies, self._centres, strict=True)):
            body.setTransform(transform)
            centres[i] = rotation @ centre + translation
        return centres


def probe_distance(obj: ObjectSpec, geometry: fcl.CollisionGeometry, pose: fcl.Transform) -> float:
    """``fcl.distance`` [m] of ``obj`` (as a :class:`SceneWorld` holds it) to a probe of
    ``geometry`` at ``pose``: the call :meth:`SceneWorld.probe_hits` makes.
    """
    body = fcl.CollisionObject(object_geometry(obj), object_transform(obj))
    return fcl.distance(body, fcl.CollisionObject(geometry, pose), _REQUEST, _UNREAD)


def cull_half_extents(obj: ObjectSpec) -> tuple[float, float, float]:
    """Half sizes [m] of the box in the object's frame containing it that the scene queries'
    culls bound distances with (cylinder: r, r, h/2; :func:`.kernels.scene_candidates`).
    """
    if obj.shape == 'cylinder':
        return (obj.radius, obj.radius, obj.height / 2)
    sx, sy, sz = obj.size
    return (0.5 * float(sx), 0.5 * float(sy), 0.5 * float(sz))


def _probe_first(p: Proximity) -> Proximity:
    if p.name_b == 'probe':
        return Proximity(p.name_b, p.name_a, p.distance, p.point_b, p.point_a)
    return p


class RobotBodies:
    """The arm's collision primitives (from the Pinocchio ``GeometryModel``) as fcl objects.

    Self-hit queries cover exactly the pairs of ``self_pairs``
    (``Jaco2Model.self_collision_pairs``), plus the carried object against every link but the
    hand that holds it (link 7, fingers); the pair lists are rebuilt on attach / detach.
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
        self._result = fcl.DistanceResult()  # see _fresh_result
        # What is carried (object, pose in the EE frame, settle), hashable: None when nothing.
        self.attach_key: tuple | None = None
        self.attached_radius = 0.0  # bounding radius of the carried object [m]
        self._attached_offset = np.eye(4)  # the carried object's pose in the EE frame
        # Bottom-shortened body of the carried object used against static bodies only, and its
        # centre above the main body's along the object's z [m] (``settle_vs_static_only``).
        self._attached_support: fcl.CollisionObject | None = None
        self._support_delta = 0.0
        self._transforms.append(fcl.Transform())  # the carried object's
        self._placed = np.zeros(len(self.bodies) + 1, dtype=bool)
        # World placement of every body, homogeneous [m] (G + 1, 4, 4), last: the carried object.
        self._placements = np.tile(np.eye(4), (len(self.bodies) + 1, 1, 1))
        # Active logs of scene queries (:class:`SceneQuery`), appended to by every scene query
        # (:meth:`scene_proximities`, :meth:`scene_clear`): RobustStpik's replay memo.
        self.recorders: list[QueryRecorder] = []  # logs of the scene queries (memos, footprints)
        self._build_managers()

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
        self._pair_a = np.array([i for i, _ in pairs], dtype=np.int64)
        self._pair_b = np.array([j for _, j in pairs], dtype=np.int64)
        self._pair_names = [(names[i], names[j]) for i, j in pairs]
        self._objects = [*self.bodies, self.attached]
        self._all_radii = np.ascontiguousarray(np.r_[self._radii, self.attached_radius], float)
        # Bodies checked against the scene: every link but the base and link 1, and the carried
        # object.
        self._scene_index = np.array(
            [i for i, n in enumerate(self.link_names) if _short(n) not in _NOT_VS_SCENE]
            + ([len(self.bodies)] if self.attached is not None else []),
            dtype=np.int64,
        )
        self._scene_names = [names[i] for i in self._scene_index]
        self._scene_radii = np.ascontiguousarray(self._all_radii[self._scene_index])

    def attach(
        self,
        obj: ObjectSpec,
        transform_obj_to_ee: pin.SE3,
        settle_m: float = 0.0,
        settle_top_m: float | None = None,
        settle_vs_static_only: bool = False,
    ) -> None:
        """Carry ``obj`` rigidly at ``transform_obj_to_ee`` (its pose in the EE frame).

        Args:
            obj: the grasped object (upright: its z axis is the one shortened).
            transform_obj_to_ee: pose of the object in the EE frame.
            settle_m: the object's collision body is this much shorter at its bottom [m], so
                that setting it down on the table is not a collision (sideways margins stay).
            settle_top_m: this much shorter at its top [m]; None: ``settle_m`` (the planner's
                symmetric body). The closed loop passes 0: the top end is checked exactly (#29).
            settle_vs_static_only: shorten the bottom against *static* bodies only (the table
                it is set down on); movable and placed objects meet the whole bottom (the
                closed loop, #29: 20 mm of the carried bottom went into a placed object unseen).
        """
        top_m = settle_m if settle_top_m is None else settle_top_m
        full = obj.height if obj.shape == 'cylinder' else obj.size[2]
        geometry = _carried_geometry(obj, max(full - settle_m - top_m, 1e-3))
        self._support_delta = 0.0  # the support body's centre above the main one's [m]
        self._attached_support = None
        if settle_vs_static_only:  # main body: only the top cut; support body: both cuts
            support = fcl.CollisionObject(geometry, fcl.Transform())
            self.names[id(geometry)] = 'attached'
            self._attached_support = support
            geometry = _carried_geometry(obj, max(full - top_m, 1e-3))
            self._support_delta = 0.5 * settle_m
            settle_m_main = 0.0
        else:
            settle_m_main = settle_m
        self.names[id(geometry)] = 'attached'
        self._attached_geometry = geometry
        across = obj.radius if obj.shape == 'cylinder' else 0.5 * math.hypot(*obj.size[:2])
        self.attached_radius = math.hypot(across, full / 2)
        self.attached = fcl.CollisionObject(geometry, fcl.Transform())
        # The body's centre: half the difference of the two cuts above the object's centre.
        shift = np.eye(4)
        shift[2, 3] = 0.5 * (settle_m_main - top_m)
        self._attached_offset = np.array(transform_obj_to_ee.homogeneous) @ shift
        self.attach_key = (
            obj,
            transform_obj_to_ee.homogeneous.tobytes(),
            float(settle_m),
            float(top_m),
            bool(settle_vs_static_only),
        )
        self._build_managers()

    def detach(self) -> None:
        """Stop carrying the attached object."""
        if self.attached is not None:
            self.attached = None
            self._attached_support = None
            self.attach_key = None
            self._build_managers()

    def place(self, placements: np.ndarray, world_ee: np.ndarray) -> None:
        """Move the bodies to their world placements and the carried object with the EE.

        Only the centres are stored here; a body's fcl transform is set when a query first
        needs it (most bodies are far from everything and never reach fcl).

        Args:
            placements: world placement of each body, homogeneous [m] (G, 4, 4)
                (:func:`.kernels.chain_placements`).
            world_ee: the EE pose in the world frame, homogeneous [m] (4, 4).
        """
        count = len(self.bodies)
        self._placements[:count] = placements
        self._centres[:count] = placements[:, :3, 3]
        self._placed[:] = False
        if self.attached is not None:
            world_obj = world_ee @ self._attached_offset
            self._placements[count] = world_obj
            self._centres[count] = world_obj[:3, 3]

    @property
    def centres(self) -> np.ndarray:
        """Centre of every body [m] (G + 1, 3) at the last :meth:`place` (last row: the carried
        object, valid while attached).
        """
        return self._centres

    def _fresh_result(self) -> fcl.DistanceResult:
        """This instance's reused DistanceResult, emptied (#28: building one per query costs
        about as much as a far pair's distance). fcl.distance keeps the smaller of its result
        and the stored minimum, hence the reset; the nearest points are new arrays each time.
        """
        self._result.min_distance = _NO_DISTANCE
        return self._result

    def _body(self, index: int) -> fcl.CollisionObject:
        """The fcl object of body ``index`` (the carried object: ``len(bodies)``), placed."""
        if not self._placed[index]:
            placement = self._placements[index]
            tf = self._transforms[index]
            tf.setRotation(placement[:3, :3])
            tf.setTranslation(placement[:3, 3])
            self._objects[index].setTransform(tf)
            self._placed[index] = True
        return self._objects[index]

    def _scene_body(self, index: int, obj: ObjectSpec) -> fcl.CollisionObject:
        """The fcl object of body ``index`` against scene object ``obj``: the carried object's
        bottom-shortened support body against a static one (``settle_vs_static_only``).
        """
        body = self._body(index)
        support = self._attached_support
        if support is None or index != len(self.bodies) or obj.role != 'static':
            return body
        placement = self._placements[index]
        tf = fcl.Transform(
            placement[:3, :3], placement[:3, 3] + placement[:3, 2] * self._support_delta
        )
        support.setTransform(tf)
        return support

    def self_proximities(self, threshold: float) -> list[Proximity]:
        """Pairs of the self-hit list closer than ``threshold`` [m].

        A pair whose bounding spheres are ``threshold`` apart or more cannot be closer, so only
        the others reach ``fcl.distance`` (the result is the same set as a query of every pair).
        """
        a, b = self._pair_a, self._pair_b
        if a.size == 0:
            return []
        found: list[Proximity] = []
        for k in self_candidates(self._centres, self._all_radii, a, b, threshold, False):
            result = self._fresh_result()
            body_a, body_b = self._body(int(a[k])), self._body(int(b[k]))
            distance = fcl.distance(body_a, body_b, _REQUEST, result)
            if distance < threshold:
                name_a, name_b = self._pair_names[k]
                pa, pb = result.nearest_points
                found.append(Proximity(name_a, name_b, distance, pa, pb))
        return found

    def self_clear(self, threshold: float) -> bool:
        """True when every self-hit pair is more than ``threshold`` [m] apart (validity checks).

        Same pairs, bounding-sphere cull and ``fcl.distance`` as :meth:`self_proximities`, but
        stops at the first pair at or below ``threshold`` and builds no :class:`Proximity`.
        """
        a, b = self._pair_a, self._pair_b
        if a.size == 0:
            return True
        for k in self_candidates(self._centres, self._all_radii, a, b, threshold, True):
            result = self._fresh_result()
            body_a, body_b = self._body(int(a[k])), self._body(int(b[k]))
            if fcl.distance(body_a, body_b, _REQUEST, result) <= threshold:
                return False
        return True

    def _scene_candidates(
        self, scene: SceneWorld, threshold: float, inclusive: bool
    ) -> tuple[np.ndarray, np.ndarray]:
        """(rows into the scene-checked bodies, object indices) of the pairs whose lower bound
        is below ``threshold`` [m] (at or below with ``inclusive``): the distance from the
        body's centre to a box around the object in the object's frame, minus the body's
        bounding radius (:func:`.kernels.scene_candidates`); the base is skipped.
        """
        return scene_candidates(
            self._centres,
            self._all_radii,
            self._scene_index,
            scene.centres,
            scene.cos,
            scene.sin,
            scene.half,
            threshold,
            inclusive,
        )

    def _record(
        self,
        scene: SceneWorld,
        threshold: float,
        inclusive: bool,
        culled: tuple[np.ndarray, np.ndarray],
        hits: list[int],
    ) -> None:
        """Log one query to every active recorder (:class:`SceneQuery`): its cull ``culled``
        (:meth:`_scene_candidates`) and the indices of the objects it found within reach.
        """
        rows, objects = culled
        specs = scene.specs
        query = SceneQuery(
            self._centres[self._scene_index],
            self._scene_radii,
            threshold,
            inclusive,
            rows,
            tuple([specs[o] for o in objects.tolist()]),
            hits=tuple({specs[o]: None for o in hits}),
        )
        for log in self.recorders:
            log.append(query)

    def scene_clear(self, scene: SceneWorld, threshold: float) -> bool:
        """True when every (body, scene object) pair is more than ``threshold`` [m] apart.

        Same bound and ``fcl.distance`` as :meth:`scene_proximities`, first hit stops it.
        """
        culled = self._scene_candidates(scene, threshold, True)
        index = self._scene_index
        for body, obj in zip(*culled, strict=True):
            result = self._fresh_result()
            robot = self._scene_body(int(index[body]), scene.specs[obj])
            if fcl.distance(robot, scene.bodies[obj], _REQUEST, result) <= threshold:
                if self.recorders:
                    self._record(scene, threshold, True, culled, [int(obj)])
                return False
        if self.recorders:
            self._record(scene, threshold, True, culled, [])
        return True

    def scene_proximities(self, scene: SceneWorld, threshold: float) -> list[Proximity]:
        """(body, scene object) pairs closer than ``threshold`` [m]; the base is skipped.

        Lower bound per pair (numpy, every pair at once): the distance from the body's centre
        to a box around the object in the object's frame, minus the body's bounding radius.
        Only pairs whose bound is below ``threshold`` reach ``fcl.distance``, so the result
        is the same set as a query of every pair.
        """
        culled = self._scene_candidates(scene, threshold, False)
        index = self._scene_index
        found: list[Proximity] = []
        hits: list[int] = []
        for body, obj in zip(*culled, strict=True):
            result = self._fresh_result()
            robot = self._scene_body(int(index[body]), scene.specs[obj])
            distance = fcl.distance(robot, scene.bodies[obj], _REQUEST, result)
            if distance < threshold:
                pa, pb = result.nearest_points
                found.append(Proximity(self._scene_names[body], scene.ids[obj], distance, pa, pb))
                hits.append(int(obj))
        if self.recorders:
            self._record(scene, threshold, False, culled, hits)
        return found


def _carried_geometry(obj: ObjectSpec, length: float) -> fcl.CollisionGeometry:
    """The carried object's fcl geometry, ``length`` [m] along its axis."""
    if obj.shape == 'cylinder':
        return fcl.Cylinder(obj.radius, length)
    sx, sy, _ = obj.size
    return fcl.Box(sx, sy, length)


@dataclass(frozen=True)
class SceneQuery:
    """One scene query's cull, as :func:`.kernels.scene_candidates` saw it (#28 replay memo).

    A query's result depends on the scene only through the pairs its cull lets through (then
    ``fcl.distance`` of those objects): the same robot bodies give the same result in any scene
    whose cull lets through the same (body, object) pairs in the same order.

    Attributes:
        centres: centres of the scene-checked bodies [m] (K, 3); radii: their radii [m] (K,).
        threshold: the query's distance threshold [m]; inclusive: ``<=`` instead of ``<``.
        rows: rows into the scene-checked bodies of the pairs let through (n,).
        objects: the object of each of those pairs (n,).
        hits: the objects the query found within ``threshold`` (its result depends on them
            only; a ``scene_clear`` stops at its first).
        probe: a probe query's geometry and pose (:meth:`SceneWorld.probe_hits`), if given.
    """

    centres: np.ndarray
    radii: np.ndarray
    threshold: float
    inclusive: bool
    rows: np.ndarray
    objects: tuple[ObjectSpec, ...]
    hits: tuple[ObjectSpec, ...] = ()
    probe: tuple[fcl.CollisionGeometry, fcl.Transform] | None = None


class QueryRecorder(Protocol):
    """What the scene queries log to: a :class:`QueryList` (the memos) or a
    :class:`~.footprint.Footprint` (an answer's reuse after a scene change).
    """

    def append(self, query: SceneQuery, /) -> None:
        """Record one query."""

    def extend(self, queries: Iterable[SceneQuery], /) -> None:
        """Record the queries of a result reused from a memo."""

    def lose(self, why: str, /) -> None:
        """Note that a part of the computation made queries that were not recorded."""


class QueryList(list[SceneQuery]):
    """The scene queries of one computation (a memo's log); ``complete`` is False once a part
    of it was reused from a memo that kept no queries (then the log proves nothing elsewhere).
    """

    complete = True

    def lose(self, why: str, /) -> None:
        """Note that queries were not recorded (``why`` is for the footprint's log only)."""
        self.complete = False


class QueryLog:
    """The scene queries of one computation, stacked for :meth:`replays_in` (#28 replay memo).

    Attributes:
        queries: the :class:`SceneQuery` list it was built from (n).
        replayable: False when the queries did not cull as many bodies each (then
            :meth:`replays_in` is False: the computation is reused in its own scene only).
    """

    def __init__(self, queries: list[SceneQuery]) -> None:
        self.queries = queries
        size = len(queries[0].radii) if queries else 0
        self.replayable = all(len(q.radii) == size for q in queries)
        self._radii = np.zeros((len(queries), size))
        self._centres = np.zeros((len(queries), size, 3))
        if self.replayable:
            for i, q in enumerate(queries):
                self._radii[i] = q.radii
                self._centres[i] = q.centres
        self._thresholds = np.array([q.threshold for q in queries], dtype=float)
        self._inclusive = np.array([q.inclusive for q in queries], dtype=np.bool_)
        self._query = np.concatenate(
            [np.full(len(q.rows), i, dtype=np.int64) for i, q in enumerate(queries)]
            + [np.zeros(0, dtype=np.int64)]
        )
        self._rows = np.concatenate([q.rows for q in queries] + [np.zeros(0, dtype=np.int64)])
        objects = [spec for q in queries for spec in q.objects]
        self._specs = list(dict.fromkeys(objects))  # the distinct objects met, first-met order
        number = {spec: i for i, spec in enumerate(self._specs)}
        self._spec_index = np.array([number[spec] for spec in objects], dtype=np.int64)

    def __len__(self) -> int:
        return len(self.queries)

    def replays_in(self, scene: SceneWorld) -> bool:
        """True when every query's cull in ``scene`` lets through exactly the pairs it did, in
        the same order (:func:`.kernels.replay_candidates`: each query culled as it was).
        """
        if not self.replayable:
            return False
        index = scene.index_of
        where = np.array([index.get(spec, -1) for spec in self._specs], dtype=np.int64)
        if np.any(where < 0):  # an object met is not in this scene (or not the same)
            return False
        query, rows, objects = replay_candidates(
            self._centres,
            self._radii,
            self._thresholds,
            self._inclusive,
            scene.centres,
            scene.cos,
            scene.sin,
            scene.half,
        )
        return (
            np.array_equal(query, self._query)
            and np.array_equal(rows, self._rows)
            and np.array_equal(objects, where[self._spec_index])
        )


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


def _fcl_geometry(geometry: Any) -> fcl.CollisionGeometry:
    if hasattr(geometry, 'halfLength'):
        return fcl.Cylinder(float(geometry.radius), 2.0 * float(geometry.halfLength))
    if hasattr(geometry, 'halfSide'):
        return fcl.Box(*(2.0 * np.asarray(geometry.halfSide)))
    if hasattr(geometry, 'radius'):
        return fcl.Sphere(float(geometry.radius))
    raise TypeError(f'unsupported collision geometry {type(geometry).__name__}')
