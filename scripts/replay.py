#!/usr/bin/env python3
"""Entry point of :mod:`qtree_recorder.replay_cli` (``--help``)."""

import sys

from qtree_recorder import replay_cli

if __name__ == '__main__':
    sys.exit(replay_cli.main())
