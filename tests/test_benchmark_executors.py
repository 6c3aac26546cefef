"""scripts/benchmark.py gives the same trainings on a process pool, a local Ray instance and the
ROS graph.

Every training is seeded, so the executor must not change a single figure.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARK = Path(__file__).resolve().parents[1] / 'scripts' / 'benchmark.py'
FIELDS = ('seed', 'sequence', 'episodes', 'mp_calls', 'first_optimal_episode', 'converged')


def _run(out: Path, *extra: str) -> list[dict]:
    command = [sys.executable, str(BENCHMARK), '--trainings', '3', '--scenarios', 's1',
               '--policies', 'H-EG', 'H-EG-SET', '--out', str(out), *extra]  # fmt: skip
    done = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=out.parent)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    records = json.loads((out / 'benchmark.json').read_text())['records']
    return sorted(({k: r[k] for k in ('policy', *FIELDS)} for r in records), key=str)


def test_ray_and_process_pool_agree(tmp_path: Path) -> None:
    pytest.importorskip('ray')
    pool = _run(tmp_path / 'pool', '--workers', '2')
    ray = _run(tmp_path / 'ray', '--workers', '1', '--ray', 'local')
    assert len(pool) == 6
    assert pool == ray
    assert all(len(r['sequence']) == 4 for r in pool), 'S1 optimum: 3 obstacles + target'


def test_ros_graph_and_in_process_agree(tmp_path: Path) -> None:
    """The same seeded trainings through sim + motion planner + task planner as processes."""
    in_process = _run(tmp_path / 'in_process', '--workers', '1')
    graph = _run(tmp_path / 'graph', '--ros')
    assert graph == in_process
    meta = json.loads((tmp_path / 'graph' / 'benchmark.json').read_text())['meta']
    assert 'ROS graph' in meta['oracle']
