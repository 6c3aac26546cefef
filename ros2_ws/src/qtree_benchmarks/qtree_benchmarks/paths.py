"""Where the repository's files are, for the benchmarks and tools run from a checkout."""

from __future__ import annotations

import os
from pathlib import Path


def repo_root() -> Path:
    """The qtree-tamp checkout these tools write into.

    ``QTREE_ROOT`` (exported by ``env.sh``) when set; otherwise the checkout holding this file
    (the colcon build links the installed modules back to ``ros2_ws/src``).

    Raises:
        RuntimeError: neither names a checkout (no ``ros2_ws`` directory there).
    """
    env = os.environ.get('QTREE_ROOT')
    candidates = [Path(env)] if env else []
    candidates += list(Path(__file__).resolve().parents)
    for candidate in candidates:
        if (candidate / 'ros2_ws' / 'src').is_dir() and (candidate / 'benchmarks').is_dir():
            return candidate
    raise RuntimeError(
        'cannot find the qtree-tamp checkout: source env.sh (it sets QTREE_ROOT) and run again'
    )


def results_dir() -> Path:
    """``benchmarks/results`` of the checkout: every benchmark writes its JSON/MD/PNG here."""
    return repo_root() / 'benchmarks' / 'results'
