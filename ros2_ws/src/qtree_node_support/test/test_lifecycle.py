"""run_node against the shutdown race of rclpy: a node publishing at 1 kHz, its context shut down
from another thread (what rclpy's SIGINT/SIGTERM handler does) always gives exit code 0."""

from __future__ import annotations

import threading

import pytest
import rclpy
from qtree_node_support.lifecycle import run_node
from rclpy.context import Context
from rclpy.executors import MultiThreadedExecutor
from std_msgs.msg import String


def _busy_node(context: Context, name: str, stop_after_s: float):
    """A node whose 1 kHz timer publishes, and a subscription: many chances to meet the race.

    Its context is shut down from another thread ``stop_after_s`` [s] after it is built."""
    node = rclpy.create_node(name, context=context)
    pub = node.create_publisher(String, 'chatter', 10)
    node.create_subscription(String, 'chatter', lambda _: None, 10)
    node.create_timer(0.001, lambda: pub.publish(String(data='x' * 100)))
    _shutdown_later(context, stop_after_s)
    return node


def _shutdown_later(context: Context, delay_s: float) -> None:
    thread = threading.Thread(target=lambda: (threading.Event().wait(delay_s), context.shutdown()))
    thread.start()


@pytest.mark.parametrize('threads', [1, 4], ids=['single-threaded', 'multi-threaded'])
def test_shutdown_from_another_thread_always_exits_0(threads: int) -> None:
    cleaned: list[str] = []
    for i in range(15):
        context = Context()
        make_executor = (
            None if threads == 1 else (lambda c: MultiThreadedExecutor(threads, context=c))
        )
        code = run_node(
            lambda c=context, i=i: _busy_node(c, f'busy_{threads}_{i}', 0.05 + 0.013 * i),
            make_executor=make_executor,
            cleanup=lambda node: cleaned.append(node.get_name()),
            context=context,
        )
        assert code == 0
        assert not context.ok()
    assert len(cleaned) == 15


def test_entities_destroyed_by_worker_threads_do_not_end_the_node() -> None:
    """Three threads create and destroy a subscription (what the motion planner does with
    /joint_states per execution) while a 2 kHz timer keeps the executor rebuilding its wait set:
    before the fix run_node raised InvalidHandle within a few seconds (as in CI)."""
    context = Context()
    stop = threading.Event()
    rounds = [0]

    def make(c=context):
        node = rclpy.create_node('churn', context=c)
        topic = f'churn_{id(node)}'

        def churn() -> None:
            while not stop.is_set() and c.ok():
                sub = node.create_subscription(String, topic, lambda _: None, 10)
                threading.Event().wait(0.0005)
                node.destroy_subscription(sub)
                rounds[0] += 1

        for _ in range(3):
            threading.Thread(target=churn, daemon=True).start()
        pub = node.create_publisher(String, topic, 10)
        node.create_subscription(String, topic, lambda _: None, 10)
        node.create_timer(0.0005, lambda: pub.publish(String(data='x')))
        _shutdown_later(c, 5.0)
        return node

    try:
        code = run_node(
            make, make_executor=lambda c: MultiThreadedExecutor(context=c), context=context
        )
    finally:
        stop.set()
    assert code == 0
    assert rounds[0] > 500  # the churn went on the whole time (about 1 000 rounds here)


def test_an_error_while_running_is_not_hidden() -> None:
    context = Context()

    def broken(c=context):
        node = rclpy.create_node('broken', context=c)

        def fail() -> None:
            raise ZeroDivisionError('a real bug')

        node.create_timer(0.01, fail)
        return node

    with pytest.raises(ZeroDivisionError, match='a real bug'):
        run_node(broken, context=context)
    assert not context.ok()  # shut down on the way out all the same


def test_startup_error_gives_exit_code_2() -> None:
    def bad_start():
        raise ValueError('scenario: no such scenario')

    assert run_node(bad_start, startup_errors=(ValueError,), context=Context()) == 2


def test_exit_watchdog_ends_a_process_kept_alive_by_a_stuck_thread():
    """Soak: once in 10 runs a cleaned-up motion planner stayed alive until SIGKILL (-9)."""
    import subprocess
    import sys

    script = (
        'import threading\n'
        'from qtree_node_support.lifecycle import start_exit_watchdog\n'
        'threading.Thread(target=threading.Event().wait).start()  # never returns\n'
        'start_exit_watchdog(0, 0.5)\n'
    )
    done = subprocess.run(
        [sys.executable, '-c', script], capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 0
    assert 'forced' in done.stderr and 'Thread' in done.stderr  # the stacks are shown


def test_exit_watchdog_keeps_the_code_and_never_delays_a_clean_exit():
    import subprocess
    import sys
    import time

    script = (
        'import sys\n'
        'from qtree_node_support.lifecycle import start_exit_watchdog\n'
        'start_exit_watchdog(3, 20.0)\n'
        'sys.exit(3)\n'
    )
    start = time.monotonic()
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True)
    assert done.returncode == 3 and 'forced' not in done.stderr
    assert time.monotonic() - start < 15.0


NODE_SCRIPT = """
import sys
import rclpy
from qtree_node_support.lifecycle import run_node
from rclpy.executors import MultiThreadedExecutor

rclpy.install_signal_handlers = lambda *a, **k: None  # rclpy's handler missing the signal

def make_node():
    node = rclpy.create_node('idle_node')  # nothing ever wakes its executor up
    print('ready', flush=True)
    return node

sys.exit(run_node(make_node, make_executor=lambda c: MultiThreadedExecutor(4, context=c)))
"""


@pytest.mark.parametrize('sig', ['SIGINT', 'SIGTERM'])
def test_a_signal_stops_an_idle_node_even_if_rclpys_handler_misses_it(sig: str, tmp_path) -> None:
    """Soak: a node still spinning 10 s after SIGINT (main thread in wait_for_ready_callbacks)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    env = dict(os.environ, ROS_DOMAIN_ID='231', ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    process = subprocess.Popen(
        [sys.executable, '-c', NODE_SCRIPT], stdout=subprocess.PIPE, text=True, env=env
    )
    try:
        assert process.stdout.readline().strip() == 'ready'
        time.sleep(0.5)
        process.send_signal(getattr(signal, sig))
        assert process.wait(timeout=10.0) == 0
    finally:
        process.kill()
        process.wait()


DEL_SCRIPT = """
import os
import signal
import sys
import time
import rclpy
from qtree_node_support.lifecycle import run_node


class SignalsInDestructor:
    def __del__(self):  # the signal handler runs inside this destructor
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)


def make_node():
    node = rclpy.create_node('del_node')
    node.create_timer(0.05, lambda: SignalsInDestructor())  # dropped at once: __del__ runs
    print('ready', flush=True)
    return node


sys.exit(run_node(make_node))
"""


def test_a_signal_landing_in_a_destructor_still_stops_the_node() -> None:
    """#26: the old handler raised KeyboardInterrupt inside ``__del__``; it was dropped there."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, ROS_DOMAIN_ID='232', ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    process = subprocess.Popen(
        [sys.executable, '-c', DEL_SCRIPT],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert process.stdout.readline().strip() == 'ready'
        assert process.wait(timeout=20.0) == 0
        assert 'Exception ignored' not in process.stderr.read()
    finally:
        process.kill()
        process.wait()


def test_the_stop_handler_records_the_signal_and_never_raises() -> None:
    import signal

    from qtree_node_support import lifecycle

    lifecycle.StopRequest.clear()
    assert not lifecycle.StopRequest.requested()
    lifecycle._request_stop(signal.SIGTERM, None)  # would raise KeyboardInterrupt before #26
    assert lifecycle.StopRequest.signal_name == 'SIGTERM' and lifecycle.StopRequest.requested()
    lifecycle.StopRequest.clear()


EARLY_SCRIPT = """
import sys
import rclpy
from qtree_node_support import lifecycle

lifecycle.StopRequest.signal_name = 'SIGINT'  # arrived before run_node was called
print('ready', flush=True)
sys.exit(lifecycle.run_node(lambda: rclpy.create_node('early_node'), exit_watchdog=False))
"""


def test_a_stop_requested_before_the_run_starts_is_not_forgotten() -> None:
    """Fresh-clone soak: clearing the request at the start of run_node lost a signal that came
    just before it, and the sim node of one storm run spun on until the test timed out."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, ROS_DOMAIN_ID='230', ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    done = subprocess.run(
        [sys.executable, '-c', EARLY_SCRIPT], capture_output=True, text=True, env=env, timeout=30
    )
    assert done.stdout.startswith('ready') and done.returncode == 0, done.stderr[-2000:]


SWITCH_SCRIPT = """
import sys
import rclpy
from qtree_node_support.lifecycle import run_node


def make_node():
    node = rclpy.create_node('switch_node')
    print(f'{sys.getswitchinterval():.6f}', flush=True)
    rclpy.get_default_context().try_shutdown()
    return node


sys.exit(run_node(make_node))
"""


def test_a_node_process_hands_the_gil_over_every_half_millisecond() -> None:
    """The README demo's closed loop ran at 27 Hz instead of 100 (CPython's 5 ms GIL hand-over
    between rclpy's spinning thread and its callback threads) and its first segment timed out.
    """
    import os
    import subprocess
    import sys

    from qtree_node_support.lifecycle import GIL_SWITCH_INTERVAL_S

    env = dict(os.environ, ROS_DOMAIN_ID='232', ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    done = subprocess.run(
        [sys.executable, '-c', SWITCH_SCRIPT], capture_output=True, text=True, env=env, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert float(done.stdout.split()[0]) == pytest.approx(GIL_SWITCH_INTERVAL_S)
    assert GIL_SWITCH_INTERVAL_S <= 0.001
