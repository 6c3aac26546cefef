"""Drop slots: where relocated objects stand, shared by the motion planner and the simulator.

No ROS import, pure function of the :class:`~qtree_scene.scene.Scenario`. The k-th relocation of a
run (k = number of objects relocated before it, counted from 0) puts its object upright on the
table at slot k. Which slots are occupied after relocating a set R is therefore {0, …, |R|−1},
whatever the order; only which object stands in which slot depends on the order. A planner that
treats each occupied slot as the envelope of the objects of R (:func:`occupied_envelopes`: the
largest footprint radius and the largest height over R) sees obstacles that are a function of the
SET R only, so a feasibility answer keyed on ``(frozenset(R), o)`` stays valid (Assumption 2).

The slots are laid out so that placing into slot k never touches slots 0 … k−1 (the open hand and
the wrist behind it, :data:`HAND_FOOTPRINT`, clear every earlier slot's disc by
:data:`SLOT_MARGIN_M`), and so that no slot's hand footprint meets an object standing in the
clutter at the start. Candidates are rings about the base axis, outermost first, those
nearest the drop zone's azimuth first, on the free table area all around the base (beside and
behind the robot too, where the table reaches), away from every clutter object's approach
corridors; every candidate that fits is kept (#29: a cap of 30 made a 50-object scene
unclearable by design; generated 50-object scenes now hold 36-42).

Room scales with the free table area within reach: about one slot per 0.167 m × 0.092 m of ring
(open hand 0.20 m wide, 3 cm objects). The 1.2 m × 1.4 m table of S1-S3 gives 15-23 slots; a
table reaching :data:`DROP_TABLE_REACH_M` around the base (what
:func:`qtree_scene.generator.generate_clutter` lays) gives 36-42 beside 30-50 clutter objects.
When the slots run out the motion planner answers ``NO_PLACEMENT`` (:func:`capacity`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from qtree_scene.scene import ObjectSpec, Scenario

MAX_SLOTS = 1000  # a bound on the slot search only: the table's free area decides [-]
# An object released within SNAP_RADIUS_M of its slot is stood upright on it by the simulator
# (jaco2_sim.world), so placed objects stand within PLACEMENT_TOLERANCE_M of the slot centre.
SNAP_RADIUS_M = 0.05
PLACEMENT_TOLERANCE_M = 0.002
# Clearance between the hand footprint / a carried object and other slots or clutter objects:
# above the planner's obstacle activation distance (25 mm), so STPIK tracks placements freely [m].
SLOT_MARGIN_M = 0.03
# Open Jaco² hand (fingers at 0.2 rad) seen from above in a side grasp, in the frame of the slot:
# u along the approach (radially outward, EE z), v lateral (EE x). From the URDF collision boxes
# (stpik_motion_planner.hand_model checks these bounds): fingertips 0.023 m beyond the EE origin,
# palm 0.16 m behind it, fingers ±0.104 m lateral; the wrist (link 5/6, radius 0.032 m) and the
# forearm follow 0.45 m behind along −u.
HAND_AHEAD_M = 0.025
HAND_HALF_WIDTH_M = 0.105
HAND_BEHIND_M = 0.16
WRIST_BEHIND_M = 0.45
WRIST_HALF_WIDTH_M = 0.045
# Outermost slot ring radius [m]: side-grasp reach at carry height (the 30 slots of a 30-object
# scene, beside and behind the base, planned and verified in test_placement_room.py of
# stpik_motion_planner).
RING_MAX_M = 0.84
# Farthest slot centre from the base axis a hand holding an object from above reaches [m].
TOP_PLACE_REACH_M = 0.58
# Nearest side slot of a planner that also grasps from above: the rings between are left free
# for the hands placing on the top slots [m].
SIDE_SLOT_MIN_M = 0.7
RING_MIN_M = 0.46  # innermost slot ring radius [m] (the wrist must fit behind the hand)
# Table reach around the base axis that holds every ring (+ the largest object and a margin) [m].
DROP_TABLE_REACH_M = RING_MAX_M + 0.11
# The radial approach corridor of every clutter object (from it toward the base, CORRIDOR_M long,
# as wide as the open hand) is kept free of slots [m].
CORRIDOR_M = 0.45


@dataclass(frozen=True)
class Slot:
    """One placement slot.

    Attributes:
        index: relocation number that uses it (0 = first relocation).
        xy: centre on the table [m], shape (2,).
        yaw: azimuth of the approach (hand facing radially outward) [rad].
    """

    index: int
    xy: tuple[float, float]
    yaw: float


def footprint_radius(obj: ObjectSpec) -> float:
    """Radius of the disc about the object's axis that covers its footprint [m]."""
    if obj.shape == 'cylinder':
        return float(obj.radius)
    return 0.5 * math.hypot(obj.size[0], obj.size[1])


def object_height(obj: ObjectSpec) -> float:
    """Full height of the object [m]."""
    return float(obj.height if obj.shape == 'cylinder' else obj.size[2])


def _in_corridor(point: np.ndarray, radius: float, obj_xy: np.ndarray) -> bool:
    """True when a disc meets an approach corridor of the clutter object at ``obj_xy``."""
    azimuth = math.atan2(obj_xy[1], obj_xy[0])
    reach = HAND_HALF_WIDTH_M + radius + PLACEMENT_TOLERANCE_M + SLOT_MARGIN_M
    back = -np.array([math.cos(azimuth), math.sin(azimuth)])
    t = min(max(float((point - obj_xy) @ back), 0.0), CORRIDOR_M)
    return float(np.linalg.norm(point - (obj_xy + t * back))) < reach


def _table(scenario: Scenario) -> ObjectSpec:
    return next(o for o in scenario.statics if o.id == 'table')


def _hand_hits(centre: np.ndarray, yaw: float, point: np.ndarray, radius: float) -> bool:
    """True when a disc (``point``, ``radius``) meets the hand + wrist footprint at a slot."""
    u = np.array([math.cos(yaw), math.sin(yaw)])
    v = np.array([-u[1], u[0]])
    d = point - centre
    a, b = float(d @ u), float(d @ v)
    r = radius + PLACEMENT_TOLERANCE_M + SLOT_MARGIN_M
    in_hand = -HAND_BEHIND_M - r <= a <= HAND_AHEAD_M + r and abs(b) <= HAND_HALF_WIDTH_M + r
    in_wrist = -WRIST_BEHIND_M - r <= a <= 0.0 and abs(b) <= WRIST_HALF_WIDTH_M + r
    return in_hand or in_wrist


@functools.cache
def drop_slots(scenario: Scenario) -> tuple[Slot, ...]:
    """The scenario's slots in relocation order, as many as the free table area in reach holds."""
    return _ring_slots(scenario, RING_MAX_M, ())


def _ring_slots(scenario: Scenario, rho_max: float, taken: tuple[Slot, ...]) -> tuple[Slot, ...]:
    """Slots on rings from ``rho_max`` [m] inward (outer first), none where the hand placing
    in one of ``taken`` would be.
    """
    movable = [o for o in scenario.objects if o.role != 'static']
    r_max = max((footprint_radius(o) for o in movable), default=0.03)
    table = _table(scenario)
    t_centre = np.asarray(table.position[:2], dtype=float)
    t_half = np.asarray(table.size[:2], dtype=float) / 2 - r_max - SLOT_MARGIN_M
    zone_c = np.asarray(scenario.drop_zone_center[:2], dtype=float)
    zone_half = np.asarray(scenario.drop_zone_size[:2], dtype=float) / 2
    zone_yaw = math.atan2(zone_c[1], zone_c[0])
    radial = max(HAND_AHEAD_M + r_max, 2 * r_max) + PLACEMENT_TOLERANCE_M + SLOT_MARGIN_M
    lateral = HAND_HALF_WIDTH_M + r_max + PLACEMENT_TOLERANCE_M + SLOT_MARGIN_M
    clutter = [(np.asarray(o.position[:2], dtype=float), footprint_radius(o)) for o in movable]
    candidates = []
    rho = rho_max
    while rho >= RING_MIN_M - 1e-9:
        # Neighbours on a ring are ``lateral`` apart across the hand (not along the chord, which
        # is longer: a chord of ``lateral`` put every other candidate inside a hand footprint).
        step = math.asin(min(1.0, lateral / rho)) * (1.0 + 1e-6)
        count = math.floor(math.pi / step)
        for k in range(-count, count + 1):
            yaw = zone_yaw + k * step
            xy = rho * np.array([math.cos(yaw), math.sin(yaw)])
            if np.any(np.abs(xy - t_centre) > t_half):
                continue
            if rho - r_max < scenario.robot_keepout_radius:
                continue
            if any(_hand_hits(xy, yaw, p, r) or _in_corridor(xy, r_max, p) for p, r in clutter):
                continue
            in_zone = bool(np.all(np.abs(xy - zone_c) <= zone_half))
            candidates.append((-round(rho, 6), not in_zone, abs(k), k, xy, yaw))
        rho -= radial
    candidates.sort(key=lambda c: c[:4])
    slots: list[Slot] = []
    index = len(drop_slots(scenario)) if taken else 0  # top slots: indices after drop_slots'
    for *_, xy, yaw in candidates:
        if len(slots) == MAX_SLOTS:
            break
        near = (*taken, *slots)
        if any(_hand_hits(xy, yaw, np.asarray(s.xy), r_max) for s in near):
            continue
        slots.append(Slot(index + len(slots), (float(xy[0]), float(xy[1])), float(yaw)))
    return tuple(slots)


def slot_position(scenario: Scenario, index: int, obj: ObjectSpec) -> np.ndarray:
    """Centre [m] (3,) of ``obj`` standing upright in slot ``index`` on the table top.

    Raises:
        IndexError: the scenario has no slot ``index`` (see :func:`drop_slots`).
    """
    slots = drop_slots(scenario)
    if not 0 <= index < len(slots):
        raise IndexError(f'slot {index} of a scene with {len(slots)} slots')
    top = _table(scenario).top_z
    x, y = slots[index].xy
    return np.array([x, y, top + object_height(obj) / 2])


@functools.cache
def top_place_slots(scenario: Scenario) -> tuple[tuple[Slot, ...], tuple[Slot, ...]]:
    """The slots of a planner that grasps from above too (#30): (side, top).

    A hand holding an object from above reaches only :data:`TOP_PLACE_REACH_M` from the base
    axis (measured from the planner's READY_TOP: top-down poses up to 0.45 m high at 0.55 m,
    0.4 m at 0.6 m, 0.3 m at 0.65 m, 0.2 m at 0.7 m, none at 0.75 m; a tall object is carried
    0.4 m high). The side slots are those of :func:`drop_slots` from :data:`SIDE_SLOT_MIN_M`
    out (its outer rings come first, so the simulator's settling on slot k is unchanged for
    them); the top slots lie on rings from that reach inward, the hand placing on one clear of
    every side slot and of the top slots before it (indices after :func:`drop_slots`'). The
    k-th relocation stands on side slot k or top slot k, each a function of k only; an object
    released on a top slot stays where it
    was released.
    """
    side = tuple(s for s in drop_slots(scenario) if math.hypot(*s.xy) >= SIDE_SLOT_MIN_M)
    return side, _ring_slots(scenario, TOP_PLACE_REACH_M, side)


def slot_centre(scenario: Scenario, slot: Slot, obj: ObjectSpec) -> np.ndarray:
    """Centre [m] (3,) of ``obj`` standing upright on ``slot`` on the table top."""
    return np.array([slot.xy[0], slot.xy[1], _table(scenario).top_z + object_height(obj) / 2])


def settle_pose(
    scenario: Scenario, index: int, obj: ObjectSpec, released: np.ndarray, yaw: float
) -> tuple[np.ndarray, float] | None:
    """Where the ``index``-th relocated object comes to stand when released at ``released``.

    Args:
        scenario: the scene.
        index: relocation number (objects relocated before this one).
        obj: the object.
        released: its centre at release [m], shape (3,).
        yaw: its yaw at release [rad].

    Returns:
        (centre [m] (3,), yaw [rad]) upright on slot ``index`` when released within
        :data:`SNAP_RADIUS_M` of it (horizontally), else None (the object stays where it is).
    """
    slots = drop_slots(scenario)
    if not 0 <= index < len(slots):
        return None
    centre = slot_position(scenario, index, obj)
    if float(np.linalg.norm(np.asarray(released[:2], dtype=float) - centre[:2])) > SNAP_RADIUS_M:
        return None
    return centre, float(yaw)


def occupied_envelopes(
    scenario: Scenario,
    relocated_ids: frozenset[str] | set[str] | list[str],
    margin: float = PLACEMENT_TOLERANCE_M,
    slots: Sequence[Slot] | None = None,
) -> list[ObjectSpec]:
    """Obstacles standing in the occupied slots 0 … |R|−1, as a function of the SET R only.

    Each is an upright cylinder of the largest footprint radius over R plus ``margin`` [m] and
    the largest height over R plus ``margin``, so it contains whichever object of R stands there
    (placed within ``margin`` of its slot). Ids are ``'slot_<k>'`` (k: the index in
    :func:`drop_slots`), role ``'obstacle'``. ``slots``: the slot sequence the relocations
    fill (default :func:`drop_slots`; one of :func:`top_place_slots`).
    """
    objects = [scenario.object(i) for i in relocated_ids]
    if not objects:
        return []
    slots = drop_slots(scenario) if slots is None else tuple(slots)
    radius = max(footprint_radius(o) for o in objects) + margin
    height = max(object_height(o) for o in objects) + margin
    top = _table(scenario).top_z
    return [
        ObjectSpec(
            id=f'slot_{s.index}',
            role='obstacle',
            shape='cylinder',
            position=(s.xy[0], s.xy[1], top + height / 2),
            radius=radius,
            height=height,
        )
        for s in slots[: len(objects)]
    ]


def capacity(scenario: Scenario) -> int:
    """Relocations the scenario has room for (number of :func:`drop_slots`) [-]."""
    return len(drop_slots(scenario))
