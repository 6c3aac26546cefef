"""Independent trajectory verifier: is a joint trajectory physically valid in a scene? No ROS.

It shares nothing with the planner's checks (python-fcl worlds of :mod:`.collision`, the STPIK
tasks) beyond the robot model of ``jaco2_description``: the collision queries run in C++ through
Pinocchio's own coal back-end (``pin.computeCollisions``) on a private ``GeometryModel`` that
holds the arm's primitives, the scene objects and the carried object.

What is checked, at every densified configuration:

* joint limits of the URDF's *revolute* joints (2, 4, 6); the continuous joints 1, 3, 5, 7 have
  none;
* self-collision of every pair of ``Jaco2Model.self_collision_pairs``, plus the carried object
  against every link except the hand (link 7 and the fingers, which hold it);
* scene collisions of every link and of the carried object against every scene object. The
  base (it stands on the table) is not checked against static bodies. The whole carried object
  is checked against every other object; only against the *static* bodies it is picked up from
  and set down on (the table) is its body shortened at its bottom by
  :attr:`TrajectoryVerifier.support_tolerance_m`, so that lifting it from / setting it down on
  a surface within the tracking tolerance is not a collision (#29: the bottom 12 mm were
  unchecked against everything, and a neighbour grazing the carried object 3 mm deep passed).

A pair counts as colliding below ``clearance_m``; the planner verifies with
:data:`STOP_CLEARANCE_M`, the distance at which the executor stops the arm, so a returned
trajectory is proven to keep at least that clearance on every pair, between samples too.

The carried object stands at its initial pose until ``grasp_index``, moves rigidly with the
end-effector from ``grasp_index`` to ``release_index``, and stands where it was released
afterwards (where the simulator leaves it).

Densification: between two trajectory samples the joints move on a straight line Δq. A point p
of a body carried by joint i moves at most m_g = Σ_{j ≤ i} |Δq_j| · ‖p − o_j‖, and ‖p − o_j‖ is
bounded by a configuration-independent reach D_{j,g} (the joint-origin chain lengths from joint j
to the body's joint plus the body's own bounding radius). Every sample is checked with exact
distances of every pair. On a segment, pair k's distance changes by at most m_k per unit of the
segment parameter t, so a pair at distance d is provably free on an interval of t of length
d / m_k around any checked configuration (conservative advancement). A pair whose intervals from
the two ends meet is free on the whole segment; the others are marched from the start, checking
their exact distances at the smallest proven-free advance, and never at a finer step than
``resolution_m`` (1 cm) of their motion: where nothing is proven free, no point of a body that
could touch anything moves more than 1 cm between two checks.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from jaco2_description.model import ARM_JOINTS, EE_FRAME, Jaco2Model, urdf_text
from qtree_scene.scene import ObjectSpec

RESOLUTION_M = 0.01  # largest motion of any body point between two checks [m]
SUPPORT_TOLERANCE_M = 0.012  # bottom slice of the carried object not checked vs statics [m]
# The executor's stop distance: the planner's obstacle_min_distance_m (5 mm) less the closed
# loop's margin_tolerance_m (2 mm) [m].
STOP_CLEARANCE_M = 0.003
# ``min_distance_m`` is exact where it is below this [m] (above, a lower bound of it).
EXACT_BELOW_M = 0.02
_HAND_KEYS = ('link_7', 'link_finger')


@dataclass(frozen=True)
class Carried:
    """The object the trajectory grasps and places.

    Attributes:
        obj: the object at its initial pose (before the grasp).
        grasp_index: trajectory index where it is attached to the hand.
        release_index: trajectory index where it is released (≥ ``grasp_index``).
    """

    obj: ObjectSpec
    grasp_index: int
    release_index: int


@dataclass(frozen=True)
class Violation:
    """The worst instance of one kind of violation on one pair (or joint).

    Attributes:
        kind: ``'joint_limit'``, ``'self_collision'`` or ``'scene_collision'``.
        name_a: joint name, or robot body (link name or ``'carried'``).
        name_b: ``'lower'``/``'upper'``, or the other body (link or object id).
        index: fractional trajectory index of the worst configuration (e.g. 12.4: 40 % of the
            way from sample 12 to 13).
        value: joint-limit excess [rad], or signed distance [m] (< 0: penetration depth).
    """

    kind: str
    name_a: str
    name_b: str
    index: float
    value: float

    def __str__(self) -> str:
        if self.kind == 'joint_limit':
            return f'{self.name_a} beyond its {self.name_b} limit by {self.value:.3f} rad'
        return (
            f'{self.kind.replace("_", " ")} {self.name_a} / {self.name_b} at index '
            f'{self.index:.2f}: distance {self.value * 1000:.1f} mm'
        )


@dataclass(kw_only=True)
class VerificationReport:
    """Outcome of :meth:`TrajectoryVerifier.verify`.

    Attributes:
        checked: number of configurations checked (trajectory samples + densified ones).
        max_gap_m: largest bound on any body point's motion between two checks [m].
        limit_violations: worst excess per (joint, side).
        self_collisions: worst distance per colliding pair of links (or carried/link).
        scene_collisions: worst distance per colliding (body, object) pair.
        min_distance_m: smallest pair distance at the trajectory's samples [m], exact below
            :data:`EXACT_BELOW_M` (else a lower bound above it); between them every pair is
            proven to stay above ``clearance_m`` when :attr:`ok`.
    """

    checked: int = 0
    min_distance_m: float = math.inf
    max_gap_m: float = 0.0
    limit_violations: list[Violation] = field(default_factory=list)
    self_collisions: list[Violation] = field(default_factory=list)
    scene_collisions: list[Violation] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when nothing is violated."""
        return not (self.limit_violations or self.self_collisions or self.scene_collisions)

    @property
    def violations(self) -> list[Violation]:
        """Every violation, limits first."""
        return [*self.limit_violations, *self.self_collisions, *self.scene_collisions]

    def summary(self) -> str:
        """One line: 'ok (N checks)' or the first violations."""
        if self.ok:
            return f'ok ({self.checked} configurations checked)'
        shown = '; '.join(str(v) for v in self.violations[:3])
        more = len(self.violations) - 3
        return shown + (f'; … ({more} more)' if more > 0 else '')


def revolute_limits() -> dict[str, tuple[float, float]]:
    """Position limits [rad] of the URDF's revolute arm joints (continuous joints: none)."""
    root = ET.fromstring(urdf_text())
    out = {}
    for joint in root.iter('joint'):
        name = joint.get('name')
        limit = joint.find('limit')
        if name in ARM_JOINTS and joint.get('type') == 'revolute' and limit is not None:
            out[name] = (float(limit.attrib['lower']), float(limit.attrib['upper']))
    return out


def _coal_geometry(obj: ObjectSpec, shorten_bottom: float = 0.0) -> tuple[object, float]:
    """Coal primitive of ``obj`` and its centre's z offset [m] when shortened at the bottom."""
    height = obj.height if obj.shape == 'cylinder' else obj.size[2]
    cut = min(shorten_bottom, 0.5 * height)
    short = max(height - cut, 1e-4)
    if obj.shape == 'cylinder':
        return coal.Cylinder(float(obj.radius), float(short)), cut / 2
    sx, sy, _ = obj.size
    return coal.Box(float(sx), float(sy), float(short)), cut / 2


def object_pose(obj: ObjectSpec) -> pin.SE3:
    """World pose of a scene object (yaw about z, centre)."""
    return pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, obj.yaw), np.asarray(obj.position, dtype=float))


def _bounding_radius(geometry: Any) -> float:
    if isinstance(geometry, coal.Cylinder):
        return math.hypot(geometry.radius, geometry.halfLength)
    if isinstance(geometry, coal.Box):
        return float(np.linalg.norm(geometry.halfSide))
    if isinstance(geometry, coal.Sphere):
        return float(geometry.radius)
    raise TypeError(f'unsupported geometry {type(geometry).__name__}')


class TrajectoryVerifier:
    """Checks joint trajectories of the j2s7s300 against scenes (see the module docstring).

    Attributes:
        resolution_m: largest body-point motion between two checks [m].
        support_tolerance_m: bottom slice of the carried object left unchecked [m].
        clearance_m: a pair closer than this counts as colliding [m] (0: contact only).
    """

    def __init__(
        self,
        robot: Jaco2Model | None = None,
        resolution_m: float = RESOLUTION_M,
        support_tolerance_m: float = SUPPORT_TOLERANCE_M,
        clearance_m: float = 0.0,
    ) -> None:
        self.robot = robot if robot is not None else Jaco2Model()
        self.resolution_m = resolution_m
        self.support_tolerance_m = support_tolerance_m
        self.clearance_m = clearance_m
        self.model = self.robot.model
        self.data = self.model.createData()
        self.links = [g.name.rsplit('_', 1)[0] for g in self.robot.geometry_model.geometryObjects]
        limits = revolute_limits()
        self._limited = [i for i, n in enumerate(ARM_JOINTS) if n in limits]
        self._lower = np.array([limits[ARM_JOINTS[i]][0] for i in self._limited])
        self._upper = np.array([limits[ARM_JOINTS[i]][1] for i in self._limited])
        self._ee = self.model.getFrameId(EE_FRAME)
        self._ee_joint = self.model.frames[self._ee].parentJoint
        # Chain length between consecutive joint origins: ‖o_{k+1} − o_k‖ [m], index k = 1..7.
        chain = np.zeros(self.model.njoints + 1)
        for k in range(1, self.model.njoints):
            chain[k] = np.linalg.norm(self.model.jointPlacements[k].translation)
        self._chain = chain

    def reach(self, joint: int, placement: pin.SE3, geometry: Any) -> np.ndarray:
        """D_{j,g} [m] (7,): bound on ‖p − o_j‖ for every point p of ``geometry`` on ``joint``."""
        own = float(np.linalg.norm(placement.translation)) + _bounding_radius(geometry)
        out = np.zeros(7)
        for j in range(1, joint + 1):  # joint index j (1-based); o_j to o_joint along the chain
            out[j - 1] = float(np.sum(self._chain[j + 1 : joint + 1])) + own
        return out

    def _build(self, obstacles: list[ObjectSpec], carried: Carried | None, q_grasp, q_release):
        """Private GeometryModel, body names, pair reaches and kinds, and per phase (before /
        during / after the carry) the mask of the pairs it checks.
        """
        gm = pin.GeometryModel()
        robot_ids = []
        for g in self.robot.geometry_model.geometryObjects:
            robot_ids.append(gm.addGeometryObject(pin.GeometryObject(g)))
        names = list(self.links)
        reaches = [
            self.reach(g.parentJoint, g.placement, g.geometry)
            for g in self.robot.geometry_model.geometryObjects
        ]
        scene_ids, static = [], []
        for obj in obstacles:
            geometry, _ = _coal_geometry(obj)
            scene_ids.append(
                gm.addGeometryObject(
                    pin.GeometryObject(f'obj:{obj.id}', 0, 0, object_pose(obj), geometry)
                )
            )
            names.append(obj.id)
            reaches.append(np.zeros(7))
            static.append(obj.role == 'static')
        pairs: dict[str, list[tuple[int, int, str]]] = {'before': [], 'carry': [], 'after': []}
        for i, j in self.robot.self_collision_pairs:
            for members in pairs.values():
                members.append((robot_ids[i], robot_ids[j], 'self_collision'))
        for k, sid in enumerate(scene_ids):
            for r, rid in enumerate(robot_ids):
                if static[k] and names[r].endswith('link_base'):
                    continue
                for members in pairs.values():
                    members.append((rid, sid, 'scene_collision'))
        if carried is not None:
            pose0 = object_pose(carried.obj)
            short, lift = _coal_geometry(carried.obj, self.support_tolerance_m)
            lifted = pose0 * pin.SE3(np.eye(3), np.array([0.0, 0.0, lift]))
            full, _ = _coal_geometry(carried.obj)
            before = gm.addGeometryObject(pin.GeometryObject('carried_before', 0, 0, pose0, full))
            world_ee = self._ee_pose(q_grasp)
            joint_pose = self._joint_pose(q_grasp)
            on_joint = joint_pose.actInv(pose0)
            held = gm.addGeometryObject(
                pin.GeometryObject('carried', self._ee_joint, 0, on_joint, full)
            )
            on_joint_short = joint_pose.actInv(lifted)
            held_short = gm.addGeometryObject(
                pin.GeometryObject('carried_short', self._ee_joint, 0, on_joint_short, short)
            )
            released = self._ee_pose(q_release) * world_ee.actInv(pose0)
            after = gm.addGeometryObject(pin.GeometryObject('carried_after', 0, 0, released, full))
            names += [carried.obj.id, 'carried', 'carried', f'{carried.obj.id} (placed)']
            reaches.append(np.zeros(7))
            reaches.append(self.reach(self._ee_joint, on_joint, full))
            reaches.append(self.reach(self._ee_joint, on_joint_short, short))
            reaches.append(np.zeros(7))
            for r, rid in enumerate(robot_ids):
                pairs['before'].append((rid, before, 'scene_collision'))
                pairs['after'].append((rid, after, 'scene_collision'))
                if not any(key in names[r] for key in _HAND_KEYS):
                    pairs['carry'].append((held, rid, 'self_collision'))
            for k, sid in enumerate(scene_ids):  # the whole body, but on its support surfaces
                pairs['carry'].append((held_short if static[k] else held, sid, 'scene_collision'))
        # One symmetric activation map per phase; the model holds their union (one call instead
        # of one per pair), each phase checks the pairs of its mask.
        count = len(gm.geometryObjects)
        kinds: dict[tuple[int, int], str] = {}
        maps = {}
        for phase, members in pairs.items():
            active = np.zeros((count, count), dtype=bool)
            for a, b, kind in members:
                kinds.setdefault((min(a, b), max(a, b)), kind)
                active[a, b] = active[b, a] = True
            maps[phase] = active
        gm.setCollisionPairs(np.logical_or.reduce(list(maps.values())), True)
        first = np.array([p.first for p in gm.collisionPairs], dtype=int)
        second = np.array([p.second for p in gm.collisionPairs], dtype=int)
        masks = {phase: active[first, second] for phase, active in maps.items()}
        pair_kinds = [kinds[(min(a, b), max(a, b))] for a, b in zip(first, second, strict=True)]
        reach = self._pair_reach(gm, np.array(reaches).T)
        return gm, names, reach, pair_kinds, masks

    @staticmethod
    def _pair_reach(gm: pin.GeometryModel, reaches: np.ndarray) -> np.ndarray:
        """Per pair, D of the body that moves relative to the other, shape (7, P) [m].

        For two robot bodies on joints i ≤ k only joints i+1 … k change their distance (joints
        ≤ i move both rigidly), so the pair's relative motion over a segment is bounded by
        Σ_{i < j ≤ k} |Δq_j| D_{j, body on k}; a world-fixed body does not move.
        """
        joints = [g.parentJoint for g in gm.geometryObjects]
        out = np.zeros((7, len(gm.collisionPairs)))
        for p, pair in enumerate(gm.collisionPairs):
            a, b = pair.first, pair.second
            if joints[a] > joints[b]:
                a, b = b, a
            low = joints[a]  # 0 for a world-fixed body: every joint counts
            out[low:, p] = reaches[low:, b]
        return out

    def _ee_pose(self, q: np.ndarray) -> pin.SE3:
        pin.framesForwardKinematics(self.model, self.data, q)
        return pin.SE3(self.data.oMf[self._ee])

    def _joint_pose(self, q: np.ndarray) -> pin.SE3:
        pin.forwardKinematics(self.model, self.data, q)
        return pin.SE3(self.data.oMi[self._ee_joint])

    @staticmethod
    def motion_bounds(trajectory: np.ndarray, reaches: np.ndarray) -> np.ndarray:
        """Bound on the relative motion [m] of each pair over each segment, shape (N−1, P).

        Args:
            trajectory: joint angles [rad], shape (N, 7).
            reaches: per pair, D of its moving body [m], shape (7, P) (see ``_pair_reach``).
        """
        return np.abs(np.diff(trajectory, axis=0)) @ reaches

    def verify(
        self,
        trajectory: np.ndarray,
        obstacles: Iterable[ObjectSpec],
        carried: Carried | None = None,
    ) -> VerificationReport:
        """Check ``trajectory`` (N, 7) [rad] among ``obstacles`` (statics included).

        Args:
            trajectory: joint angles [rad], shape (N, 7), N ≥ 1.
            obstacles: every body standing in the scene during the motion (not the carried one).
            carried: the grasped object and where it is attached / released, or None.

        Raises:
            ValueError: wrong trajectory shape, non-finite values or carried indices outside it.
        """
        q = np.asarray(trajectory, dtype=float)
        if q.ndim != 2 or q.shape[1] != 7 or len(q) == 0:
            raise ValueError(f'trajectory must have shape (N, 7), N >= 1, got {q.shape}')
        if not np.all(np.isfinite(q)):
            raise ValueError('trajectory has non-finite values')
        if carried is not None and not (
            0 <= carried.grasp_index <= carried.release_index < len(q)
        ):
            raise ValueError(
                f'grasp/release indices {carried.grasp_index}/{carried.release_index} '
                f'outside the trajectory of {len(q)} samples'
            )
        grasp = carried.grasp_index if carried else len(q)
        release = carried.release_index if carried else len(q)
        gm, names, reaches, kinds, masks = self._build(
            list(obstacles), carried, q[min(grasp, len(q) - 1)], q[min(release, len(q) - 1)]
        )
        report = VerificationReport(checked=len(q))
        motion = self.motion_bounds(q, reaches)  # (N-1, P): relative motion of each pair [m]
        worst: dict[tuple[str, str, str], Violation] = {}

        def phase_at(t: float) -> str:
            return 'before' if t < grasp else ('carry' if t <= release else 'after')

        full = pin.GeometryData(gm)
        # Bounding sphere of every geometry about its frame's origin [m], pair members.
        radius = np.array([_bounding_radius(g.geometry) for g in gm.geometryObjects])
        first = np.array([p.first for p in gm.collisionPairs], dtype=int)
        second = np.array([p.second for p in gm.collisionPairs], dtype=int)
        # Per sample and pair: the largest motion bound of the two segments around it [m].
        padded = np.vstack(
            [np.zeros((1, motion.shape[1])), motion, np.zeros((1, motion.shape[1]))]
        )
        around = np.maximum(padded[:-1], padded[1:]) + self.clearance_m  # (N, P)
        cache: dict[int, np.ndarray] = {}
        # Geometries on the world (obstacles, the carried object before and after) never move:
        # their centres are read once; only those on a joint are read per sample (#28: reading
        # a placement out of Pinocchio costs about 1 µs, half the verifier's time went there).
        moving = [i for i, g in enumerate(gm.geometryObjects) if g.parentJoint != 0]
        centres = np.array([g.placement.translation for g in gm.geometryObjects]).reshape(-1, 3)

        def distance(i: int, phase: str) -> np.ndarray:
            """Per pair at sample i: the exact distance where it can matter, else a lower bound.

            The bound (centre distance minus both bounding radii) is used where it exceeds both
            the clearance plus the pair's motion on both neighbouring segments (such a pair is
            free at the sample and, from it, on both segments, which is all the checks use) and
            the smallest distance found so far up to :data:`EXACT_BELOW_M`, so
            ``min_distance_m`` is exact below that (it was a bound: 7.8 mm reported where the
            exact minimum is 12 mm; same verdicts and CPU time on 214 planner calls,
            benchmarks/results/verifier_exact_min_ab.json).
            """
            if i not in cache:
                pin.updateGeometryPlacements(self.model, self.data, gm, full, q[i])
                placements = full.oMg
                for g in moving:
                    centres[g] = placements[g].translation
                d = np.linalg.norm(centres[first] - centres[second], axis=1)
                d -= radius[first] + radius[second]
                floor = np.maximum(around[i], min(report.min_distance_m, EXACT_BELOW_M))
                for k in np.flatnonzero(d < floor):
                    d[k] = pin.computeDistance(gm, full, int(k)).min_distance
                cache[i] = d
            return np.where(masks[phase], cache[i], np.inf)

        for i in range(len(q)):
            self._limits(q[i], float(i), worst)
            d = distance(i, phase_at(float(i)))
            report.min_distance_m = min(report.min_distance_m, float(np.min(d, initial=np.inf)))
            for k in np.flatnonzero(d < self.clearance_m):
                self._record(worst, gm, names, kinds, int(k), float(i), float(d[k]))
        for i in range(len(q) - 1):
            phase = 'before' if i < grasp else ('carry' if i < release else 'after')
            self._segment(
                q[i], q[i + 1], float(i), motion[i], distance(i, phase), distance(i + 1, phase),
                full, (gm, names, kinds, worst), report,
            )  # fmt: skip
        for v in worst.values():
            {
                'joint_limit': report.limit_violations,
                'self_collision': report.self_collisions,
                'scene_collision': report.scene_collisions,
            }[v.kind].append(v)
        return report

    def _segment(
        self,
        q_a: np.ndarray,
        q_b: np.ndarray,
        start: float,
        motion: np.ndarray,
        d_a: np.ndarray,
        d_b: np.ndarray,
        gd: pin.GeometryData,
        record: tuple,
        report: VerificationReport,
    ) -> None:
        """Conservative advancement along the joint line ``q_a`` → ``q_b`` (one segment).

        Pair k's distance changes by at most m_k·|Δt| (``motion``: its bound over the whole
        segment), so with slack s = d − clearance it is free on [t, t + s/m_k] from any checked
        t, and on [1 − s_b/m_k, 1] from the end. Pairs whose intervals meet are done; the
        others are checked at t + Δt, Δt the smallest proven-free advance, but never less
        than ``resolution_m`` of their largest motion (the uniform densification's guarantee
        where nothing is proven).
        """
        gm, names, kinds, worst = record
        c = self.clearance_m
        slack_b = d_b - c
        slack = d_a - c
        close = np.flatnonzero((motion > 1e-12) & (slack + slack_b <= motion))
        t = 0.0
        while close.size:
            m = motion[close]
            done = t * m + np.maximum(slack[close], 0.0) + slack_b[close] >= m
            close, m = close[~done], m[~done]
            if close.size == 0:
                return
            free = float(np.min(np.maximum(slack[close], 0.0) / m))
            largest = float(np.max(m))
            step = max(free, self.resolution_m / largest)
            if step == self.resolution_m / largest:
                report.max_gap_m = max(report.max_gap_m, step * largest)
            t += step
            if t >= 1.0:
                return
            pin.updateGeometryPlacements(self.model, self.data, gm, gd, q_a + (q_b - q_a) * t)
            report.checked += 1  # joint limits: extremes of a joint line are its ends
            for k in close:
                dist = float(pin.computeDistance(gm, gd, int(k)).min_distance)
                slack[k] = dist - c
                if dist < c:
                    self._record(worst, gm, names, kinds, int(k), start + t, dist)

    def _record(self, worst, gm, names, kinds, k: int, t: float, distance: float) -> None:
        pair = gm.collisionPairs[k]
        a, b = names[pair.first], names[pair.second]
        if b == 'carried' or (a not in self.links and a != 'carried'):
            a, b = b, a
        key = (kinds[k], a, b)
        if key not in worst or distance < worst[key].value:
            worst[key] = Violation(kinds[k], a, b, t, distance)

    def _limits(self, q: np.ndarray, t: float, worst: dict) -> None:
        values = q[self._limited]
        for k in np.flatnonzero((values < self._lower) | (values > self._upper)):
            joint = ARM_JOINTS[self._limited[k]]
            side = 'lower' if values[k] < self._lower[k] else 'upper'
            excess = float(
                self._lower[k] - values[k] if side == 'lower' else values[k] - self._upper[k]
            )
            key = ('joint_limit', joint, side)
            if key not in worst or excess > worst[key].value:
                worst[key] = Violation('joint_limit', joint, side, float(t), excess)
