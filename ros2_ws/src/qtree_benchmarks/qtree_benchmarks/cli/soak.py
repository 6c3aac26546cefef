"""Soak (#18): the node tests N times in a row, repeated SIGINT/SIGTERM stops of every node, and
optionally the whole suite under a CPU hog on both cores. Writes benchmarks/results/soak.json
(keys ``runs``, ``passed``, ``failed_tests``, plus ``stops``, ``hog`` and the run details).

Thin entry point over :mod:`soaking` (scripts/soaking.py).

With ``--fresh-clone`` (#26) it instead clones ``main`` into a temporary directory and runs the
README's ``./qtree test`` there exactly as written, ``--runs`` times in a row (the first run sets
the clone up from scratch), while ``--load`` busy processes hold that many cores; it updates only
the ``fresh_clone_*``, ``loaded``, ``load_processes`` and ``commit`` keys of soak.json, so the
node-stop figures of the other mode stay.

Examples:
    ./qtree run python scripts/soak.py --fresh-clone --runs 10 --load 1
    ./qtree run python scripts/soak.py --runs 10 --stops 50
    ./qtree run python scripts/soak.py --runs 0 --stops 0 --hog-runs 1   # suite under a CPU hog
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from tqdm import tqdm

from qtree_benchmarks.soak import (
    NODE_TESTS,
    REPO_ROOT,
    SIGNALS,
    cpu_hog,
    default_work_dir,
    repeat_fresh_clone,
    repeat_tests,
    repeat_tests_parallel,
    stop_rounds,
)

DEFAULT_OUTPUT = REPO_ROOT / 'benchmarks' / 'results' / 'soak.json'


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line options of ``argv`` (``sys.argv[1:]`` when None)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--runs', type=int, default=10, help='runs of the node tests (>= 0)')
    parser.add_argument('--tests', nargs='+', default=list(NODE_TESTS), help='test paths')
    parser.add_argument(
        '--parallel', type=int, default=1, help='concurrent sequences sharing the runs (>= 1)'
    )
    parser.add_argument(
        '--stops', type=int, default=50, help='stops per node, SIGINT and SIGTERM alternating'
    )
    parser.add_argument('--hog-runs', type=int, default=0, help='whole-suite runs under a hog')
    parser.add_argument('--hog-processes', type=int, default=2, help='busy loops (2 = 2 cores)')
    parser.add_argument(
        '--fresh-clone', action='store_true', help="the README's ./qtree test on a fresh clone"
    )
    parser.add_argument('--load', type=int, default=0, help='busy processes while soaking')
    parser.add_argument('--branch', default='main', help='branch cloned by --fresh-clone')
    parser.add_argument('--output', type=Path, default=DEFAULT_OUTPUT, help='JSON result file')
    args = parser.parse_args(argv)
    if args.parallel < 1:
        parser.error('--parallel must be >= 1')
    for name in ('runs', 'stops', 'hog_runs', 'hog_processes', 'load'):
        if getattr(args, name) < 0:
            parser.error(f'--{name.replace("_", "-")} must be >= 0')
    return args


def _progress(bar: tqdm):
    def update(_i: int, failed: list[str]) -> None:
        bar.update()
        if failed:
            bar.write(f'run {bar.n}: failed {failed}')

    return update


def _commit() -> str:
    try:
        out = subprocess.run(['git', 'rev-parse', 'HEAD'], cwd=REPO_ROOT, capture_output=True)
        return out.stdout.decode().strip()
    except OSError:
        return ''


def fresh_clone_main(args: argparse.Namespace) -> int:
    """``--fresh-clone``: the README's test command on a fresh clone, soak.json updated."""
    work = default_work_dir()
    previous = json.loads(args.output.read_text()) if args.output.is_file() else {}

    def write(fresh: dict, complete: bool) -> None:
        previous.update(fresh)
        previous.update(
            loaded=args.load > 0,
            load_processes=args.load,
            fresh_clone_complete=complete,  # False while runs are still to come
            fresh_clone_date_utc=time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
            fresh_clone_work_dir=str(work / 'fresh'),
        )
        args.output.parent.mkdir(parents=True, exist_ok=True)
        args.output.write_text(json.dumps(previous, indent=2) + '\n')

    with (
        cpu_hog(args.load) if args.load else contextlib.nullcontext(),
        tqdm(total=args.runs, desc=f'./qtree test on a fresh clone of {args.branch}') as bar,
    ):
        fresh = repeat_fresh_clone(
            args.runs,
            work / 'fresh',
            _progress(bar),
            args.branch,
            checkpoint=lambda partial: write(partial, complete=False),
        )
    write(fresh, complete=True)
    print(
        f'fresh clone {fresh["commit"][:10]}: {fresh["fresh_clone_passed"]}/{args.runs} runs of '
        f'./qtree test green ({"loaded, " + str(args.load) + " busy" if args.load else "idle"}); '
        f'failed: {fresh["fresh_clone_failed_tests"] or "none"}; written {args.output}'
    )
    return 0 if fresh['fresh_clone_passed'] == args.runs else 1


def main(argv: list[str] | None = None) -> int:
    """Run the soak, write ``soak.json``; exit code 0 when every run passed."""
    args = parse_args(argv)
    if args.fresh_clone:
        return fresh_clone_main(args)
    work = default_work_dir()
    result: dict = {
        'date_utc': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
        'machine': f'{platform.node()}, {os.cpu_count()} cores, shared with other work',
        'node_tests': args.tests,
        'work_dir': str(work),
        'commit': _commit(),
    }
    with tqdm(total=args.runs, desc='node-test runs', unit='run') as bar:
        result.update(
            repeat_tests_parallel(
                args.tests, args.runs, work / 'tests', args.parallel, _progress(bar)
            )
        )
    rounds = (args.stops + 1) // 2  # one SIGINT and one SIGTERM stop per round
    with tqdm(total=2 * rounds, desc='stops of the 4 nodes', unit='stop') as bar:
        codes = stop_rounds(rounds, work / 'stops', progress=bar.update)
    result['stops'] = {
        exe: {
            sig: {'stops': len(c), 'nonzero': sum(x != 0 for x in c), 'codes': sorted(set(c))}
            for sig, c in by_signal.items()
        }
        for exe, by_signal in codes.items()
    }
    result['stops_per_node'] = 2 * rounds if args.stops else 0
    if args.hog_runs:
        with (
            cpu_hog(args.hog_processes),
            tqdm(total=args.hog_runs, desc='suite under a hog') as bar,
        ):
            hog = repeat_tests(['--timeout=1200'], args.hog_runs, work / 'hog', _progress(bar))
        result['hog'] = {'processes': args.hog_processes, **hog}
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(result, indent=2) + '\n')
    stops_ok = all(v['nonzero'] == 0 for s in result['stops'].values() for v in s.values())
    print(
        f'node tests: {result["passed"]}/{result["runs"]} runs green; '
        f'failed: {result["failed_tests"] or "none"}; stops: '
        f'{"all exit 0" if stops_ok else "NONZERO exits"} '
        f'({result["stops_per_node"]} per node, {", ".join(SIGNALS)}); written {args.output}'
    )
    return 0 if result['passed'] == result['runs'] and stops_ok else 1


if __name__ == '__main__':
    sys.exit(main())
