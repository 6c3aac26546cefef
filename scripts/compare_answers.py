#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.compare_answers` (``--help``)."""

import sys

from qtree_benchmarks.cli import compare_answers

if __name__ == '__main__':
    sys.exit(compare_answers.main())
