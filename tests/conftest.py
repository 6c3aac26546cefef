"""Shared fixtures for cross-node tests: a private ROS domain, started nodes, an rclpy client node.

Every test that starts nodes gets its own ``ROS_DOMAIN_ID`` (file-locked counter in
``scripts/orchestration.py``) and localhost-only discovery, so tests can run in parallel.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from orchestration import NodeProcess, allocate_domain_id, start_node

REPO_ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def ros_domain(monkeypatch: pytest.MonkeyPatch) -> int:
    """A private ROS_DOMAIN_ID for this test, set in the environment of the test and its nodes."""
    domain_id = allocate_domain_id()
    monkeypatch.setenv('ROS_DOMAIN_ID', str(domain_id))
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    return domain_id


@pytest.fixture
def launch(ros_domain: int, tmp_path: Path) -> Iterator[Callable[..., NodeProcess]]:
    """Start nodes as processes (``launch(pkg, exe, parameters={...})``); all stopped at teardown.

    Teardown asserts every node still alive exits cleanly on SIGINT (exit code 0), like a
    launch_testing post-shutdown check; nodes a test killed on purpose are skipped.
    """
    nodes: list[NodeProcess] = []

    def _launch(package: str, executable: str, **kwargs: Any) -> NodeProcess:
        kwargs.setdefault('log_dir', tmp_path / 'logs')
        node = start_node(package, executable, **kwargs)
        nodes.append(node)
        return node

    yield _launch
    failures = []
    for node in reversed(nodes):
        was_alive = node.alive()
        code = node.stop()
        if was_alive and code != 0:  # log_text() still reads the (closed) log: last lines
            failures.append(f'{node.name} exited with {code}:\n{node.log_text()[-2000:]}')
    assert not failures, '\n'.join(failures)


@pytest.fixture
def ros_node(ros_domain: int) -> Iterator[Any]:
    """An rclpy node in a private context and executor for the test process (rclpy test shape).

    Use ``spin_until(predicate, timeout_s)`` on the returned node to spin until a condition holds.
    """
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    context = Context()
    rclpy.init(context=context, domain_id=ros_domain)
    node = rclpy.create_node(f'test_client_{os.getpid()}', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)

    def spin_until(predicate: Callable[[], bool], timeout_s: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            executor.spin_once(timeout_sec=0.05)
        return predicate()

    def call(client: Any, request: Any, timeout_s: float = 30.0) -> Any:
        """Wait for the service, call it, spin until the answer arrives; return the response."""
        assert client.wait_for_service(timeout_sec=timeout_s), f'{client.srv_name} not available'
        future = client.call_async(request)
        assert spin_until(future.done, timeout_s), f'{client.srv_name}: no answer in {timeout_s} s'
        return future.result()

    def wait_matched(*entities: Any, timeout_s: float = 30.0) -> None:
        """Spin until every publisher has a subscriber, every subscription a publisher and every
        service client its server (Fast DDS needs 2-3 s to discover a participant; anything
        published or sent before the match is lost: the QoS is volatile)."""

        def matched(entity: Any) -> bool:
            if hasattr(entity, 'get_subscription_count'):
                return entity.get_subscription_count() > 0
            if hasattr(entity, 'get_publisher_count'):
                return entity.get_publisher_count() > 0
            if hasattr(entity, 'server_is_ready'):
                return entity.server_is_ready()
            return entity.service_is_ready()

        names = [getattr(e, 'topic_name', None) or getattr(e, 'srv_name', e) for e in entities]
        ok = spin_until(lambda: all(matched(e) for e in entities), timeout_s)
        assert ok, f'not matched within {timeout_s} s: {names}'

    node.spin_until = spin_until
    node.call = call
    node.wait_matched = wait_matched
    node.executor_ = executor
    yield node
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown(context=context)
