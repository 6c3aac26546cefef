#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.bench_live` (``--help``)."""

import sys

from qtree_benchmarks.cli import bench_live

if __name__ == '__main__':
    sys.exit(bench_live.main())
