"""#26: the fresh-clone soak reads pytest's summary and runs in a clean shell's environment."""

from __future__ import annotations

import pathlib
import subprocess
import tempfile
from collections.abc import Iterator

import pytest
from qtree_benchmarks.soak import (
    FRESH_CLONE_COMMAND,
    clean_environment,
    fresh_clone,
    pytest_current_dir,
    repeat_runs,
    summary_failures,
    worst_tracking_error,
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


def test_a_cut_soak_leaves_the_runs_it_finished() -> None:
    seen: list[dict] = []
    outcomes = [(0, [], True), (1, ['tests/t.py::a'], False), (0, [], True)]
    tally = repeat_runs(3, lambda i: i, lambda i, done: outcomes[done], None, seen.append)
    assert [(c['runs'], c['passed'], c['failed_tests']) for c in seen] == [
        (1, 1, {}),
        (2, 1, {'tests/t.py::a': 1}),
    ]
    assert (tally['runs'], tally['passed'], tally['exit_codes']) == (3, 2, [0, 1, 0])


@pytest.fixture
def outside_session() -> Iterator[pathlib.Path]:
    """A scratch directory outside pytest's session directory.

    The soak reads every log under that directory after a run: a fake node log written there
    (a 53.1 mm line under ``tmp_path``) was each run's "worst tracking error" (soak of 1751b84).
    """
    with tempfile.TemporaryDirectory() as scratch:
        root = pathlib.Path(scratch)
        assert pytest_current_dir().resolve() not in root.resolve().parents
        yield root


def test_the_worst_tracking_error_is_read_from_every_node_log(outside_session) -> None:
    root = outside_session
    assert worst_tracking_error(root / 'missing') is None
    (root / 'a' / 'logs').mkdir(parents=True)
    (root / 'a' / 'logs' / 'motion_planner_node.log').write_text(
        '[INFO] segment to sample 40 done: 310 ticks, worst EE error 4.2 mm / 0.031 rad\n'
        '[INFO] segment to sample 61 stopped: 12 ticks, worst EE error 53.1 mm / 0.116 rad\n'
    )
    (root / 'b.log').write_text(
        'segment to sample 9 done: 1 ticks, worst EE error 7.0 mm / 0.2 rad'
    )
    assert worst_tracking_error(root) == (53.1, 0.2)
    (root / 'c').mkdir()
    assert worst_tracking_error(root / 'c') is None


def test_the_node_logs_are_looked_for_where_pytest_puts_them(monkeypatch) -> None:
    import getpass

    monkeypatch.delenv('USER', raising=False)
    monkeypatch.delenv('LOGNAME', raising=False)
    assert pytest_current_dir().parent.name == f'pytest-of-{getpass.getuser()}'
