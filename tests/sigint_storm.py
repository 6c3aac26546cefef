"""SIGINT storm (#26): run one node in this process many times and interrupt each run once with
SIGINT at a random moment (during start-up, callbacks, garbage collection, spinning or
cleanup); every run must return exit code 0 within a bounded time.

The signal is sent by a thread to this very process, so the Python handler runs in the main
thread at whatever bytecode it was executing, exactly as in a node started alone; the garbage
collector runs every few allocations (``gc.set_threshold(50)``) and a churn thread drops
``rclpy.task.Future`` objects in reference cycles, so some signals land in ``Future.__del__``.
Where each signal landed (the innermost function of the interrupted frame) is counted.

Usage: python tests/sigint_storm.py NODE RUNS SEED OUTPUT_JSON
"""

from __future__ import annotations

import gc
import json
import os
import random
import signal
import sys
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

import rclpy.utilities
from qtree_node_support import lifecycle
from rclpy.task import Future

MAX_DELAY_S = 0.8  # the signal comes uniformly within this time of the run's start [s]


def node_runner(name: str, output_dir: Path):
    """(run function, ROS arguments) of one of the four nodes."""
    if name == 'sim_node':
        from jaco2_sim.sim_node import run

        return run, ['--ros-args', '-p', 'scenario:=s1', '-p', 'sim_rate_hz:=1000.0']
    if name == 'motion_planner_node':
        from stpik_motion_planner.motion_planner_node import run

        return run, []
    if name == 'task_planner_node':
        from qtree_task_planner.task_planner_node import run

        return run, []
    if name == 'recorder_node':
        from qtree_recorder.recorder_node import run

        return run, ['--ros-args', '-p', f'output_dir:={output_dir}']
    raise SystemExit(f'unknown node {name!r}')


def churn(stop: threading.Event) -> None:
    """Drop Futures in reference cycles so that the collector finalises some in the main thread."""
    while not stop.is_set():
        for _ in range(20):
            future = Future()
            future.cycle = future  # type: ignore[attr-defined]
        time.sleep(0.005)  # light: the storm runs beside the rest of the suite


def main(argv: list[str]) -> int:
    name, runs, seed, output = argv[0], int(argv[1]), int(argv[2]), Path(argv[3])
    run, ros_args = node_runner(name, output.parent / f'{name}_mcap')
    rng = random.Random(seed)
    gc.set_threshold(50)
    stop = threading.Event()
    threading.Thread(target=churn, args=(stop,), daemon=True).start()
    landed: Counter[str] = Counter()
    install = signal.signal

    def install_with_spy(signum: int, handler: Any) -> Any:  # wraps the handler run_node installs
        def spy(signum: int, frame: Any) -> Any:  # where the signal interrupted the main thread
            landed[frame.f_code.co_name if frame is not None else '?'] += 1
            return handler(signum, frame)

        return install(signum, spy if callable(handler) else handler)

    lifecycle.signal.signal = install_with_spy  # type: ignore[assignment]
    # A signal of the first run may come before run_node installs its handler: install it now
    # (a node process gets its handler as early as its run() is called).
    install_with_spy(signal.SIGINT, lifecycle._request_stop)
    codes, stop_s = [], []
    for _ in range(runs):
        delay = rng.uniform(0.0, MAX_DELAY_S)
        sent: list[float] = []

        def interrupt(delay: float = delay, sent: list[float] = sent) -> None:
            time.sleep(delay)
            sent.append(time.monotonic())
            os.kill(os.getpid(), signal.SIGINT)

        threading.Thread(target=interrupt, daemon=True).start()
        code = run(ros_args, exit_watchdog=False)
        while not sent:  # the run ended (a bug) before its signal: wait for it, then go on
            time.sleep(0.01)
        codes.append(code)
        rclpy.utilities.get_default_context(shutting_down=True)  # a fresh one for the next run
        stop_s.append(max(0.0, time.monotonic() - sent[0]))
    stop.set()
    result = {'node': name, 'runs': runs, 'codes': codes, 'stop_s': stop_s, 'landed': landed}
    output.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
