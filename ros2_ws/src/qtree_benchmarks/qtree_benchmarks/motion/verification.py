"""Benchmark side of the independent verifier: every feasible trajectory re-checked against the
objects where the simulator stands them (no ROS import).

A check ``(R, o)`` is answered once for the SET R; in a run, the objects of R stand on slots
0 … |R|−1 in the order they were relocated. Each feasible trajectory is therefore verified in
several orders of R (sorted, reversed, and random ones), with the objects of R as they really
are (exact shapes on their slots, :func:`qtree_scene.placement.slot_position`), not the
planner's conservative envelopes. An object of R stands where its own answer's hand released
it (position and yaw of the released pose, #29) when that answer is among the results, else on
its slot with its original yaw (counted as ``placed_pose_approximated``).

Also measured per trajectory: the smallest pair distance the verifier computed
(``min_clearance_mm``, verified at the executor's stop distance) and the carried object's
largest tilt from upright between grasp and release (``carried_tilt_max_deg``).
"""

from __future__ import annotations

import dataclasses
import random
import time
from typing import Any

import numpy as np
from qtree_scene.placement import slot_position
from qtree_scene.scene import ObjectSpec, Scenario
from stpik_motion_planner.carried import carried_poses, released, tilt_deg
from stpik_motion_planner.result import PlanResult
from stpik_motion_planner.verifier import Carried, TrajectoryVerifier

ORDERS = 3  # relocation orders of R tried per trajectory [-]


def placed_objects(
    scenario: Scenario, order: list[str], answers: dict | None = None, robot=None
) -> tuple[list[ObjectSpec], int]:
    """The objects of ``order`` where they stand once relocated in that order, and how many of
    them stand on their slot with their original yaw because their own answer is not known.

    Args:
        scenario: the scene before any relocation.
        order: ids in the order they are relocated (slot 0, 1, ...).
        answers: feasible results by ``(frozenset(relocated before), object id)``.
        robot: the robot model that replays an answer's release pose (None: slots only).
    """
    out, approximated = [], 0
    for index, object_id in enumerate(order):
        obj = scenario.object(object_id)
        own = (answers or {}).get((frozenset(order[:index]), object_id))
        if own is not None and robot is not None:
            out.append(released(obj, own, robot))
            continue
        approximated += 1
        out.append(dataclasses.replace(obj, position=tuple(slot_position(scenario, index, obj))))
    return out, approximated


def verify_results(
    scenario: Scenario,
    results: list[tuple[tuple[frozenset[str], str], PlanResult]],
    verifier: TrajectoryVerifier,
    seed: int = 0,
) -> dict:
    """Verifier figures over the feasible ``results`` of one scenario (cache items)."""
    rng = random.Random(seed)
    out: dict[str, Any] = {
        'trajectories': 0,
        'colliding': 0,
        'limit_violations': 0,
        'configurations': 0,
    }
    out['placed_pose_approximated'] = 0
    gaps: list[float] = []
    times: list[float] = []
    examples: list[str] = []
    clearances: list[float] = []
    tilts: list[float] = []
    robot = verifier.robot
    answers = {key: r for key, r in results if r.feasible}
    for (relocated, object_id), result in results:
        if not result.feasible:
            continue
        out['trajectories'] += 1
        tilts.append(
            max(tilt_deg(p) for p in carried_poses(scenario.object(object_id), result, robot))
        )
        base = sorted(relocated)
        orders = [base, base[::-1]]
        while len(orders) < ORDERS:
            orders.append(rng.sample(base, len(base)))
        obj = scenario.object(object_id)
        removed = set(relocated) | {object_id}
        standing = [o for o in scenario.objects if o.id not in removed]
        collides = violates = False
        for order in orders[:ORDERS]:
            placed, approximated = placed_objects(scenario, order, answers, robot)
            out['placed_pose_approximated'] += approximated
            start = time.perf_counter()
            report = verifier.verify(
                result.joint_trajectory,
                standing + placed,
                Carried(obj, result.grasp_index, result.release_index),
            )
            times.append(time.perf_counter() - start)
            clearances.append(report.min_distance_m)
            out['configurations'] += report.checked
            gaps.append(report.max_gap_m)
            collides |= bool(report.self_collisions or report.scene_collisions)
            violates |= bool(report.limit_violations)
            if not report.ok and len(examples) < 3:
                examples.append(f'{scenario.name} {object_id} after {order}: {report.summary()}')
        out['colliding'] += int(collides)
        out['limit_violations'] += int(violates)
    out['max_gap_mm'] = round(max(gaps, default=0.0) * 1e3, 2)
    out['times'] = times
    out['examples'] = examples
    out['clearances'] = clearances
    out['tilts'] = tilts
    return out


def merge(parts: list[dict], planner_rejections: int, verifier_clearance_m: float = 0.0) -> dict:
    """One ``verifier`` JSON block from the per-scenario parts."""
    times = [t for p in parts for t in p['times']]
    clearances = [c for p in parts for c in p['clearances']]
    tilts = [t for p in parts for t in p['tilts']]
    return {
        'trajectories': sum(p['trajectories'] for p in parts),
        'colliding': sum(p['colliding'] for p in parts),
        'limit_violations': sum(p['limit_violations'] for p in parts),
        'orders': ORDERS,
        'configurations': sum(p['configurations'] for p in parts),
        'max_gap_mm': max((p['max_gap_mm'] for p in parts), default=0.0),
        'median_ms': round(float(np.median(times)) * 1e3, 1) if times else None,
        'planner_rejections': planner_rejections,
        'clearance_m': verifier_clearance_m,
        'min_clearance_mm': round(min(clearances) * 1e3, 2) if clearances else None,
        'placed_pose_approximated': sum(p['placed_pose_approximated'] for p in parts),
        'carried_tilt_max_deg': round(max(tilts), 1) if tilts else None,
        'carried_tilt_median_of_maxima_deg': round(float(np.median(tilts)), 1) if tilts else None,
        'examples': [e for p in parts for e in p['examples']][:3],
    }
