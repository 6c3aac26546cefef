"""Run a node until SIGINT or SIGTERM and exit 0, whatever the shutdown race raises (#18).

rclpy's signal handler shuts the context down asynchronously: the executor may then fail to build
its wait set (``RCLError: failed to initialize wait set``), a timer callback's ``publish`` may
fail (``RCLError: publisher's context is invalid``), and cleanup may meet destroyed handles.
:func:`run_node` treats any exception raised once the context is shut down (or within
``SHUTDOWN_GRACE_S`` after it was raised) as the end of the run, so every node exits 0 on SIGINT
and SIGTERM, every time; an exception while the context is still valid is a real error and
propagates (exit code 1, with its traceback).

In a process of its own the node's SIGINT and SIGTERM are Python handlers (rclpy's own signal
handler is not installed) that only record the request in :class:`StopRequest` and never raise
(#26): an exception raised from a signal handler lands wherever the main thread happens to be,
and inside ``rclpy.task.Future.__del__``, a weakref callback or a ``finally:`` it is printed as
"Exception ignored in" and dropped, so the node never stopped and was killed (seen in
``test_motion_planner_absent_or_dying``). The executor spins in steps of ``SPIN_POLL_S`` and the
loop checks the request after each step, so a signal always ends the spin loop within that
time: with rclpy's handler and ``executor.spin()``, 2 of 10 soak runs had a node still
spinning 10 s after its SIGINT (stacks dumped: the main thread waiting in
``wait_for_ready_callbacks``), killed with SIGKILL.

Two guards against a stop that hangs: ``SIGUSR1`` dumps every thread's stack to stderr (the
node's log; :mod:`.orchestration` sends it before a SIGKILL), and once the node is
cleaned up (its data saved) an exit watchdog (daemon thread) ends the process with the run's
code if the interpreter has not exited within ``EXECUTOR_SHUTDOWN_S + EXIT_WATCHDOG_S`` (a
callback thread that never returns would otherwise keep it alive: seen once in 10 soak runs,
the motion planner killed after 10 s), dumping the stacks first so the hang is still visible.
"""

from __future__ import annotations

import faulthandler
import functools
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from typing import Any, TypeVar

import rclpy
import rclpy.logging
from rclpy.context import Context
from rclpy.exceptions import InvalidHandle
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

SHUTDOWN_GRACE_S = 1.0  # longest wait for the context to report a shutdown in progress [s]
EXECUTOR_SHUTDOWN_S = 5.0  # longest wait for running callbacks at exit [s]
# GIL hand-over interval of a node process [s] (CPython's default is 5 ms). rclpy's executor
# rebuilds its wait set in Python on the spinning thread while the callbacks run on worker
# threads: at 5 ms every hand-over between the two waited up to 5 ms, so on 2 cores the
# simulator's 100 Hz timer ran at 69 Hz and the 100 Hz closed loop at 27 Hz with the processes
# mostly idle; the README demo's first segment then timed out (EXECUTION_FAILED). At 0.5 ms:
# 93 Hz and 62 Hz, the demo executes.
GIL_SWITCH_INTERVAL_S = 0.0005
SPIN_POLL_S = 0.2  # longest wait of the spin loop before a pending signal is handled [s]
EXIT_WATCHDOG_S = 3.0  # longest wait for the interpreter to exit once cleaned up [s]
EXIT_OK, EXIT_STARTUP = 0, 2
NodeT = TypeVar('NodeT', bound=Node)  # the node class run_node builds and cleans up


class StopRequest:
    """The stop asked for by SIGINT / SIGTERM: a flag the spin loop reads, set by the handler.

    Setting a class attribute is atomic and cannot fail, so the handler is safe wherever the
    signal lands (inside a destructor, a weakref callback, a lock release, a ``finally:``).
    """

    signal_name: str | None = None

    @classmethod
    def requested(cls) -> bool:
        """Whether a SIGINT or SIGTERM arrived since the last :meth:`clear`."""
        return cls.signal_name is not None

    @classmethod
    def clear(cls) -> None:
        """Forget the request once it was answered (the end of :func:`run_node`). Not at the
        start of a run: a signal landing before that would be forgotten and the node would
        spin on (seen in the fresh-clone soak: one of 200 storm runs of the sim hung).
        """
        cls.signal_name = None


def shutting_down(context: Context, grace_s: float = SHUTDOWN_GRACE_S) -> bool:
    """Whether ``context`` is shut down, waiting up to ``grace_s`` [s] for it to become so."""
    deadline = time.monotonic() + grace_s
    try:
        while context.ok() and time.monotonic() < deadline:
            time.sleep(0.01)
    except KeyboardInterrupt:  # SIGINT while waiting: a shutdown
        return True
    return not context.ok()


def run_node(
    make_node: Callable[[], NodeT],
    *,
    args: list[str] | None = None,
    make_executor: Callable[[Context], Executor] | None = None,
    cleanup: Callable[[NodeT], Any] | None = None,
    startup_errors: tuple[type[BaseException], ...] = (),
    context: Context | None = None,
    name: str = 'node',
    exit_watchdog: bool = True,
) -> int:
    """Initialise rclpy, build the node, spin it until shutdown, clean up; return the exit code.

    Args:
        make_node: builds the node (after ``rclpy.init``).
        args: command-line arguments for ``rclpy.init``.
        make_executor: builds the executor from the context (default single-threaded).
        cleanup: called with the node before the executor and the node are destroyed (e.g. end
            a running training, finish a file); its shutdown-race exceptions are ignored too.
        startup_errors: exceptions of ``make_node`` that mean bad start-up parameters: logged
            as fatal, exit code 2.
        context: the rclpy context (default: the global one); tests pass a private one.
        name: logger name of the fatal start-up message.
        exit_watchdog: in a process of its own, force the exit once cleaned up (see the module
            docstring); in-process test harnesses that run many nodes in turn pass False.

    Returns:
        0 after SIGINT, SIGTERM or another shutdown of the context; 2 on a startup error.

    Raises:
        Exception: raised while the context was still valid (a bug): it is not hidden.
    """
    context = context or rclpy.get_default_context()
    own_process = (
        context is rclpy.get_default_context()
        and threading.current_thread() is threading.main_thread()
    )
    if own_process:
        sys.setswitchinterval(GIL_SWITCH_INTERVAL_S)
        faulthandler.register(signal.SIGUSR1, all_threads=True)
        signal.signal(signal.SIGINT, _request_stop)
        signal.signal(signal.SIGTERM, _request_stop)
        rclpy.init(args=args, context=context, signal_handler_options=SignalHandlerOptions.NO)
    else:
        rclpy.init(args=args, context=context)
    node: NodeT | None = None
    executor: Executor | None = None
    code = EXIT_OK
    try:
        node = make_node()
        executor = (make_executor or (lambda c: SingleThreadedExecutor(context=c)))(context)
        executor.add_node(node)
        while context.ok() and not StopRequest.requested():  # checked every SPIN_POLL_S
            _spin_once(executor, node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except startup_errors as err:
        if node is not None:
            raise
        rclpy.logging.get_logger(name).fatal(f'cannot start: {err}')
        code = EXIT_STARTUP
    except Exception:
        if not shutting_down(context):
            raise
    finally:
        if cleanup is not None and node is not None:
            _quietly(context, functools.partial(cleanup, node))  # data saved first
        if own_process and exit_watchdog:  # bound the exit of the process
            start_exit_watchdog(code, EXECUTOR_SHUTDOWN_S + EXIT_WATCHDOG_S)
        if executor is not None:
            _quietly(context, functools.partial(executor.shutdown, EXECUTOR_SHUTDOWN_S))
        if node is not None:
            _quietly(context, node.destroy_node)
        rclpy.try_shutdown(context=context)
        if own_process:  # answered: a later run in this process starts afresh; a request that
            StopRequest.clear()  # comes before it calls run_node still stops it at once
    return code


def _spin_once(executor: Executor, node: Node) -> None:
    """One ``spin_once`` that outlives an entity destroyed by a worker thread meanwhile.

    A node that creates and destroys a subscription or timer in a service callback (the motion
    planner's /joint_states while executing) races the executor, which builds its wait set from
    the node's entities on this thread: rclpy raises ``InvalidHandle`` ("destruction was
    requested") when one is destroyed between the two (CI, #26). The next ``spin_once`` builds
    the wait set without it, so the loop goes on; nothing else raises ``InvalidHandle`` in a
    node whose context is valid.
    """
    try:
        executor.spin_once(timeout_sec=SPIN_POLL_S)
    except InvalidHandle as err:
        node.get_logger().debug(f'an entity went away while the executor waited: {err}')


def _request_stop(signum: int, frame: Any) -> None:
    """SIGINT / SIGTERM: ask the spin loop of :func:`run_node` to stop; never raises (#26)."""
    StopRequest.signal_name = signal.Signals(signum).name


def start_exit_watchdog(code: int, timeout_s: float = EXIT_WATCHDOG_S) -> threading.Thread:
    """Force the process to end with ``code`` if it is still alive ``timeout_s`` [s] from now.

    A daemon thread: a normal exit never waits for it; if a non-daemon thread keeps the
    interpreter alive, every stack is dumped to stderr and the process ends with ``os._exit``.
    """

    def force_exit() -> None:
        time.sleep(timeout_s)
        print(f'exit took over {timeout_s:.0f} s: forced; thread stacks:', file=sys.stderr)
        faulthandler.dump_traceback(all_threads=True)
        sys.stderr.flush()
        os._exit(code)

    watchdog = threading.Thread(target=force_exit, name='exit_watchdog', daemon=True)
    watchdog.start()
    return watchdog


def _quietly(context: Context, step: Callable[[], Any]) -> None:
    """Run a cleanup ``step``; ignore what the shutdown race raises (KeyboardInterrupt too)."""
    try:
        step()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if context.ok():
            raise
