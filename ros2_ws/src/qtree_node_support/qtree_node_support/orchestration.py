"""Start, supervise and stop qtree-tamp nodes as separate processes, the way ``ros2 run`` does.

No rclpy import here: this module only resolves executables and manages processes, so the demo,
the benchmark (``--ros``) and the cross-process tests share one tested way of starting nodes.

Resolution rule (what ``ros2 run PKG EXE`` does): when a ``ros2`` command is on ``PATH`` the node
is started with ``ros2 run``; otherwise the executable ``<prefix>/lib/<pkg>/<exe>`` is found
through ``ament_index_python.get_package_prefix`` and started directly.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

ROS_DOMAIN_ID_RANGE = (10, 100)  # valid on Linux without port clashes: 0..101
_DOMAIN_COUNTER_FILE = Path(tempfile.gettempdir()) / 'qtree_tamp_domain_ids'


class LaunchError(RuntimeError):
    """A node could not be found, started or did not become ready."""


def allocate_domain_id() -> int:
    """Return a ROS_DOMAIN_ID not handed out recently on this machine (a file-locked counter).

    Parallel test workers and concurrent demos each get their own domain so their graphs never
    see each other.
    """
    low, high = ROS_DOMAIN_ID_RANGE
    with open(_DOMAIN_COUNTER_FILE, 'a+') as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        handle.seek(0)
        text = handle.read().strip()
        last = int(text) if text.isdigit() else low - 1
        value = last + 1 if low <= last + 1 <= high else low
        handle.seek(0)
        handle.truncate()
        handle.write(str(value))
    return value


def format_parameter(value: Any) -> str:
    """Format a Python value as a ``-p name:=value`` literal (YAML, as ``ros2 run`` parses it)."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, (list, tuple)):
        return '[' + ', '.join(format_parameter(v) for v in value) + ']'
    if isinstance(value, str):
        return "'" + value.replace("'", "''") + "'"
    return repr(value)


def node_command(
    package: str,
    executable: str,
    parameters: dict[str, Any] | None = None,
    ros_args: list[str] | None = None,
) -> list[str]:
    """Return the command line that starts ``executable`` of ``package`` like ``ros2 run``.

    Raises:
        LaunchError: the package or executable is not installed.
    """
    extra: list[str] = []
    if parameters or ros_args:
        extra.append('--ros-args')
        for name, value in (parameters or {}).items():
            extra += ['-p', f'{name}:={format_parameter(value)}']
        extra += ros_args or []
    ros2 = shutil.which('ros2')
    if ros2 is not None:
        return [ros2, 'run', package, executable, *extra]
    try:
        from ament_index_python.packages import PackageNotFoundError, get_package_prefix
    except ImportError as err:  # pragma: no cover - only without any ROS environment
        raise LaunchError('ament_index_python is not importable: source env.sh first') from err
    try:
        prefix = get_package_prefix(package)
    except PackageNotFoundError:
        message = f"package '{package}' not found in the ament index (is env.sh sourced?)"
        raise LaunchError(message) from None
    path = Path(prefix) / 'lib' / package / executable
    if not path.is_file() or not os.access(path, os.X_OK):
        raise LaunchError(f"no executable '{executable}' in {path.parent}")
    return [str(path), *extra]


@dataclass
class NodeProcess:
    """One started node: its command, process and log file."""

    name: str
    command: list[str]
    log_path: Path
    process: subprocess.Popen[bytes]
    _log: IO[bytes] = field(repr=False)

    def alive(self) -> bool:
        """True while the process runs."""
        return self.process.poll() is None

    def log_text(self) -> str:
        """Everything the node wrote to stdout and stderr so far (also after :meth:`stop`)."""
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors='replace')

    def wait_for_log(self, text: str, timeout_s: float = 20.0) -> None:
        """Block until ``text`` appears in the node's output.

        Raises:
            LaunchError: the node exited or the text did not appear in time.
        """
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if text in self.log_text():
                return
            if not self.alive():
                raise LaunchError(
                    f'{self.name} exited with {self.process.returncode} before '
                    f'printing {text!r}:\n{self.log_text()[-3000:]}'
                )
            time.sleep(0.05)
        raise LaunchError(
            f'{self.name} did not print {text!r} within {timeout_s} s:\n{self.log_text()[-3000:]}'
        )

    def stop(self, timeout_s: float = 10.0, sig: int = signal.SIGINT) -> int:
        """Send ``sig`` (SIGINT: Ctrl-C), SIGKILL after ``timeout_s``; return the exit code."""
        if self.alive():
            self.process.send_signal(sig)
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.process.send_signal(signal.SIGUSR1)  # the node dumps its thread stacks
                time.sleep(1.0)
                self.process.kill()
                self.process.wait()
        self._log.close()
        return int(self.process.returncode)

    def kill(self) -> None:
        """SIGKILL the node (fault injection)."""
        if self.alive():
            self.process.kill()
            self.process.wait()


def start_node(
    package: str,
    executable: str,
    *,
    name: str | None = None,
    parameters: dict[str, Any] | None = None,
    ros_args: list[str] | None = None,
    env: dict[str, str] | None = None,
    log_dir: Path | None = None,
) -> NodeProcess:
    """Start one node as a separate process; its output goes to ``log_dir/<name>.log``."""
    command = node_command(package, executable, parameters, ros_args)
    name = name or executable
    log_dir = Path(log_dir or tempfile.mkdtemp(prefix='qtree_logs_'))
    log_dir.mkdir(parents=True, exist_ok=True)
    log_path = log_dir / f'{name}.log'
    log = open(log_path, 'wb')  # noqa: SIM115 - closed in NodeProcess.stop
    full_env = dict(os.environ if env is None else env)
    full_env.setdefault('PYTHONUNBUFFERED', '1')
    full_env.setdefault('RCUTILS_COLORIZED_OUTPUT', '0')
    process = subprocess.Popen(
        command,
        stdout=log,
        stderr=subprocess.STDOUT,
        env=full_env,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
    )
    return NodeProcess(name, command, log_path, process, log)


def stop_all(nodes: list[NodeProcess], timeout_s: float = 10.0) -> dict[str, int]:
    """Stop nodes in reverse start order; return each node's exit code."""
    return {node.name: node.stop(timeout_s) for node in reversed(nodes)}


def python_executable() -> str:
    """The interpreter running this script (the set-up virtual environment's)."""
    return sys.executable
