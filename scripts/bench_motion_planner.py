#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.bench_motion_planner` (``--help``)."""

import sys

from qtree_benchmarks.cli import bench_motion_planner

if __name__ == '__main__':
    sys.exit(bench_motion_planner.main())
