#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.design_scenarios` (``--help``)."""

import sys

from qtree_benchmarks.cli import design_scenarios

if __name__ == '__main__':
    sys.exit(design_scenarios.main())
