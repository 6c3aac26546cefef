#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.planner_answers` (``--help``)."""

import sys

from qtree_benchmarks.cli import planner_answers

if __name__ == '__main__':
    sys.exit(planner_answers.main())
