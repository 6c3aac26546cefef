"""Regenerate the README's benchmark table and claims from the committed benchmark JSON.

Reads benchmarks/results/benchmark.json (the default command) and benchmark_sweep.json
(--paper-sweep, optional) and rewrites the block between the markers in README.md, so every
number and every "holds / does not hold" in it comes from those files.

Usage:
    python scripts/benchmark_readme.py            # rewrite README.md
    python scripts/benchmark_readme.py --print    # print the block only
    python scripts/benchmark_readme.py --check    # exit 1 if README.md is out of date
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from qtree_benchmarks.paths import repo_root
from qtree_benchmarks.task.readme import replace_section, section

REPO = repo_root()
RESULTS = REPO / 'benchmarks' / 'results'


def main(argv: list[str] | None = None) -> int:
    """Rewrite, print or check the README block; exit code."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--results', type=Path, default=RESULTS)
    parser.add_argument('--readme', type=Path, default=REPO / 'README.md')
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument('--print', action='store_true', help='print the block, write nothing')
    mode.add_argument('--check', action='store_true', help='exit 1 if the README is stale')
    args = parser.parse_args(argv)
    try:
        data = json.loads((args.results / 'benchmark.json').read_text())
    except (OSError, json.JSONDecodeError) as err:
        print(f'benchmark_readme.py: error: cannot read benchmark.json: {err}', file=sys.stderr)
        return 2
    sweep_file = args.results / 'benchmark_sweep.json'
    sweep = json.loads(sweep_file.read_text()) if sweep_file.exists() else None
    block = section(data, sweep)
    if args.print:
        print(block)
        return 0
    readme = args.readme.read_text()
    updated = replace_section(readme, block)
    if args.check:
        if updated != readme:
            print('README.md benchmark block is out of date: run scripts/benchmark_readme.py')
            return 1
        return 0
    args.readme.write_text(updated)
    print(f'updated {args.readme}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
