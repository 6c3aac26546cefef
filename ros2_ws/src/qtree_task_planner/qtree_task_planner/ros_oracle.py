"""Feasibility oracle of the ``task_planner`` node over the ``/relocate_object`` service.

:class:`RosPlannerOracle` answers the Q-Tree learner's "can ``object_id`` be relocated after
``relocated``?" with one RelocateObject call (execute=false); :func:`wait_for_future` blocks an
executor thread until another one completes a service call (:mod:`.sequence_execution` relocates
a learned sequence on the arm).
"""

from __future__ import annotations

import threading
import time
from typing import Any

import rclpy
from qtree_msgs.srv import RelocateObject
from stpik_motion_planner.result import ReasonFamily, reason_family

from qtree_task_planner.exceptions import OracleUnavailableError
from qtree_task_planner.oracle import (
    FeasibilityAnswer,
    SetKey,
    approach_blockers_of,
    blockers_of,
)
from qtree_task_planner.replanning import ReuseCounter
from qtree_task_planner.retry import Backoff

COPY_AFTER = 0.8  # share of the answer time-out after which a question is sent again [-]


def wait_for_future(future: rclpy.task.Future, timeout_s: float, stop: Any) -> bool:
    """Block this thread until ``future`` is done (another executor thread completes it).

    Args:
        future: the pending service call.
        timeout_s: longest wait [s].
        stop: anything with ``is_set()`` (an Event): once set, the wait ends at once.

    Returns:
        Whether ``future`` is done: False on time-out, or at once when ``stop`` is set.
    """
    done = threading.Event()
    future.add_done_callback(lambda _: done.set())
    deadline = time.monotonic() + timeout_s
    while not done.wait(0.1):
        if stop.is_set() or time.monotonic() > deadline:
            return future.done()
    return True


class RosPlannerOracle:
    """Feasibility oracle over the ``/relocate_object`` service (execute=false).

    Planning failures (reason 2xx) are "cannot relocate" (-1 of eq. 8). A busy planner
    (PLANNER_BUSY), a planning time-out (TIMEOUT) and a reply lost in transport are not answers:
    they are asked again with the bounded exponential back-off of :class:`~.retry.Backoff`,
    then raise (the goal aborts with MOTION_PLANNER_UNAVAILABLE); they never become -1.
    Request errors (1xx: unknown object, invalid request, no or invalid scene) are not answers
    either: NO_SCENE is retried for ``scene_wait_s``, the others raise.

    Attributes:
        planner_runs: answers not served from the motion planner's cache (``from_cache``).
        retries: questions asked again (busy, time-out or lost reply), over the oracle's life.
        reuse: distinct questions answered from the planner's cache since its last reset (#32).
    """

    RETRIED = frozenset({RelocateObject.Response.TIMEOUT, RelocateObject.Response.PLANNER_BUSY})

    def __init__(
        self,
        client: rclpy.client.Client,
        timeout_s: float,
        scene_wait_s: float,
        stop: threading.Event | None = None,
        backoff: Backoff | None = None,
        scene_name: str = '',
    ) -> None:
        """Keep the client and the waits.

        Args:
            client: a ``/relocate_object`` client (anything with ``call_async``).
            timeout_s: longest wait for one answer [s].
            scene_wait_s: how long NO_SCENE answers are retried [s].
            stop: set when the node is shutting down; ends a wait at once.
            backoff: retry bounds of busy / timed-out / lost answers (default :class:`Backoff`).
            scene_name: the scene every question is about (the request's ``scene_name``: the
                planner answers only for it); '' for the planner's current scene.
        """
        self.client = client
        self.timeout_s = timeout_s
        self.scene_wait_s = scene_wait_s
        self.scene_name = scene_name
        self.stop = stop or threading.Event()
        self.backoff = backoff or Backoff()
        self.planner_runs = 0
        self.retries = 0
        self.reuse = ReuseCounter()
        self._approaches: dict[SetKey, tuple[frozenset[str], ...] | None] = {}

    def feasible(self, relocated: tuple[str, ...], object_id: str) -> bool:
        """Ask the motion planner whether ``object_id`` can be relocated after ``relocated``.

        Args:
            relocated: ids already relocated, in order.
            object_id: the object to relocate next.

        Returns:
            True if the relocation is feasible (eq. 8: +1), False if not (-1).

        Raises:
            OracleUnavailableError: no answer after the retries, or the request was rejected.
        """
        return self.answer(relocated, object_id).feasible

    def answer(self, relocated: tuple[str, ...], object_id: str) -> FeasibilityAnswer:
        """Like :meth:`feasible`, with the response's blockers (``blocking_ids``, issue #14).

        Planning failures (2xx) carry the response's ``blocking_ids`` (``()`` when
        ``blocked_by_immovable``; None when it names nobody or the field is absent); time-outs
        (3xx) carry no report (None).

        Raises:
            OracleUnavailableError: no answer in time, or the request was rejected.
        """
        request = RelocateObject.Request(
            object_id=object_id,
            relocated_ids=list(relocated),
            execute=False,
            scene_name=self.scene_name,
        )
        deadline = time.monotonic() + self.scene_wait_s
        busy = 0
        while True:
            response = self._ask(request, object_id, relocated)
            if response is None:
                why = f'{self.service}: no answer in {self.timeout_s} s'
                detail = f'{why} (asked {self.backoff.missing_retries + 1} times)'
                raise OracleUnavailableError(object_id, relocated, detail)
            if response.reason == RelocateObject.Response.NO_SCENE:
                if time.monotonic() > deadline:
                    raise OracleUnavailableError(object_id, relocated, response.message)
                time.sleep(0.2)  # the planner has not received /scene yet
                continue
            if response.reason not in self.RETRIED:
                break
            why, busy = f'reason {response.reason}: {response.message}', busy + 1
            if busy > self.backoff.retries:
                detail = f'{why} (gave up after {busy - 1} retries)'
                raise OracleUnavailableError(object_id, relocated, detail)
            self.retries += 1
            self.stop.wait(self.backoff.delay(busy - 1))
        family = reason_family(response.reason)
        if family in (ReasonFamily.REQUEST_ERROR, ReasonFamily.UNKNOWN):
            detail = f'request rejected (reason {response.reason}): {response.message}'
            raise OracleUnavailableError(object_id, relocated, detail)
        self.planner_runs += not response.from_cache
        self.reuse.count(relocated, object_id, response.from_cache)
        if response.feasible:
            return FeasibilityAnswer(True, ())
        if family == ReasonFamily.RUNTIME_FAILURE:  # a time-out says nothing about who blocks
            return FeasibilityAnswer(False, None)
        key = (frozenset(relocated), object_id)
        self._approaches[key] = approach_blockers_of(response, relocated, object_id)
        return FeasibilityAnswer(False, blockers_of(response, relocated, object_id))

    @property
    def service(self) -> str:
        """Name of the service asked (for messages)."""
        return getattr(self.client, 'srv_name', '/relocate_object')

    def _ask(
        self, request: RelocateObject.Request, object_id: str, relocated: tuple[str, ...]
    ) -> RelocateObject.Response | None:
        """One answer to ``request`` within one call time-out, or None (#26).

        A reply lost in transport is covered inside the same time-out: the request is sent
        again ``missing_retries`` times late in it (from :data:`COPY_AFTER` of it on, when a
        planner that finished answers a copy from its cache in milliseconds; earlier copies
        would double the work of a planner that is merely slow on a loaded machine) and the
        first real answer of any copy is taken (a PLANNER_BUSY answer to a copy means the first
        one is being planned: ignored while the first is pending). A dead planner is thus
        reported after one time-out, not one per retry (was 10.2 s with two 5 s waits).

        Raises:
            OracleUnavailableError: the node is shutting down.
        """
        busy = RelocateObject.Response.PLANNER_BUSY
        start = time.monotonic()
        copies = self.backoff.missing_retries + 1
        k = self.backoff.missing_retries
        send_at = [self.timeout_s * (COPY_AFTER + (1 - COPY_AFTER) * j / k) for j in range(k)]
        futures = [self.client.call_async(request)]
        try:
            while True:
                for index, future in enumerate(futures):
                    response = future.result() if future.done() else None
                    if response is None:
                        continue
                    pending = any(not f.done() for f in futures[:index])
                    if response.reason != busy or index == 0 or not pending:
                        return response
                elapsed = time.monotonic() - start
                if elapsed > self.timeout_s:
                    return None
                if len(futures) < copies and elapsed > send_at[len(futures) - 1]:
                    futures.append(self.client.call_async(request))
                    self.retries += 1
                if self.stop.wait(0.01):
                    raise OracleUnavailableError(object_id, relocated, 'node shutting down')
        finally:
            for future in futures:
                if not future.done():
                    future.cancel()

    def approach_blockers(
        self, relocated: tuple[str, ...], object_id: str
    ) -> tuple[frozenset[str], ...] | None:
        """The per-approach blockers (``approach_blocking_ids``) of the last infeasible
        response about this pair, or None (no request is sent).
        """
        return self._approaches.get((frozenset(relocated), object_id))
