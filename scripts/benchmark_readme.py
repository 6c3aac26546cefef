#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.benchmark_readme` (``--help``)."""

import sys

from qtree_benchmarks.cli import benchmark_readme

if __name__ == '__main__':
    sys.exit(benchmark_readme.main())
