#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.bench_execution` (``--help``)."""

import sys

from qtree_benchmarks.cli import bench_execution

if __name__ == '__main__':
    sys.exit(bench_execution.main())
