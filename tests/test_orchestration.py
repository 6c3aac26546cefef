"""qtree_node_support.orchestration without ROS: a stopped node's log stays readable."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

from qtree_node_support.orchestration import NodeProcess


def _process(tmp_path: Path, code: str) -> NodeProcess:
    log_path = tmp_path / 'node.log'
    log = open(log_path, 'wb')  # noqa: SIM115 - closed by NodeProcess.stop
    command = [sys.executable, '-u', '-c', code]
    process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
    return NodeProcess('fake', command, log_path, process, log)


def test_log_text_after_stop_shows_the_last_lines(tmp_path: Path) -> None:
    node = _process(tmp_path, "print('first'); print('last words')")
    node.process.wait(10)
    assert node.stop() == 0
    # conftest's teardown quotes log_text() after stop(): it raised 'flush of closed file'
    assert node.log_text().splitlines()[-1] == 'last words'


def test_stop_sends_the_requested_signal(tmp_path: Path) -> None:
    code = (
        'import signal, sys, time\n'
        "signal.signal(signal.SIGTERM, lambda *_: (print('got SIGTERM'), sys.exit(3)))\n"
        "print('ready')\n"
        'time.sleep(30)\n'
    )
    node = _process(tmp_path, code)
    node.wait_for_log('ready', 10.0)
    assert node.stop(5.0, sig=signal.SIGTERM) == 3
    assert 'got SIGTERM' in node.log_text()
