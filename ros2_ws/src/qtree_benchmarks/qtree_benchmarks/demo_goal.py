"""The demo's RetrieveTarget goal: sent, its training progress shown (rich), its result returned.

Imported by ``scripts/run_demo.py``; every wait checks that the demo's nodes are still alive.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from qtree_node_support.orchestration import NodeProcess


class DemoError(RuntimeError):
    """The demo cannot go on (a node died, the goal was rejected or failed)."""


def check_alive(nodes: list[NodeProcess]) -> None:
    """Raise DemoError naming the first node that is no longer running."""
    for node in nodes:
        if not node.alive():
            tail = '\n'.join(node.log_text().splitlines()[-15:])
            raise DemoError(
                f'node {node.name} died (exit code {node.process.returncode}); last output:\n'
                f'{tail}'
            )


def retrieve_target(args: argparse.Namespace, nodes: list[NodeProcess]) -> Any:
    """Send the RetrieveTarget goal, show progress from its feedback, return the result."""
    import rclpy
    from qtree_msgs.action import RetrieveTarget
    from rclpy.action import ActionClient
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    rclpy.init()
    with _ctrl_c_is_interrupt():
        node = rclpy.create_node('qtree_demo')
    try:
        client = ActionClient(node, RetrieveTarget, '/retrieve_target')
        deadline = time.monotonic() + args.timeout
        while not _wait_for_server(client):
            check_alive(nodes)
            if time.monotonic() > deadline:
                raise DemoError('the /retrieve_target action server did not appear')
        goal = RetrieveTarget.Goal(
            policy=args.policy,
            seed=args.seed,
            max_episodes=args.max_episodes,
            execute=not args.no_execute,
        )
        columns = (
            TextColumn('[bold]{task.description}'),
            BarColumn(),
            TextColumn('{task.fields[status]}'),
            TimeElapsedColumn(),
        )
        with Progress(*columns, transient=False) as progress:
            task = progress.add_task(
                f'training {args.policy} on {args.scenario}',
                total=args.max_episodes,
                status='waiting for the first episode',
            )

            plain = not sys.stdout.isatty()  # CI, pipes: plain lines instead of a live bar
            last_line = [0.0]

            def on_feedback(message: Any) -> None:
                fb = message.feedback
                best = ' → '.join(fb.best_sequence) or '-'
                status = (
                    f'ep {fb.episode}  nodes {fb.nodes}  MP calls {fb.mp_calls}  '
                    f'Q̄ {fb.q_bar:.1f}  ε {fb.epsilon:.3g}  best {best}'
                )
                progress.update(task, completed=fb.episode, status=status)
                if plain and time.monotonic() - last_line[0] > 2.0:
                    last_line[0] = time.monotonic()
                    print(f'training: {status}', flush=True)

            goal_future = client.send_goal_async(goal, feedback_callback=on_feedback)
            handle = _spin_until_done(node, goal_future, nodes, deadline)
            if not handle.accepted:
                raise DemoError('the task planner rejected the goal')
            result_future = handle.get_result_async()
            wrapped = _spin_until_done(node, result_future, nodes, deadline)
            progress.update(task, completed=args.max_episodes, status='done')
        return wrapped.result
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def _wait_for_server(client: Any) -> bool:
    """``client.wait_for_server`` for 0.5 s; KeyboardInterrupt once rclpy's SIGINT handler
    shut the context down (the suite of 9ffde18: Ctrl-C there exited 1 with RCLError, not 130).
    """
    import rclpy

    with _ctrl_c_is_interrupt():
        found = client.wait_for_server(timeout_sec=0.5)
    if not rclpy.ok():
        raise KeyboardInterrupt
    return found


def _spin_until_done(node: Any, future: Any, nodes: list[NodeProcess], deadline: float) -> Any:
    import rclpy

    while not future.done():
        with _ctrl_c_is_interrupt():
            rclpy.spin_once(node, timeout_sec=0.1)
        check_alive(nodes)
        if time.monotonic() > deadline:
            raise DemoError('timed out waiting for the task planner (see --timeout)')
    return future.result()


@contextmanager
def _ctrl_c_is_interrupt() -> Iterator[None]:
    """A Ctrl-C during the block ends the demo with KeyboardInterrupt (exit code 130).

    rclpy's SIGINT handler shuts the context down; the rclpy call in flight then raises
    ExternalShutdownException, or RCLError when the shutdown came while it built its wait set or
    created the node (suites of 9ffde18 and c3e95c4: Ctrl-C exited 1 instead of 130).
    """
    import rclpy
    from rclpy.executors import ExternalShutdownException

    try:
        yield
    except ExternalShutdownException:
        raise KeyboardInterrupt from None
    except Exception:
        if not rclpy.ok():
            raise KeyboardInterrupt from None
        raise
