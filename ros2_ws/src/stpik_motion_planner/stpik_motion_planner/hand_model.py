"""The open hand from the URDF collision geometry, in the end-effector frame (no ROS import).

Used by the Cartesian sampler (:class:`HandModel`: the approach corridor swept by the real hand,
the free-space probe inside it), to check the hand constants of :mod:`qtree_scene.placement`
(slot layout) and the grasp opening of the planner (``OBJECT_TOO_BIG``). EE frame: z = approach,
x = across the fingers, y = up in a side grasp
(:func:`~stpik_motion_planner.cartesian_path.grasp_rotation`).

Measured on the j2s7s300 URDF (fingers at 0.2 rad): palm (link 7) x ∈ [−0.051, 0.054],
y ± 0.047, z ∈ [−0.160, −0.039]; the open fingers reach x ∈ [−0.099, 0.104] but only over
z ∈ [−0.066, 0.023]; link 6 (radius 0.032, coaxial with the EE z axis) spans z ∈ [−0.295, −0.160].
The hand is therefore 0.20 m wide over its front 9 cm and 0.105 m wide behind.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import fcl
import numpy as np
import pinocchio as pin
from jaco2_description.model import EE_FRAME, Jaco2Model
from qtree_scene.scene import ObjectSpec
from scipy.spatial import ConvexHull

RING_POINTS = 24  # polygon inscribed in a cylinder's circle (under by r·(1 − cos(π/24)) ≈ 1 %)
WRIST_LINK = 'link_6'  # the last arm link, coaxial with the EE z axis whatever joint 7 does


def _corners(geometry: Any) -> np.ndarray:
    if hasattr(geometry, 'halfSide'):
        return np.array(list(itertools.product([-1.0, 1.0], repeat=3))) * geometry.halfSide
    r, h = float(geometry.radius), float(geometry.halfLength)
    a = np.linspace(0.0, 2 * np.pi, RING_POINTS, endpoint=False)
    ring = np.c_[r * np.cos(a), r * np.sin(a)]
    return np.vstack([np.c_[ring, np.full(RING_POINTS, z)] for z in (-h, h)])


def hand_points(robot: Jaco2Model) -> dict[str, np.ndarray]:
    """Corner points [m] of every body rigid with the EE (link 7 + fingers), EE frame, (k, 3)."""
    ee = robot.model.frames[robot.frame_id(EE_FRAME)]
    out = {}
    for link, g in zip(robot.collision_links, robot.geometry_model.geometryObjects, strict=True):
        if g.parentJoint != ee.parentJoint:
            continue
        joint_to_geometry = g.placement
        points = [ee.placement.actInv(joint_to_geometry.act(c)) for c in _corners(g.geometry)]
        out[link] = np.array(points)
    return out


def open_hand_box(robot: Jaco2Model) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned box (lower, upper) [m] (3,) in the EE frame containing the open hand."""
    points = np.vstack(list(hand_points(robot).values()))
    return points.min(axis=0), points.max(axis=0)


def grasp_width(obj: ObjectSpec, approach_yaw: float) -> float:
    """Width of ``obj`` across the fingers of a side grasp approaching at ``approach_yaw`` [m].

    The fingers close along the EE x axis, horizontal and perpendicular to the approach:
    v = (−sin yaw, cos yaw). A cylinder is 2r across whatever the yaw; an upright box of edges
    (sx, sy) turned by its own yaw θ spans |sx·(v·u)| + |sy·(v·w)| with u = (cos θ, sin θ),
    w = (−sin θ, cos θ) (#30: only the box's narrower side was compared with the opening, so a
    box 95-148 mm across at the chosen approach was "grasped").
    """
    if obj.shape == 'cylinder':
        return 2.0 * obj.radius
    across = approach_yaw + math.pi / 2 - obj.yaw  # the closing direction in the box's frame
    return abs(obj.size[0] * math.cos(across)) + abs(obj.size[1] * math.sin(across))


def finger_opening(robot: Jaco2Model) -> float:
    """Gap [m] across the open fingertips (EE x) at the EE origin height, inner faces."""
    tips = [p for name, p in hand_points(robot).items() if 'finger_tip' in name]
    positive = min(p[:, 0].min() for p in tips if p[:, 0].mean() > 0)
    negative = max(p[:, 0].max() for p in tips if p[:, 0].mean() < 0)
    return float(positive - negative)


def wrist_points(robot: Jaco2Model) -> np.ndarray | None:
    """Points [m] (k, 3) of the wrist link coaxial with the EE z axis, EE frame, else None.

    Joint 7 turns it about the EE z axis only, so a polygon inscribed in its circle stays inside
    it for every joint-7 angle. None when the model has no such coaxial cylinder.
    """
    q = pin.neutral(robot.model)
    pin.forwardKinematics(robot.model, robot.data, q)
    pin.updateFramePlacements(robot.model, robot.data)
    ee = robot.data.oMf[robot.frame_id(EE_FRAME)]
    for link, g in zip(robot.collision_links, robot.geometry_model.geometryObjects, strict=True):
        if not link.endswith(WRIST_LINK) or not hasattr(g.geometry, 'radius'):
            continue
        relative = ee.actInv(robot.data.oMi[g.parentJoint] * g.placement)
        on_axis = np.linalg.norm(relative.translation[:2]) < 1e-6
        if on_axis and abs(abs(relative.rotation[2, 2]) - 1.0) < 1e-6:
            return np.array([relative.act(c) for c in _corners(g.geometry)])
    return None


def palm_ball(robot: Jaco2Model) -> tuple[np.ndarray, float]:
    """Largest ball inside the palm box (link 7): centre [m] (3,) in the EE frame, radius [m].

    Inside the hand whatever the hand's orientation: the free-space probe of the sampler, where
    the orientation along the path is not known, so a blocked probe means a blocked hand.
    """
    ee = robot.model.frames[robot.frame_id(EE_FRAME)]
    for link, g in zip(robot.collision_links, robot.geometry_model.geometryObjects, strict=True):
        if link.endswith('link_7') and hasattr(g.geometry, 'halfSide'):
            centre = ee.placement.actInv(g.placement.translation)
            return np.asarray(centre, dtype=float), float(np.min(g.geometry.halfSide))
    raise ValueError('the robot model has no palm box (link 7)')


def bounding_sphere(points: np.ndarray) -> tuple[np.ndarray, float]:
    """A sphere containing ``points`` [m] (k, 3) (so their convex hull): the centre of their
    bounding box [m] (3,) and the largest distance of a point from it [m].
    """
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    return centre, float(np.max(np.linalg.norm(points - centre, axis=1)))


def convex(points: np.ndarray) -> fcl.Convex:
    """python-fcl convex hull of ``points`` [m] (k, 3), in the points' frame."""
    hull = ConvexHull(points)
    used = np.unique(hull.simplices)
    index = {int(v): i for i, v in enumerate(used)}
    faces = [n for tri in hull.simplices for n in (3, *(index[int(v)] for v in tri))]
    return fcl.Convex(points[used], len(hull.simplices), np.array(faces, dtype=np.int32))


class HandModel:
    """Hand-shaped probes of the Cartesian sampler, built once from the URDF.

    Attributes:
        parts: name -> points [m] (k, 3) in the EE frame of every body rigid with the EE (palm,
            fingers) and of the coaxial wrist link.
        standoff_m: length of the approach swept by :attr:`swept` [m].
        swept: name -> convex hull of a part swept from ``standoff_m`` behind the EE pose (the
            pre-grasp) to the EE pose (the grasp), EE frame: exact for the boxes (the sweep of a
            convex body along a segment is the hull of its two ends), inscribed for cylinders.
        at_pose: name -> convex hull of a part at the EE pose, EE frame.
        ball_centre: centre [m] (3,) of :func:`palm_ball` in the EE frame.
        ball_radius: its radius [m].
    """

    def __init__(self, robot: Jaco2Model, standoff_m: float) -> None:
        self.parts = dict(hand_points(robot))
        wrist = wrist_points(robot)
        if wrist is not None:
            self.parts[WRIST_LINK] = wrist
        self.standoff_m = float(standoff_m)
        back = np.array([0.0, 0.0, -self.standoff_m])
        self.swept = {k: convex(np.vstack([p, p + back])) for k, p in self.parts.items()}
        self.at_pose = {k: convex(p) for k, p in self.parts.items()}
        # Bounding spheres (centre in the EE frame [m] (3,), radius [m]) of the same hulls, for
        # the cull of SceneWorld.probe_hits (#28).
        self.swept_spheres = {
            k: bounding_sphere(np.vstack([p, p + back])) for k, p in self.parts.items()
        }
        self.at_pose_spheres = {k: bounding_sphere(p) for k, p in self.parts.items()}
        self.ball_centre, self.ball_radius = palm_ball(robot)

    def ball_point(self, pose: pin.SE3) -> np.ndarray:
        """World centre [m] (3,) of the palm ball with the EE at ``pose``."""
        return np.asarray(pose.act(self.ball_centre), dtype=float)

    def top_grasp_depth(
        self, obj: ObjectSpec, yaw: float, clearance_m: float, iterations: int = 12
    ) -> float:
        """Deepest EE origin below ``obj``'s top [m] in a top grasp of closing yaw ``yaw`` [rad]
        keeping every hand body ``clearance_m`` [m] from the object (bisection, python-fcl).

        The open fingers narrow toward the palm (36 mm apart at the knuckles, 82 mm at the EE
        origin height), so a wide object cannot go as deep as a thin one (#30: a 60 mm bottle
        taken 29 mm deep was 4.8 mm from finger 1). 0 when even the top touches the margin.
        """
        from stpik_motion_planner.grasps import top_rotation

        height = obj.height if obj.shape == 'cylinder' else obj.size[2]
        if obj.shape == 'cylinder':
            geometry = fcl.Cylinder(obj.radius, height)
        else:
            geometry = fcl.Box(*obj.size)
        turn = top_rotation(yaw).T @ pin.rpy.rpyToMatrix(0.0, 0.0, obj.yaw)  # in the EE frame
        request = fcl.DistanceRequest()
        parts = [fcl.CollisionObject(hull, fcl.Transform()) for hull in self.at_pose.values()]

        def clear(depth: float) -> bool:
            body = fcl.CollisionObject(
                geometry, fcl.Transform(turn, np.array([0.0, 0.0, height / 2 - depth]))
            )
            return all(
                fcl.distance(body, part, request, fcl.DistanceResult()) >= clearance_m
                for part in parts
            )

        low, high = 0.0, max(0.0, self.palm_front_m - clearance_m)
        if not clear(low):
            return 0.0
        if clear(high):
            return high
        for _ in range(iterations):
            middle = (low + high) / 2
            low, high = (middle, high) if clear(middle) else (low, middle)
        return low

    @property
    def palm_front_m(self) -> float:
        """Distance [m] of the palm's front face (link 7) behind the EE origin (0.039 m)."""
        return -max(float(p[:, 2].max()) for k, p in self.parts.items() if k.endswith('link_7'))

    @property
    def half_width_m(self) -> float:
        """Largest |x| (across the fingers) of the hand [m]."""
        return max(float(np.max(np.abs(p[:, 0]))) for p in self.parts.values())

    def __repr__(self) -> str:
        return (
            f'HandModel({len(self.parts)} parts, half width {self.half_width_m:.3f} m, '
            f'palm ball r {self.ball_radius:.4f} m, standoff {self.standoff_m:.3f} m)'
        )
