"""Shared fixtures for cross-node tests: a private ROS domain, started nodes, an rclpy client node.

Every test that starts nodes gets its own ``ROS_DOMAIN_ID`` (file-locked counter in
:mod:`qtree_node_support.orchestration`) and localhost-only discovery: tests run in parallel.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from qtree_node_support.orchestration import NodeProcess, allocate_domain_id, start_node, stop_all

REPO_ROOT = Path(__file__).resolve().parents[1]
LOADED_EXECUTION_TIMEOUT_S = 240.0  # motion_planner_node's execution_timeout_s unless set [s]
# motion_planner_node's joint_state_timeout_s unless set [s]: CI once saw the node default (3 s)
# run out in test_execute_relocates_the_object_in_the_sim on a loaded 2-core machine. Tests of the
# silence itself (test_faults) set the default explicitly.
LOADED_JOINT_STATE_TIMEOUT_S = 15.0
# motion_planner_node's max_tracking_error_m unless set [m] (#26): the loaded fresh-clone soak
# of 976f55b saw a closed loop stop at 53.1 mm against the node default (50 mm) while the
# grasp-failure goal of test_replanning executed O2; 2x over that worst value. Clearance is still
# held by the set-based tasks and the margin stop; tests of the limit itself set it explicitly.
LOADED_MAX_TRACKING_ERROR_M = 0.12


def probe_request(client: Any) -> Any:
    """A request the client's server answers at once with an error and no side effect, or None.

    ``wait_for_service`` returns once the client has discovered the server, but the server may
    not yet have matched the client's response reader: a reply written then is lost (volatile
    QoS; seen in 1 of 10 soak runs). A probe is re-sent until one is answered, so a real request
    (which may not be idempotent: ``execute=True``) is only sent once both directions match.
    """
    name = client.srv_type.__name__
    if name == 'RelocateObject':  # INVALID_REQUEST: empty object id
        return client.srv_type.Request(object_id='')
    if name == 'ResetScene':  # failed load: nothing installed, the scene is unchanged
        return client.srv_type.Request(scenario='/nonexistent/__probe__.yaml')
    if name == 'AttachObject':  # unknown object id
        return client.srv_type.Request(object_id='__probe__', attach=True)
    return None


def wait_answering(
    client: Any, spin_until: Callable[..., bool], timeout_s: float = 30.0, attempt_s: float = 2.0
) -> None:
    """Wait for the service and until it answers a probe (:func:`probe_request`), re-sent every
    ``attempt_s`` [s]; a no-op beyond ``wait_for_service`` for services without a probe."""
    assert client.wait_for_service(timeout_sec=timeout_s), f'{client.srv_name} not available'
    probe = probe_request(client)
    if probe is None or getattr(client, '_qtree_answered', False):
        return
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        future = client.call_async(probe)
        if spin_until(future.done, attempt_s):
            client._qtree_answered = True
            return
        client.remove_pending_request(future)
    raise AssertionError(f'{client.srv_name}: no probe answered in {timeout_s} s')


def wait_goal_answering(
    client: Any,
    spin_until: Callable[..., bool],
    probe_goal: Any,
    timeout_s: float = 60.0,
    attempt_s: float = 3.0,
) -> None:
    """Like :func:`wait_answering` for an action client: send ``probe_goal`` (one the server
    ends at once, e.g. an invalid one) until both its goal response and its result arrived.

    ``wait_for_server`` only says the client discovered the server's entities; a goal response
    or result written before the server matched this client's readers is lost (CI: 49 of 50
    burst goals answered). A probe goal has no effect beyond its own immediate abort.
    """
    assert client.wait_for_server(timeout_sec=timeout_s), 'action server not available'
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        sent = client.send_goal_async(probe_goal)
        if not spin_until(sent.done, attempt_s):
            continue  # the goal response was lost: ask again
        handle = sent.result()
        if not handle.accepted:
            return
        if spin_until(handle.get_result_async().done, attempt_s):
            return
    raise AssertionError(f'no probe goal answered in {timeout_s} s')


@pytest.fixture
def ros_domain(monkeypatch: pytest.MonkeyPatch) -> int:
    """A private ROS_DOMAIN_ID for this test, set in the environment of the test and its nodes."""
    domain_id = allocate_domain_id()
    monkeypatch.setenv('ROS_DOMAIN_ID', str(domain_id))
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    return domain_id


FAILED_LOG_CHARS = 12000  # tail of each node's log attached to a failed test's report [chars]


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo) -> Any:
    """A failed test's report gets the tail of each node's log (:func:`launch`): pytest's basetemp
    keeps only the last three runs, so the logs of a rare failure were gone when looked for."""
    report = yield
    if report.when == 'call' and report.failed:
        for node in getattr(item, 'qtree_nodes', ()):
            text = node.log_text()[-FAILED_LOG_CHARS:]
            report.sections.append((f'log of {node.name} ({node.log_path})', text))
    return report


@pytest.fixture
def launch(
    ros_domain: int, tmp_path: Path, request: pytest.FixtureRequest
) -> Iterator[Callable[..., NodeProcess]]:
    """Start nodes as processes (``launch(pkg, exe, parameters={...})``); all stopped at teardown.

    Teardown asserts every node still alive exits cleanly on SIGINT (exit code 0), like a
    launch_testing post-shutdown check; nodes a test killed on purpose are skipped. When the test
    failed, the nodes' logs are added to its report.
    """
    nodes: list[NodeProcess] = []
    request.node.qtree_nodes = nodes  # read by pytest_runtest_makereport on a failure

    def _launch(package: str, executable: str, **kwargs: Any) -> NodeProcess:
        kwargs.setdefault('log_dir', tmp_path / 'logs')
        if executable == 'motion_planner_node':
            # Two test workers on 2 cores slow the closed loop's reference time (by design, the
            # arm lags): segments then took longer than the node's default 30 s margin.
            parameters = dict(kwargs.get('parameters') or {})
            parameters.setdefault('execution_timeout_s', LOADED_EXECUTION_TIMEOUT_S)
            parameters.setdefault('joint_state_timeout_s', LOADED_JOINT_STATE_TIMEOUT_S)
            parameters.setdefault('max_tracking_error_m', LOADED_MAX_TRACKING_ERROR_M)
            kwargs['parameters'] = parameters
        node = start_node(package, executable, **kwargs)
        nodes.append(node)
        return node

    yield _launch
    failures = []
    for node in reversed(nodes):
        was_alive = node.alive()
        code = node.stop()
        if was_alive and code != 0:  # log_text() still reads the (closed) log: last lines
            failures.append(f'{node.name} exited with {code}:\n{node.log_text()[-6000:]}')
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
        """Wait until the service answers (:func:`wait_answering`), call it, spin until the answer
        arrives; return the response."""
        wait_answering(client, spin_until, timeout_s)
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
    node.wait_answering = lambda client, timeout_s=30.0: wait_answering(
        client, spin_until, timeout_s
    )
    node.wait_goal_answering = lambda client, probe, timeout_s=60.0: wait_goal_answering(
        client, spin_until, probe, timeout_s
    )
    node.wait_action_answering = lambda action, timeout_s=30.0: wait_action_answering(
        action, spin_until, timeout_s
    )
    node.executor_ = executor
    yield node
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown(context=context)


PROBE_GOAL_POLICY = '__probe__'  # the task planner aborts it at once: INVALID_GOAL


def wait_action_answering(
    action: Any, spin_until: Callable[..., bool], timeout_s: float = 30.0, attempt_s: float = 2.0
) -> None:
    """Wait for the action server and until it answers a probe goal (an unknown policy, aborted
    at once with INVALID_GOAL) and its result, re-sent every ``attempt_s`` [s].

    Like :func:`wait_answering` for services: ``wait_for_server`` returns before the server has
    matched the client's readers, and a goal answer written then is lost (soak: "goal not
    answered" in 1 of 10 runs). Waiting for the probe's result too means the server is idle
    again when the real goal arrives (a second goal would be refused as busy).
    """
    from qtree_msgs.action import RetrieveTarget

    assert action.wait_for_server(timeout_sec=timeout_s), 'action server not available'
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        sent = action.send_goal_async(RetrieveTarget.Goal(policy=PROBE_GOAL_POLICY))
        if not spin_until(sent.done, attempt_s):
            continue
        handle = sent.result()
        while handle.accepted and time.monotonic() < deadline:
            if spin_until(handle.get_result_async().done, attempt_s):
                return
        if not handle.accepted:
            return
    raise AssertionError(f'the action server answered no probe goal in {timeout_s} s')


class ClientGraph:
    """Nodes started as processes in a private domain for a whole test module, one rclpy client
    node holding what users' robot software would hold, and what it received.

    Serves the modules that send many requests to one long-lived graph (bad inputs, limits): the
    module sets ``GRAPH_NODES = {executable: (package, ROS node name, parameters)}`` and asks for
    the ``client_graph`` fixture. The sim's scenario is s1 in every such graph.

    Attributes:
        nodes: running node processes by executable name.
        states: /joint_states messages received; ``q`` the last arm configuration [rad] (7,) and
            ``state_times`` their stamps [s] (sim clock).
        scene: last /scene message (None before the first); ``scene_name`` its scenario name.
    """

    FEASIBLE = 'O2'  # feasible on s1 with nothing relocated (the planner's unit tests)

    def __init__(
        self, domain_id: int, logs: Path, specs: dict[str, tuple[str, str, dict]]
    ) -> None:
        import rclpy
        from qtree_msgs.action import RetrieveTarget
        from qtree_msgs.msg import Scene
        from qtree_msgs.srv import RelocateObject, ResetScene, SetScene
        from rclpy.action import ActionClient
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from trajectory_msgs.msg import JointTrajectory

        self.env = dict(
            os.environ, ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST'
        )
        self.specs, self.logs = specs, logs
        self.restarts = 0
        self.crashes: list[str] = []
        self.nodes: dict[str, NodeProcess] = {exe: self._start(exe, logs) for exe in specs}
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('client_graph', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.states = 0
        self.q: Any = None
        self.state_times: list[float] = []
        self.scene: Any = None
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.node.create_subscription(JointState, '/joint_states', self._on_state, 1000)
        self.node.create_subscription(Scene, '/scene', self._on_scene, latched)
        self.trajectory_pub = self.node.create_publisher(JointTrajectory, '/joint_trajectory', 10)
        self.relocate_client = self.node.create_client(RelocateObject, '/relocate_object')
        self.reset_client = self.node.create_client(ResetScene, '/jaco2_sim/reset_scene')
        self.set_scene_client = self.node.create_client(SetScene, '/jaco2_sim/set_scene')
        self.action = ActionClient(self.node, RetrieveTarget, '/retrieve_target')

    @property
    def scene_name(self) -> str:
        """Scenario name of the last /scene ('' before the first)."""
        return self.scene.scenario_name if self.scene is not None else ''

    def _on_state(self, msg: Any) -> None:
        import numpy as np

        self.states += 1
        self.q = np.array(msg.position[:7])
        self.state_times.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)

    def _on_scene(self, msg: Any) -> None:
        self.scene = msg

    def _start(self, executable: str, log_dir: Path) -> NodeProcess:
        package, _, parameters = self.specs[executable]
        return start_node(
            package, executable, parameters=parameters, env=self.env, log_dir=log_dir
        )

    def wait_ready(self) -> None:
        """Every node ready, the planner built on s1, the sim publishing and subscribed."""
        for process in self.nodes.values():
            process.wait_for_log('ready', 90.0)
        if 'motion_planner_node' in self.nodes:
            self.nodes['motion_planner_node'].wait_for_log('planner rebuilt', 30.0)
        if 'sim_node' in self.nodes:
            assert self.spin_until(lambda: self.q is not None and self.scene_name == 's1', 20.0)
            assert self.spin_until(lambda: self.trajectory_pub.get_subscription_count() > 0, 10.0)

    def revive(self) -> None:
        """Restart every node that died (a crash fails its own case, not the following ones)."""
        dead = [exe for exe, process in self.nodes.items() if not process.alive()]
        for executable in dead:
            self.crashes.append(f'{executable}: {self.nodes[executable].log_text()[-1500:]}')
            self.nodes[executable].stop()
            self.restarts += 1
            self.nodes[executable] = self._start(executable, self.logs / f'restart{self.restarts}')
        for executable in dead:
            self.nodes[executable].wait_for_log('ready', 90.0)
        if 'motion_planner_node' in dead:
            self.nodes['motion_planner_node'].wait_for_log('planner rebuilt', 30.0)

    def spin_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            self.executor.spin_once(timeout_sec=0.02)
        return predicate()

    def wait(self, future: Any, timeout_s: float = 30.0, executable: str = '') -> Any:
        """Spin until ``future`` is done; fail at once if the answering node dies."""
        process = self.nodes.get(executable)
        self.spin_until(lambda: future.done() or (process and not process.alive()), timeout_s)
        if process is not None and not process.alive() and not future.done():
            pytest.fail(f'{executable} died before answering:\n{process.log_text()[-3000:]}')
        assert future.done(), f'no answer in {timeout_s} s'
        return future.result()

    def call(
        self, client: Any, request: Any, timeout_s: float = 30.0, executable: str = ''
    ) -> Any:
        """Wait until the service answers (:func:`wait_answering`), call it; the response (see
        :meth:`wait`)."""
        wait_answering(client, self.spin_until, 20.0)
        return self.wait(client.call_async(request), timeout_s, executable)

    def timed_call(self, client: Any, request: Any, timeout_s: float) -> tuple[Any, float]:
        """(response, seconds from sending to the answer) of one service call."""
        wait_answering(client, self.spin_until, 20.0)
        start = time.monotonic()
        response = self.wait(client.call_async(request), timeout_s)
        return response, time.monotonic() - start

    def relocate(self, object_id: str, relocated: list[str], execute: bool = False) -> Any:
        from qtree_msgs.srv import RelocateObject

        request = RelocateObject.Request(
            object_id=object_id, relocated_ids=relocated, execute=execute
        )
        return self.call(self.relocate_client, request, 60.0, 'motion_planner_node')

    def reset(self, scenario: str) -> Any:
        from qtree_msgs.srv import ResetScene

        request = ResetScene.Request(scenario=scenario)
        return self.call(self.reset_client, request, 30.0, 'sim_node')

    def goal(self, timeout_s: float = 60.0, **fields: Any) -> tuple[int, Any]:
        """Send a RetrieveTarget goal; return (status, result)."""
        from qtree_msgs.action import RetrieveTarget

        assert self.action.wait_for_server(timeout_sec=20.0)
        handle = self.wait(self.action.send_goal_async(RetrieveTarget.Goal(**fields)))
        assert handle.accepted, 'the task planner rejects no goal: it aborts with a reason'
        response = self.wait(handle.get_result_async(), timeout_s, 'task_planner_node')
        return response.status, response.result

    def log_mark(self, executable: str) -> int:
        return len(self.nodes[executable].log_text())

    def wait_log(self, executable: str, mark: int, fragment: str, timeout_s: float = 5.0) -> str:
        """Spin until ``fragment`` is in the node's output after ``mark``; return that output."""
        process = self.nodes[executable]
        self.spin_until(lambda: fragment in process.log_text()[mark:], timeout_s)
        text = process.log_text()[mark:]
        assert fragment in text, f'{fragment!r} not logged; new output:\n{text[-2000:]}'
        return text

    def assert_alive(self, executable: str) -> None:
        """The node still runs and answers a valid request."""
        process = self.nodes[executable]
        assert process.alive(), f'{executable} died:\n{process.log_text()[-3000:]}'
        if executable == 'motion_planner_node':
            response = self.relocate(self.FEASIBLE, [])
            assert response.feasible and response.reason == 0, response.message
        elif executable == 'sim_node':
            count = self.states
            assert self.spin_until(lambda: self.states >= count + 10, 5.0), 'no /joint_states'
            assert self.reset('s1').success
        elif executable == 'task_planner_node':
            from qtree_msgs.action import RetrieveTarget

            _, result = self.goal(max_episodes=3, seed=1)
            codes = {RetrieveTarget.Result.SUCCESS, RetrieveTarget.Result.NO_SOLUTION}
            assert result.error_code in codes and 1 <= result.episodes <= 3, result.message

    def close(self) -> dict[str, int]:
        """Destroy the client node and stop every node; exit codes of those still alive."""
        import rclpy

        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        alive = [process for process in self.nodes.values() if process.alive()]
        dead = [process for process in self.nodes.values() if not process.alive()]
        codes = stop_all(alive)
        stop_all(dead)  # killed by the last case: already reported by it
        return codes


@pytest.fixture(scope='module')
def client_graph(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ClientGraph]:
    """The module's ``GRAPH_NODES`` running on a private domain, ready, with a client node.

    Teardown asserts that every node alive at the end exits cleanly (exit code 0).
    """
    logs = tmp_path_factory.mktemp(f'{request.module.__name__}_logs')
    graph = ClientGraph(allocate_domain_id(), logs, request.module.GRAPH_NODES)
    try:
        graph.wait_ready()
        yield graph
    finally:
        codes = graph.close()
    assert all(code == 0 for code in codes.values()), codes


@pytest.fixture
def graph(client_graph: ClientGraph) -> ClientGraph:
    """The module's client graph with every node alive (restarted if an earlier case killed it)."""
    client_graph.revive()
    return client_graph
