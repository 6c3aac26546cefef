"""Soak checks (#18): the node tests run N times in a row, repeated node stops, a CPU hog.

No rclpy import: nodes and pytest run as child processes (:mod:`orchestration`), so the checks see
exactly what a user sees. :func:`stop_rounds` starts the four nodes of the graph together in a
private ROS domain, waits until each is ready (plus a short random delay, so the stop meets a
running graph), stops every one with SIGINT or SIGTERM and records each exit code.
:func:`repeat_tests` runs pytest on the given paths N times (optionally under :func:`cpu_hog`) and
records which tests failed in which run. ``scripts/soak.py`` is the command line.
"""

from __future__ import annotations

import contextlib
import getpass
import multiprocessing as mp
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

from qtree_node_support.orchestration import NodeProcess, allocate_domain_id, start_node

from qtree_benchmarks.paths import repo_root

REPO_ROOT = repo_root()
NODE_TESTS = (  # the node tests; tests/test_node_shutdown.py is what stop_rounds repeats
    'tests/test_sim_node.py',
    'tests/test_motion_planner_node.py',
    'tests/test_task_planner_node.py',
)
READY_S = 120.0  # longest wait for a node's 'ready' line on a loaded machine [s]
STOP_S = 20.0  # longest wait for a node to exit after the signal, then SIGKILL [s]
SIGNALS = {'SIGINT': signal.SIGINT, 'SIGTERM': signal.SIGTERM}


def graph_nodes(output_dir: Path) -> list[tuple[str, str, dict[str, Any]]]:
    """(package, executable, parameters) of the four nodes; the sim at 1 kHz (most timer races)."""
    return [
        ('jaco2_sim', 'sim_node', {'scenario': 's1', 'sim_rate_hz': 1000.0}),
        ('stpik_motion_planner', 'motion_planner_node', {}),
        ('qtree_task_planner', 'task_planner_node', {}),
        ('qtree_recorder', 'recorder_node', {'output_dir': str(output_dir)}),
    ]


def stop_graph_once(
    sig: int, log_dir: Path, rng: random.Random, env: dict[str, str] | None = None
) -> dict[str, int]:
    """Start the four nodes, wait until ready, stop each with ``sig``; exit code by executable.

    A node that does not exit within ``STOP_S`` is SIGKILLed and counted with its code (-9).
    """
    env = dict(os.environ if env is None else env)
    env.setdefault('ROS_DOMAIN_ID', str(allocate_domain_id()))
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    nodes: list[NodeProcess] = []
    try:
        for package, executable, parameters in graph_nodes(log_dir / 'mcap'):
            nodes.append(
                start_node(package, executable, parameters=parameters, env=env, log_dir=log_dir)
            )
        for node in nodes:
            node.wait_for_log('ready', READY_S)
        time.sleep(rng.uniform(0.0, 0.5))
        codes = {}
        for node in nodes:
            codes[node.name] = node.stop(STOP_S, sig=sig)
            if codes[node.name] != 0:
                tail = node.log_text()[-1500:]
                print(f'\n{node.name} exited with {codes[node.name]} on {sig!r}:\n{tail}')
        return codes
    finally:
        for node in nodes:
            node.stop(STOP_S)


def stop_rounds(
    stops: int, log_root: Path, seed: int = 0, progress: Callable[[], Any] | None = None
) -> dict[str, dict[str, list[int]]]:
    """``stops`` rounds per signal (SIGINT, SIGTERM alternating) of :func:`stop_graph_once`.

    Returns:
        ``{executable: {'SIGINT': [codes], 'SIGTERM': [codes]}}``, ``stops`` codes in each list.
    """
    rng = random.Random(seed)
    codes: dict[str, dict[str, list[int]]] = {}
    for i in range(stops):
        for name, sig in SIGNALS.items():
            round_codes = stop_graph_once(sig, log_root / f'{name}_{i}', rng)
            for executable, code in round_codes.items():
                codes.setdefault(executable, {n: [] for n in SIGNALS})[name].append(code)
            if progress is not None:
                progress()
    return codes


def _burn(stop_at: float) -> None:
    x = 0
    while time.monotonic() < stop_at:
        x = (x * 31 + 7) % 1_000_003


@contextlib.contextmanager
def cpu_hog(processes: int, limit_s: float = 24 * 3600.0) -> Iterator[None]:
    """Keep ``processes`` busy-looping processes running (one per core loads both cores)."""
    stop_at = time.monotonic() + limit_s
    ctx = mp.get_context('spawn')
    workers = [ctx.Process(target=_burn, args=(stop_at,), daemon=True) for _ in range(processes)]
    for worker in workers:
        worker.start()
    try:
        yield
    finally:
        for worker in workers:
            worker.terminate()
            worker.join(5.0)


def failed_tests(junit_xml: Path) -> list[str]:
    """Node ids (``file::test``) of the failed or erroring test cases of a JUnit XML report."""
    if not junit_xml.is_file():
        return ['<no report: pytest did not finish>']
    failed = []
    for case in ET.parse(junit_xml).getroot().iter('testcase'):
        if case.find('failure') is not None or case.find('error') is not None:
            path = case.get('classname', '').replace('.', '/')
            failed.append(f'{path}.py::{case.get("name")}')
    return failed


def run_pytest(paths: list[str], junit_xml: Path, extra: list[str] | None = None) -> int:
    """Run pytest on ``paths`` as a child process (quiet); return its exit code."""
    command = [
        sys.executable,
        '-m',
        'pytest',
        '-q',
        '-p',
        'no:randomly',
        f'--junitxml={junit_xml}',
    ]
    command += [*(extra or []), *paths]
    with open(junit_xml.with_suffix('.log'), 'wb') as log:
        return subprocess.call(command, cwd=REPO_ROOT, stdout=log, stderr=subprocess.STDOUT)


Outcome = tuple[int, list[str], bool]  # a run's exit code, the tests it failed, whether it passed
_R = TypeVar('_R')


def repeat_runs(
    runs: int,
    run: Callable[[int], _R],
    judge: Callable[[int, _R], Outcome],
    progress: Callable[[int, list[str]], Any] | None = None,
    checkpoint: Callable[[dict[str, Any]], Any] | None = None,
) -> dict[str, Any]:
    """``run(i)`` for i in 0..runs-1 in a row, each timed, then judged by ``judge(i, done)``.

    ``checkpoint`` (optional) receives the tally of the runs done so far after each run, so a
    soak of hours that is cut short still leaves its figures.

    Returns:
        ``runs``, ``passed`` (runs judged passed), ``failed_tests`` (test id → number of runs it
        failed in), ``exit_codes`` and ``run_seconds`` (one per run; ``run`` alone is timed).
    """
    failures: Counter[str] = Counter()
    passed = 0
    seconds: list[float] = []
    codes: list[int] = []

    def tally(done_runs: int) -> dict[str, Any]:
        return {
            'runs': done_runs,
            'passed': passed,
            'failed_tests': dict(failures),
            'exit_codes': list(codes),
            'run_seconds': list(seconds),
        }

    for i in range(runs):
        start = time.monotonic()
        done = run(i)
        seconds.append(round(time.monotonic() - start, 1))
        code, failed, ok = judge(i, done)
        codes.append(code)
        passed += ok
        failures.update(failed)
        if progress is not None:
            progress(i, failed)
        if checkpoint is not None and i + 1 < runs:
            checkpoint(tally(i + 1))
    return tally(runs)


def repeat_tests(
    paths: list[str],
    runs: int,
    work_dir: Path,
    progress: Callable[[int, list[str]], Any] | None = None,
) -> dict[str, Any]:
    """Run pytest on ``paths`` ``runs`` times in a row.

    Returns:
        ``runs``, ``passed`` (runs with every test green), ``failed_tests`` (node id → number
        of runs it failed in), ``run_seconds`` and ``exit_codes`` (one per run).
    """
    work_dir.mkdir(parents=True, exist_ok=True)

    def judge(i: int, code: int) -> Outcome:
        failed = failed_tests(work_dir / f'run_{i}.xml')
        return code, failed, code == 0 and not failed

    return repeat_runs(
        runs, lambda i: run_pytest(paths, work_dir / f'run_{i}.xml'), judge, progress
    )


def repeat_tests_parallel(
    paths: list[str],
    runs: int,
    work_dir: Path,
    sequences: int,
    progress: Callable[[int, list[str]], Any] | None = None,
) -> dict[str, Any]:
    """:func:`repeat_tests` as ``sequences`` concurrent sequences sharing ``runs`` between them
    (each sequence runs in a row; the runs load each other, like a second user of the machine).

    Returns:
        The keys of :func:`repeat_tests`, summed over the sequences, and ``sequences``.
    """
    from concurrent.futures import ThreadPoolExecutor

    shares = [runs // sequences + (k < runs % sequences) for k in range(sequences)]
    with ThreadPoolExecutor(sequences) as pool:
        parts = list(
            pool.map(
                lambda k: repeat_tests(paths, shares[k], work_dir / f'seq{k}', progress),
                range(sequences),
            )
        )
    failures: Counter[str] = Counter()
    for part in parts:
        failures.update(part['failed_tests'])
    return {
        'runs': sum(p['runs'] for p in parts),
        'passed': sum(p['passed'] for p in parts),
        'failed_tests': dict(failures),
        'exit_codes': [c for p in parts for c in p['exit_codes']],
        'run_seconds': [t for p in parts for t in p['run_seconds']],
        'sequences': sequences,
    }


FRESH_CLONE_COMMAND = ['./qtree', 'test']  # the README's test command, verbatim
SUMMARY_LINE = re.compile(r'^(?:FAILED|ERROR) (\S+?)(?: - |$)')


def clean_environment() -> dict[str, str]:
    """The environment of a new login shell: no venv, ROS or Python path of this one."""
    keep = ('HOME', 'USER', 'LANG', 'LC_ALL', 'TERM', 'TMPDIR')
    env = {k: os.environ[k] for k in keep if k in os.environ}
    env['PATH'] = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'
    return env


def summary_failures(output: str) -> list[str]:
    """Test ids named FAILED or ERROR in pytest's short summary of ``output``."""
    return [m.group(1) for line in output.splitlines() if (m := SUMMARY_LINE.match(line))]


def fresh_clone(work_dir: Path, branch: str = 'main') -> Path:
    """Clone ``branch`` of this repository into ``work_dir/qtree-tamp`` with ``../shared`` beside
    it (a symbolic link to this checkout's), as CI has it; the clone's path.
    """
    clone = work_dir / 'qtree-tamp'
    subprocess.run(
        ['git', 'clone', '--quiet', '--branch', branch, '--single-branch', str(REPO_ROOT), clone],
        check=True,
    )
    shared = REPO_ROOT.parent / 'shared'
    if shared.exists():
        (work_dir / 'shared').symlink_to(shared.resolve())
    return clone


TRACKING_LINE = re.compile(r'worst EE error ([0-9.]+) mm / ([0-9.]+) rad')


def worst_tracking_error(root: Path) -> tuple[float, float] | None:
    """Largest closed-loop EE error (position [mm], orientation [rad]) the motion planner
    logged for a segment in any node log under ``root`` (``segment ... worst EE error``), or
    None when no log has one.
    """
    worst: tuple[float, float] | None = None
    for log in root.rglob('*.log') if root.is_dir() else ():
        with contextlib.suppress(OSError):
            for m in TRACKING_LINE.finditer(log.read_text(errors='replace')):
                mm, rad = float(m.group(1)), float(m.group(2))
                worst = (mm, rad) if worst is None else (max(worst[0], mm), max(worst[1], rad))
    return worst


def pytest_current_dir() -> Path:
    """The base temporary directory of pytest's latest session (``pytest-current``)."""
    # pytest names it after getpass.getuser() (the password database when USER is unset: the
    # soak of 3e26e43 looked in pytest-of-0 and found no tracking error in any run)
    return Path(tempfile.gettempdir()) / f'pytest-of-{getpass.getuser()}' / 'pytest-current'


def repeat_fresh_clone(
    runs: int,
    work_dir: Path,
    progress: Callable[[int, list[str]], Any] | None = None,
    branch: str = 'main',
    checkpoint: Callable[[dict[str, Any]], Any] | None = None,
) -> dict[str, Any]:
    """Run the README's ``./qtree test`` ``runs`` times in a row on a fresh clone of ``branch``.

    The first run sets the clone up from scratch (as on a new machine); each run's output is
    kept in ``work_dir/fresh_run_<i>.log``. After each run the node logs of pytest's session are
    read for the worst closed-loop tracking error (the figure behind the node tests'
    ``max_tracking_error_m``, docs/RELIABILITY.md).

    Returns:
        ``fresh_clone_runs``, ``fresh_clone_passed``, ``fresh_clone_failed_tests`` (test id →
        runs it failed in), ``fresh_clone_exit_codes``, ``fresh_clone_run_seconds``,
        ``fresh_clone_worst_tracking_error_mm`` / ``_rad`` (per run, None when not logged) and
        ``commit`` (of the clone). ``checkpoint`` receives the same keys after each run.
    """
    work_dir.mkdir(parents=True, exist_ok=True)
    clone = fresh_clone(work_dir, branch)
    commit = subprocess.run(
        ['git', 'rev-parse', 'HEAD'], cwd=clone, capture_output=True, text=True
    ).stdout.strip()

    def run(i: int) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            FRESH_CLONE_COMMAND,
            cwd=clone,
            env=clean_environment(),
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )

    worst_mm: list[float | None] = []
    worst_rad: list[float | None] = []

    def judge(i: int, done: subprocess.CompletedProcess[str]) -> Outcome:
        (work_dir / f'fresh_run_{i}.log').write_text(done.stdout)
        worst = worst_tracking_error(pytest_current_dir())
        worst_mm.append(None if worst is None else worst[0])
        worst_rad.append(None if worst is None else worst[1])
        failed = summary_failures(done.stdout)
        if done.returncode != 0 and not failed:
            failed = [f'<exit code {done.returncode}, no test named: see fresh_run_{i}.log>']
        return done.returncode, failed, done.returncode == 0

    def keyed(tally: dict[str, Any]) -> dict[str, Any]:
        done_runs = tally['runs']
        return {
            **{f'fresh_clone_{key}': value for key, value in tally.items()},
            'fresh_clone_worst_tracking_error_mm': worst_mm[:done_runs],
            'fresh_clone_worst_tracking_error_rad': worst_rad[:done_runs],
            'commit': commit,
        }

    partial = None if checkpoint is None else (lambda tally: checkpoint(keyed(tally)))
    return keyed(repeat_runs(runs, run, judge, progress, partial))


def default_work_dir() -> Path:
    """A fresh directory for logs and JUnit reports."""
    return Path(tempfile.mkdtemp(prefix='qtree_soak_'))
