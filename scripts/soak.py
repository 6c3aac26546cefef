#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.soak` (``--help``)."""

import sys

from qtree_benchmarks.cli import soak

if __name__ == '__main__':
    sys.exit(soak.main())
