#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.bench_false_infeasible` (``--help``)."""

import sys

from qtree_benchmarks.cli import bench_false_infeasible

if __name__ == '__main__':
    sys.exit(bench_false_infeasible.main())
