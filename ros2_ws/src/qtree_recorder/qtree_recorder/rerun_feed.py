"""Defensive glue between the recorder node and the live Rerun view (``rerun_view.RunView``).

The recording must go on whatever Rerun does: the view is created only when ``rerun_mode`` is not
``off``, every call is guarded, and the first failure is reported once and disables the view.
``RunView.on_message`` takes decoded messages; the node passes the ones it decodes anyway
(joint states, URDF, scene) and this module decodes the others the view shows, with rclpy's
deserialisation (node-side glue, not core logic).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from qtree_recorder.graph_topics import load_message_class

RERUN_MODES = ('off', 'save', 'spawn')


class RerunFeed:
    """Feeds a ``RunView`` if ``mode`` is not ``'off'``; never raises.

    Args:
        mode: ``'off'``, ``'save'`` (write ``rrd_path``) or ``'spawn'`` (open a viewer).
        rrd_path: the ``.rrd`` file for ``'save'``.
        report: called with an error message (the node's logger).
    """

    def __init__(self, mode: str, rrd_path: str, report: Callable[[str], Any]) -> None:
        self._report = report
        self.view: Any = None
        self.topics: tuple[str, ...] = ()
        self.error = ''
        if mode == 'off':
            return
        if mode not in RERUN_MODES:
            self._fail(f'rerun_mode must be one of {", ".join(RERUN_MODES)}, got {mode!r}')
            return
        try:
            from qtree_recorder import rerun_view

            if mode == 'save':
                self.view = rerun_view.RunView(mode='save', rrd_path=Path(rrd_path))
            else:
                self.view = rerun_view.RunView(mode='spawn')
            self.topics = tuple(rerun_view.TOPICS)
        except Exception as err:  # ImportError, rerun errors, bad path: recording goes on
            self._fail(f'{type(err).__name__}: {err}')

    def _fail(self, message: str) -> None:
        self.view = None
        self.error = message
        self._report(f'Rerun view disabled ({message}); the MCAP recording goes on')

    def wants(self, topic: str) -> bool:
        """True when the view shows ``topic``."""
        return self.view is not None and topic in self.topics

    def on_decoded(self, topic: str, msg: Any, t_ns: int) -> None:
        """Forward a decoded message (attributes as in the ROS type)."""
        if not self.wants(topic):
            return
        try:
            self.view.on_message(topic, msg, t_ns)
        except Exception as err:
            self._fail(f'on_message({topic}): {type(err).__name__}: {err}')

    def on_raw(self, topic: str, type_name: str, raw: bytes, t_ns: int) -> None:
        """Decode a CDR message of a topic the view shows, then forward it."""
        if not self.wants(topic):
            return
        try:
            from rclpy.serialization import deserialize_message

            msg = deserialize_message(raw, load_message_class(type_name))
        except Exception as err:
            self._report(f'cannot decode {topic} [{type_name}] for Rerun: {err}')
            return
        self.on_decoded(topic, msg, t_ns)

    def close(self) -> None:
        """Close the view (flushes the .rrd file)."""
        if self.view is not None:
            try:
                self.view.close()
            except Exception as err:
                self._report(f'Rerun view close failed: {err}')
            self.view = None
