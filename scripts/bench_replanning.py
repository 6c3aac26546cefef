#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.bench_replanning` (``--help``)."""

import sys

from qtree_benchmarks.cli import bench_replanning

if __name__ == '__main__':
    sys.exit(bench_replanning.main())
