#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.load_test` (``--help``)."""

import sys

from qtree_benchmarks.cli import load_test

if __name__ == '__main__':
    sys.exit(load_test.main())
