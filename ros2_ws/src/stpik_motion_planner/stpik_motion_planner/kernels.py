"""Compiled numeric kernels of the STPIK hot path (#28). No ROS import.

The profile of a typical check (``benchmarks/results/profiles``) spent most of its time in
Python and numpy call overhead on tiny arrays, not in arithmetic: reading 14 geometry placements
out of Pinocchio (1.2 µs each), the bounding-volume culls of the collision queries (a dozen numpy
calls each) and the SVDs of eq. (6) (numpy's per-call cost dominates a 6 × 7 decomposition).
These kernels do the same arithmetic in one compiled call each (numba, compiled ahead of the
first request and cached on disk):

* :func:`chain_placements`: forward kinematics of the serial chain of revolute-z joints and
  the placements of its collision geometries (what ``pin.forwardKinematics`` +
  ``pin.updateGeometryPlacements`` give, to rounding), for the collision queries;
* :func:`self_candidates` / :func:`scene_candidates`: the lower bounds of
  :mod:`.collision` that rule pairs out before any ``fcl.distance`` call;
* :func:`solve_levels`: eq. (6) over stacked task rows, one SVD per level.

Each kernel is a pure function of numpy arrays; the unit tests compare it with the numpy (or
Pinocchio) computation it replaces.
"""

from __future__ import annotations

import math

import numba
import numpy as np

# Every kernel: cached on disk, releases the GIL, IEEE arithmetic (no fastmath).


@numba.njit(
    numba.types.Tuple((numba.float64[:, :, ::1], numba.float64[:, :, ::1]))(
        numba.float64[::1],
        numba.float64[:, :, ::1],
        numba.int64[::1],
        numba.float64[:, :, ::1],
    ),
    cache=True,
    nogil=True,
    fastmath=False,
)
def chain_placements(
    q: np.ndarray, joint_placements: np.ndarray, geometry_joint: np.ndarray, geometry_in_joint
):
    """World placements of the joints and the collision geometries of a serial arm.

    oMi_j = oMi_{j−1} · jointPlacement_j · R_z(q_j) (every joint revolute about its own z axis,
    joint j's parent is joint j − 1), oMg = oMi_parent(g) · placement_g.

    Args:
        q: joint angles [rad] (n,).
        joint_placements: jointPlacement of joints 1 … n, homogeneous (n, 4, 4) [m].
        geometry_joint: parent joint of each geometry (G,) (0: the world).
        geometry_in_joint: placement of each geometry in its parent joint (G, 4, 4) [m].

    Returns:
        oMi (n + 1, 4, 4) (row 0: the world) and oMg (G, 4, 4), homogeneous [m].
    """
    n = q.shape[0]
    joints = np.zeros((n + 1, 4, 4))
    for i in range(4):
        joints[0, i, i] = 1.0
    turn = np.zeros((4, 4))
    turn[2, 2] = 1.0
    turn[3, 3] = 1.0
    for j in range(n):
        c, s = math.cos(q[j]), math.sin(q[j])
        turn[0, 0], turn[0, 1], turn[1, 0], turn[1, 1] = c, -s, s, c
        joints[j + 1] = joints[j] @ joint_placements[j] @ turn
    geometries = np.empty((geometry_joint.shape[0], 4, 4))
    for g in range(geometry_joint.shape[0]):
        geometries[g] = joints[geometry_joint[g]] @ geometry_in_joint[g]
    return joints, geometries


@numba.njit(
    numba.int64[::1](
        numba.float64[:, ::1],
        numba.float64[::1],
        numba.int64[::1],
        numba.int64[::1],
        numba.float64,
        numba.boolean,
    ),
    cache=True,
    nogil=True,
    fastmath=False,
)
def self_candidates(
    centres: np.ndarray,
    radii: np.ndarray,
    pair_a: np.ndarray,
    pair_b: np.ndarray,
    threshold: float,
    inclusive: bool,
) -> np.ndarray:
    """Indices of the pairs whose bounding spheres are less than ``threshold`` [m] apart.

    gap_k = |c_a − c_b| − (r_a + r_b) is a lower bound of pair k's distance; pairs with
    gap < threshold (≤ with ``inclusive``) are returned in ascending order.

    Args:
        centres: sphere centres [m] (B, 3).
        radii: their radii [m] (B,).
        pair_a: first body index of each pair (P,).
        pair_b: second body index of each pair (P,).
        threshold: the distance below which a pair is kept [m].
        inclusive: also keep pairs exactly at ``threshold``.
    """
    out = np.empty(pair_a.shape[0], dtype=np.int64)
    count = 0
    for k in range(pair_a.shape[0]):
        a, b = pair_a[k], pair_b[k]
        dx = centres[a, 0] - centres[b, 0]
        dy = centres[a, 1] - centres[b, 1]
        dz = centres[a, 2] - centres[b, 2]
        gap = math.sqrt(dx * dx + dy * dy + dz * dz) - (radii[a] + radii[b])
        if gap < threshold or (inclusive and gap == threshold):
            out[count] = k
            count += 1
    return out[:count]


@numba.njit(
    numba.types.Tuple((numba.int64[::1], numba.int64[::1]))(
        numba.float64[:, ::1],
        numba.float64[::1],
        numba.int64[::1],
        numba.float64[:, ::1],
        numba.float64[::1],
        numba.float64[::1],
        numba.float64[:, ::1],
        numba.float64,
        numba.boolean,
    ),
    cache=True,
    nogil=True,
    fastmath=False,
)
def scene_candidates(
    centres: np.ndarray,
    radii: np.ndarray,
    bodies: np.ndarray,
    object_centres: np.ndarray,
    cos_yaw: np.ndarray,
    sin_yaw: np.ndarray,
    half_extents: np.ndarray,
    threshold: float,
    inclusive: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """(rows into ``bodies``, object indices) of the (body, object) pairs not ruled out.

    Lower bound of a pair's distance: the distance from the body's bounding-sphere centre to
    a box around the object in the object's frame (yaw about z), minus the sphere's radius.
    Pairs with bound < threshold (≤ with ``inclusive``), body-major order (as ``np.nonzero``).

    Args:
        centres: bounding-sphere centres of every robot body [m] (B, 3).
        radii: their radii [m] (B,).
        bodies: the bodies checked against the scene, indices into ``centres`` (K,).
        object_centres: object centres [m] (O, 3).
        cos_yaw: cosine of each object's yaw (O,).
        sin_yaw: sine of each object's yaw (O,).
        half_extents: half sizes of the box around each object in its frame [m] (O, 3).
        threshold: the bound below which a pair is kept [m].
        inclusive: also keep pairs exactly at ``threshold``.
    """
    count_max = bodies.shape[0] * object_centres.shape[0]
    rows = np.empty(count_max, dtype=np.int64)
    objects = np.empty(count_max, dtype=np.int64)
    count = 0
    for r in range(bodies.shape[0]):
        body = bodies[r]
        for o in range(object_centres.shape[0]):
            dx = centres[body, 0] - object_centres[o, 0]
            dy = centres[body, 1] - object_centres[o, 1]
            dz = centres[body, 2] - object_centres[o, 2]
            x = abs(dx * cos_yaw[o] + dy * sin_yaw[o]) - half_extents[o, 0]
            y = abs(dy * cos_yaw[o] - dx * sin_yaw[o]) - half_extents[o, 1]
            z = abs(dz) - half_extents[o, 2]
            x, y, z = max(x, 0.0), max(y, 0.0), max(z, 0.0)
            bound = math.sqrt(x * x + y * y + z * z) - radii[body]
            if bound < threshold or (inclusive and bound == threshold):
                rows[count] = r
                objects[count] = o
                count += 1
    return rows[:count], objects[:count]


@numba.njit(
    numba.float64[::1](
        numba.float64[:, ::1],
        numba.float64[::1],
        numba.int64[::1],
        numba.float64,
        numba.float64,
        numba.float64,
    ),
    cache=True,
    nogil=True,
    fastmath=False,
)
def solve_levels(
    jacobian: np.ndarray,
    error: np.ndarray,
    starts: np.ndarray,
    damping: float,
    threshold: float,
    tolerance: float,
) -> np.ndarray:
    """Eq. (6) over stacked levels: q̇_i = q̇_{i−1} + (J_i N_{i−1})^†_λ (K_i σ̃_i − J_i q̇_{i−1}),
    N_i = N_{i−1} − (J_i N_{i−1})^+ J_i N_{i−1}.

    ^†_λ: singular values s < ``threshold`` inverted as s / (s² + λ²), λ² = damping² (1 −
    (s / threshold)²) (variable damping); ^+: undamped, singular values < ``tolerance`` dropped
    (an exact projector: strict priority where damping acts). One SVD per level; the last
    level's projector is not computed.

    Args:
        jacobian: rows of every level, highest priority first (m, n).
        error: K_i σ̃_i of those rows (m,).
        starts: row where each level starts, then m (L + 1,); empty levels allowed.
        damping: largest damping λ of the damped inverse [-].
        threshold: singular value below which damping acts [-].
        tolerance: singular value below which the projector drops a direction [-].

    Returns:
        The joint step q̇ (already multiplied by dt) [rad] (n,).
    """
    n = jacobian.shape[1]
    dq = np.zeros(n)
    projector = np.eye(n)
    last = -1
    for level in range(starts.shape[0] - 1):
        if starts[level + 1] > starts[level]:
            last = level
    for level in range(last + 1):
        begin, end = starts[level], starts[level + 1]
        if end == begin:
            continue
        rows = np.ascontiguousarray(jacobian[begin:end])
        jn = rows @ projector
        u, s, vt = np.linalg.svd(jn, full_matrices=False)
        residual = error[begin:end] - rows @ dq
        damped = np.zeros(s.shape[0])
        truncated = np.zeros(s.shape[0])
        for i in range(s.shape[0]):
            lam2 = damping * damping * (1.0 - (s[i] / threshold) ** 2) if threshold > s[i] else 0.0
            denom = s[i] * s[i] + lam2
            if denom > 1e-12:
                damped[i] = s[i] / denom
            if tolerance <= s[i]:
                truncated[i] = 1.0 / s[i]
        v = vt.T
        dq = dq + (v * damped) @ (u.T @ residual)
        if level == last:
            break
        projector = projector - ((v * truncated) @ u.T) @ jn
    return dq


@numba.njit(
    numba.types.Tuple((numba.int64[::1], numba.int64[::1], numba.int64[::1]))(
        numba.float64[:, :, ::1],
        numba.float64[:, ::1],
        numba.float64[::1],
        numba.boolean[::1],
        numba.float64[:, ::1],
        numba.float64[::1],
        numba.float64[::1],
        numba.float64[:, ::1],
    ),
    cache=True,
    nogil=True,
    fastmath=False,
)
def replay_candidates(
    centres: np.ndarray,
    radii: np.ndarray,
    thresholds: np.ndarray,
    inclusive: np.ndarray,
    object_centres: np.ndarray,
    cos_yaw: np.ndarray,
    sin_yaw: np.ndarray,
    half_extents: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`scene_candidates` of many logged queries against one scene, in one call.

    Query i has the bodies ``centres[i]`` [m] (K, 3) with ``radii[i]`` [m] (K,) (every body
    of the query, rows 0 … K−1), ``thresholds[i]`` [m] and ``inclusive[i]``; each is culled by
    :func:`scene_candidates` itself, so the pairs are the ones that query would get.

    Returns:
        (query index, row, object index) of every pair let through, query-major (m,) each.
    """
    n, k = centres.shape[0], centres.shape[1]
    bodies = np.arange(k)
    total = n * k * object_centres.shape[0]
    queries = np.empty(total, dtype=np.int64)
    rows = np.empty(total, dtype=np.int64)
    objects = np.empty(total, dtype=np.int64)
    count = 0
    for i in range(n):
        r, o = scene_candidates(
            centres[i],
            radii[i],
            bodies,
            object_centres,
            cos_yaw,
            sin_yaw,
            half_extents,
            thresholds[i],
            inclusive[i],
        )
        for j in range(r.shape[0]):
            queries[count] = i
            rows[count] = r[j]
            objects[count] = o[j]
            count += 1
    return queries[:count], rows[:count], objects[:count]
