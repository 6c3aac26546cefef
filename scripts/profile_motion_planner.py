#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.profile_motion_planner` (``--help``)."""

import sys

from qtree_benchmarks.cli import profile_motion_planner

if __name__ == '__main__':
    sys.exit(profile_motion_planner.main())
