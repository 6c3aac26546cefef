#!/usr/bin/env python3
"""Entry point of :mod:`qtree_benchmarks.cli.paper_fidelity` (``--help``)."""

import sys

from qtree_benchmarks.cli import paper_fidelity

if __name__ == '__main__':
    sys.exit(paper_fidelity.main())
