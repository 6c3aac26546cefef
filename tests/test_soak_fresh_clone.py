"""#26: the fresh-clone soak reads pytest's summary and runs in a clean shell's environment."""

from __future__ import annotations

import subprocess

import pytest
from qtree_benchmarks.soak import (
    FRESH_CLONE_COMMAND,
    clean_environment,
    fresh_clone,
    summary_failures,
)

OUTPUT = """\
........F...E
=========================== short test summary info ============================
FAILED tests/test_closed_loop_execution.py::test_closed_loop_removes - assert 0.00507 < 0.005
ERROR tests/test_task_planner_node.py::test_motion_planner_absent_or_dying - sim_node exited -9
FAILED tests/test_x.py::test_param[sim_node]
1 failed, 890 passed in 612.00s
"""


def test_summary_failures_names_every_failed_and_erroring_test() -> None:
    assert summary_failures(OUTPUT) == [
        'tests/test_closed_loop_execution.py::test_closed_loop_removes',
        'tests/test_task_planner_node.py::test_motion_planner_absent_or_dying',
        'tests/test_x.py::test_param[sim_node]',
    ]
    assert summary_failures('891 passed in 600 s\n') == []


def test_the_command_is_the_readmes_and_the_shell_is_clean(monkeypatch) -> None:
    from qtree_benchmarks.soak import REPO_ROOT

    assert (
        '```bash\n./qtree demo\n' + ' '.join(FRESH_CLONE_COMMAND) + '\n```'
        in (REPO_ROOT / 'README.md').read_text()
    )
    monkeypatch.setenv('VIRTUAL_ENV', '/somewhere/.venv')
    monkeypatch.setenv('AMENT_PREFIX_PATH', '/somewhere')
    env = clean_environment()
    assert 'VIRTUAL_ENV' not in env and 'AMENT_PREFIX_PATH' not in env
    assert '.venv' not in env['PATH']


def test_fresh_clone_has_main_and_shared_beside_it(tmp_path) -> None:
    from qtree_benchmarks.soak import REPO_ROOT

    head = subprocess.run(['git', 'rev-parse', 'main'], cwd=REPO_ROOT, capture_output=True)
    if head.returncode != 0:
        pytest.skip('this checkout has no main branch to clone')
    clone = fresh_clone(tmp_path)
    cloned = subprocess.run(['git', 'rev-parse', 'HEAD'], cwd=clone, capture_output=True)
    assert cloned.stdout == head.stdout and (clone / 'qtree').is_file()
    assert not (clone / '.venv').exists()  # set up from scratch by its first run
    if (REPO_ROOT.parent / 'shared').exists():
        assert (tmp_path / 'shared' / 'paper').is_dir()
