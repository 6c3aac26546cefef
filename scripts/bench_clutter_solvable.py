#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.bench_clutter_solvable` (``--help``)."""

import sys

from qtree_benchmarks.cli import bench_clutter_solvable

if __name__ == '__main__':
    sys.exit(bench_clutter_solvable.main())
