#!/usr/bin/env python3
"""Benchmark of the STPIK motion planner: time per feasibility check, by stage, cache hit rate,
exact optimal relocation level per scenario, and a damped-least-squares IK peer on the same paths.

Usage: ``python scripts/bench_motion_planner.py [--quick]`` (env.sh sourced). Writes
``benchmarks/results/motion_planner.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import random
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from jaco2_sim.scenario import generate_clutter, load_scenario
from stpik_motion_planner.planner import MotionPlanner
from stpik_motion_planner.stpik import READY
from tqdm import tqdm

OUT = Path(__file__).resolve().parents[1] / 'benchmarks' / 'results'


def exact_levels(planner: MotionPlanner, max_level: int) -> tuple[int | None, int]:
    """BFS over sets of relocated obstacles; (smallest set size reaching the target, sets seen)."""
    obstacles = [o.id for o in planner.scenario.obstacles]
    target = planner.scenario.target.id
    frontier, seen = {frozenset()}, {frozenset()}
    for level in range(max_level + 1):
        if any(planner.check(target, s).feasible for s in frontier):
            return level, len(seen)
        nxt = set()
        for s in frontier:
            for o in obstacles:
                if o not in s and planner.check(o, s).feasible and (s | {o}) not in seen:
                    nxt.add(s | {o})
        seen |= nxt
        frontier = nxt
        if not frontier:
            break
    return None, len(seen)


def query_stream(planner: MotionPlanner, episodes: int, seed: int) -> None:
    """Task-planner-like queries: random feasible relocation sequences, target tried first."""
    rng = random.Random(seed)
    ids = [o.id for o in planner.scenario.obstacles]
    target = planner.scenario.target.id
    for _ in range(episodes):
        done: list[str] = []
        while True:
            if planner.check(target, done).feasible:
                break
            choice = rng.choice([o for o in ids if o not in done] or [target])
            if choice == target or not planner.check(choice, done).feasible:
                break
            done.append(choice)


def dls_peer(planner: MotionPlanner, result) -> tuple[bool, float]:
    """Plain damped-least-squares IK (no constraints) tracking the same EE path."""
    model, data = planner.robot.model, planner.robot.model.createData()
    ee = planner.robot.frame_id('j2s7s300_end_effector')
    q = READY.copy()
    start = time.perf_counter()
    ok = True
    for row in result.ee_path[1:]:
        target = pin.XYZQUATToSE3(row)
        for _ in range(10):
            pin.framesForwardKinematics(model, data, q)
            err = pin.log6(data.oMf[ee].actInv(target)).vector
            if np.linalg.norm(err) < 1e-3:
                break
            J = pin.computeFrameJacobian(model, data, q, ee, pin.LOCAL)
            q = q + J.T @ np.linalg.solve(J @ J.T + 1e-3 * np.eye(6), err)
        ok &= bool(np.linalg.norm(err) < 1e-2)
    ok &= bool(np.all(q >= planner.robot.limits.lower) and np.all(q <= planner.robot.limits.upper))
    return ok, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--quick', action='store_true', help='short run (a few seconds)')
    args = parser.parse_args()
    scenes = [load_scenario(n) for n in ('s1', 's2', 's3')]
    scenes += [generate_clutter(8, 0.3, seed) for seed in range(1 if args.quick else 3)]
    episodes = 20 if args.quick else 200
    rows, times, stages, peer = [], [], {'sampling': [], 'stpik': [], 'collision': []}, []
    for scene in tqdm(scenes, desc='scenes'):
        planner = MotionPlanner(scene)
        start = time.perf_counter()
        level, sets = exact_levels(planner, 3 if args.quick else 7)
        query_stream(planner, episodes, 0)
        results = list(planner.cache._results.values())
        for r in results:
            times.append(r.planning_time)
            for k in stages:
                stages[k].append(r.timings.get(k, 0.0))
            if r.feasible and len(peer) < 30:
                peer.append(dls_peer(planner, r))
        rows.append(
            {
                'scene': scene.name,
                'obstacles': len(scene.obstacles),
                'optimal_level': level,
                'feasible_sets': sets,
                'planner_runs': planner.cache.misses,
                'cache_hit_rate': round(planner.cache.hit_rate, 3),
                'wall_s': round(time.perf_counter() - start, 2),
            }
        )
    ms = np.array(times) * 1e3
    summary = {
        'checks': len(ms),
        'median_ms': float(np.median(ms)),
        'p95_ms': float(np.percentile(ms, 95)),
        'stage_median_ms': {k: float(np.median(v) * 1e3) for k, v in stages.items()},
        'stage_mean_ms': {k: float(np.mean(v) * 1e3) for k, v in stages.items()},
        'dls_peer_success': float(np.mean([p[0] for p in peer])) if peer else None,
        'dls_peer_median_ms': float(np.median([p[1] for p in peer]) * 1e3) if peer else None,
        'scenes': rows,
        'quick': args.quick,
    }
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / 'motion_planner.json').write_text(json.dumps(summary, indent=2))
    lines = [
        '# Motion planner benchmark',
        '',
        f'{summary["checks"]} uncached checks: median '
        f'{summary["median_ms"]:.1f} ms, p95 {summary["p95_ms"]:.1f} ms.',
        '',
        '| stage | median ms | mean ms |',
        '|---|---|---|',
    ]
    lines += [
        f'| {k} | {summary["stage_median_ms"][k]:.1f} | {summary["stage_mean_ms"][k]:.1f} |'
        for k in stages
    ]
    lines += [
        '',
        f'DLS IK peer (no constraints) on the same EE paths: success '
        f'{summary["dls_peer_success"]}, median {summary["dls_peer_median_ms"]} ms.',
        '',
        '| scene | obstacles | optimal level | feasible sets | runs | hit rate | wall s |',
        '|---|---|---|---|---|---|---|',
    ]
    lines += [
        f'| {r["scene"]} | {r["obstacles"]} | {r["optimal_level"]} | {r["feasible_sets"]} |'
        f' {r["planner_runs"]} | {r["cache_hit_rate"]} | {r["wall_s"]} |'
        for r in rows
    ]
    (OUT / 'motion_planner.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))


if __name__ == '__main__':
    main()
