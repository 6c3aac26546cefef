#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.benchmark` (``--help``)."""

import sys

from qtree_benchmarks.cli import benchmark

if __name__ == '__main__':
    sys.exit(benchmark.main())
