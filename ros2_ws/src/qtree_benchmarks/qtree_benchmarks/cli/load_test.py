"""Load test: concurrent RelocateObject clients against a live motion planner.

Starts ``sim_node`` and ``motion_planner_node`` in a private ROS domain, then runs N client
processes for a fixed duration, each sending a mix of valid requests (random object, random set of
already relocated obstacles) and invalid ones (unknown id, duplicate ids, the target among the
relocated ids, an object listed as already relocated, an empty id). Every answer is checked
against the reason codes it may carry; latency percentiles are printed and written to JSON.

Exit code 0 when every answer carried an expected code and both nodes are alive at the end.

Example:
    ./qtree run python scripts/load_test.py --clients 8 --duration 30
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import random
import sys
import time
from pathlib import Path
from queue import Empty
from typing import Any

from qtree_node_support.orchestration import allocate_domain_id, start_node, stop_all

# name -> (request builder label, codes the answer may carry)
PLANNING_CODES = {0, 201, 202, 203, 204, 205, 301, 303}  # 303: PLANNER_BUSY
INVALID_CASES = {
    'unknown_object': {101},
    'duplicate_ids': {103},
    'target_in_relocated': {103},
    'already_relocated': {102},
    'empty_id': {103},
}


def build_request(kind: str, rng: random.Random, obstacles: list[str], target: str) -> Any:
    """One RelocateObject request of the given kind."""
    from qtree_msgs.srv import RelocateObject

    request = RelocateObject.Request()
    if kind == 'valid':
        relocated = rng.sample(obstacles, rng.randint(0, min(4, len(obstacles))))
        remaining = [o for o in obstacles if o not in relocated] + [target]
        request.object_id = rng.choice(remaining)
        request.relocated_ids = relocated
    elif kind == 'unknown_object':
        request.object_id = 'no_such_object'
    elif kind == 'duplicate_ids':
        request.object_id = target
        request.relocated_ids = [obstacles[0], obstacles[0]]
    elif kind == 'target_in_relocated':
        request.object_id = obstacles[0]
        request.relocated_ids = [target]
    elif kind == 'already_relocated':
        request.object_id = obstacles[0]
        request.relocated_ids = [obstacles[0]]
    elif kind == 'empty_id':
        request.object_id = ''
    return request


def client_worker(index: int, domain_id: int, duration_s: float, ids: dict, out: Any) -> None:
    """One client process: send requests in a loop for ``duration_s``; put results in ``out``."""
    import rclpy
    from qtree_msgs.srv import RelocateObject
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    rng = random.Random(index)
    context = Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = rclpy.create_node(f'load_client_{index}', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    client = node.create_client(RelocateObject, '/relocate_object')
    records: list[tuple[str, int, float, bool, bool]] = []
    try:
        if not client.wait_for_service(timeout_sec=30.0):
            out.put({'index': index, 'error': 'service not available'})
            return
        deadline = time.monotonic() + duration_s
        while time.monotonic() < deadline:
            kind = 'valid' if rng.random() < 0.6 else rng.choice(sorted(INVALID_CASES))
            request = build_request(kind, rng, ids['obstacles'], ids['target'])
            start = time.perf_counter()
            future = client.call_async(request)
            while not future.done() and time.monotonic() < deadline + 30.0:
                executor.spin_once(timeout_sec=0.05)
            latency = time.perf_counter() - start
            if not future.done():
                records.append((kind, -1, latency, False, False))
                continue
            response = future.result()
            allowed = PLANNING_CODES if kind == 'valid' else INVALID_CASES[kind]
            ok = response.reason in allowed and response.feasible == (response.reason == 0)
            records.append((kind, int(response.reason), latency, ok, bool(response.from_cache)))
        out.put({'index': index, 'records': records})
    except Exception as err:  # report, never hang the parent on queue.get
        out.put({'index': index, 'error': f'{type(err).__name__}: {err}', 'records': records})
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def rss_mb(pid: int) -> float:
    """Resident memory [MB] of ``pid`` and its descendants (``/proc/<pid>/status`` VmRSS)."""
    total_kb, stack = 0, [pid]
    while stack:
        current = stack.pop()
        try:
            status = Path(f'/proc/{current}/status').read_text()
            children = Path(f'/proc/{current}/task/{current}/children').read_text().split()
        except OSError:
            continue
        rss = [line.split()[1] for line in status.splitlines() if line.startswith('VmRSS:')]
        total_kb += int(rss[0]) if rss else 0
        stack += [int(child) for child in children]
    return round(total_kb / 1024, 1)


def _ms(value: float | None) -> str:
    return '    n/a' if value is None else f'{value:7.1f} ms'


def percentile(values: list[float], q: float) -> float | None:
    """The q-th percentile (0..100) of ``values`` by nearest rank; None when empty."""
    if not values:
        return None
    ordered = sorted(values)
    rank = min(len(ordered) - 1, max(0, round(q / 100 * (len(ordered) - 1))))
    return ordered[rank]


def summarise(records: list[tuple], duration_s: float) -> dict[str, Any]:
    """Latency percentiles [ms] and counts per request kind."""
    summary: dict[str, Any] = {'requests': len(records), 'duration_s': duration_s}
    summary['throughput_per_s'] = len(records) / duration_s
    summary['unexpected'] = [r for r in records if not r[3]][:20]
    for kind in ['valid', *sorted(INVALID_CASES)]:
        latencies = [r[2] * 1000 for r in records if r[0] == kind]
        summary[kind] = {
            'count': len(latencies),
            'p50_ms': percentile(latencies, 50),
            'p95_ms': percentile(latencies, 95),
            'p99_ms': percentile(latencies, 99),
            'max_ms': max(latencies, default=None),
            'codes': sorted({r[1] for r in records if r[0] == kind}),
            'from_cache': sum(r[4] for r in records if r[0] == kind),
        }
    all_latencies = [r[2] * 1000 for r in records]
    summary['all'] = {f'p{q}_ms': percentile(all_latencies, q) for q in (50, 95, 99)}
    summary['all']['max_ms'] = max(all_latencies, default=None)
    return summary


def main(argv: list[str] | None = None) -> int:
    """Run the load test; return the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--clients', type=int, default=8, help='concurrent client processes')
    parser.add_argument('--duration', type=float, default=30.0, help='seconds of load')
    parser.add_argument('--scenario', default='s1', help='scenario loaded by the simulator')
    parser.add_argument(
        '--output',
        type=Path,
        default=Path('benchmarks/results/load_test.json'),
        help='JSON file for the figures',
    )
    args = parser.parse_args(argv)
    if args.clients < 1 or args.duration <= 0:
        parser.error('--clients must be >= 1 and --duration > 0')

    from qtree_scene.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    ids = {'obstacles': [o.id for o in scenario.obstacles], 'target': scenario.target.id}
    domain_id = allocate_domain_id()
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    logs = Path('runs/load_test_logs')
    nodes = [
        start_node(
            'jaco2_sim', 'sim_node', parameters={'scenario': args.scenario}, env=env, log_dir=logs
        ),
        start_node('stpik_motion_planner', 'motion_planner_node', env=env, log_dir=logs),
    ]
    results: list[dict[str, Any]] = []
    alive: dict[str, bool] = {}
    rss: dict[str, dict[str, float]] = {}
    try:
        for node in nodes:
            node.wait_for_log('ready', 60.0)
        nodes[1].wait_for_log('planner rebuilt', 30.0)  # the planner has the scene
        rss['before'] = {node.name: rss_mb(node.process.pid) for node in nodes}
        print(f'{args.clients} clients x {args.duration:.0f} s on domain {domain_id} ...')
        context = mp.get_context('spawn')
        queue: Any = context.Queue()
        workers = [
            context.Process(target=client_worker, args=(i, domain_id, args.duration, ids, queue))
            for i in range(args.clients)
        ]
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        for worker in workers:
            worker.start()
        deadline = time.monotonic() + args.duration + 120.0
        for _ in workers:
            try:
                results.append(queue.get(timeout=max(1.0, deadline - time.monotonic())))
            except Empty:
                results.append({'error': 'a client process sent no results'})
        for worker in workers:
            worker.join(timeout=10)
            if worker.is_alive():
                worker.kill()
        alive = {node.name: node.alive() for node in nodes}
        rss['after'] = {node.name: rss_mb(node.process.pid) for node in nodes}
    finally:
        exit_codes = stop_all(nodes)
    errors = [r['error'] for r in results if 'error' in r]
    records = [tuple(rec) for r in results for rec in r.get('records', [])]
    summary = summarise(records, args.duration)
    summary.update(
        clients=args.clients,
        scenario=args.scenario,
        nodes_alive_at_end=alive,
        node_exit_codes=exit_codes,
        rss_mb=rss,
        client_errors=errors,
    )
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(summary, indent=2) + '\n')
    print(f'requests: {summary["requests"]}  ({summary["throughput_per_s"]:.1f}/s)')
    for kind in ['valid', *sorted(INVALID_CASES)]:
        row = summary[kind]
        cells = '  '.join(f'{q} {_ms(row[q + "_ms"])}' for q in ('p50', 'p95', 'p99', 'max'))
        print(f'  {kind:22s} n={row["count"]:5d}  {cells}  codes {row["codes"]}')
    print(
        f'unexpected answers: {len(summary["unexpected"])}; nodes alive: {alive}; '
        f'exit codes: {exit_codes}; RSS [MB]: {rss}; client errors: {errors}; '
        f'written to {args.output}'
    )
    clean_exit = all(code == 0 for code in exit_codes.values())
    ok = not summary['unexpected'] and all(alive.values()) and clean_exit and not errors
    ok = ok and bool(records)
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
