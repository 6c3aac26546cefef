#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.run_demo` (``--help``)."""

import sys

from qtree_benchmarks.cli import run_demo

if __name__ == '__main__':
    sys.exit(run_demo.main())
