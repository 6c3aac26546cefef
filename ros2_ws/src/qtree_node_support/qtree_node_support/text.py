"""Clipping of text that a node echoes from a request (no ROS import).

A request may carry a 10 000-character id, scenario name or policy; answers, log lines and
published messages quote at most a bounded prefix of it, so their size never depends on the
request (docs/RELIABILITY.md).
"""

from __future__ import annotations

SHOWN_CHARS = 40  # characters of a quoted request value shown in a message [characters]


def clip(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters (ending in '…' when cut).

    Args:
        text: any text.
        limit: the longest result [characters], >= 1.
    """
    return text if len(text) <= limit else text[: limit - 1] + '…'


def quote(value: object, shown: int = SHOWN_CHARS) -> str:
    """``repr(value)``; a string longer than ``shown`` characters is cut, with its length.

    Args:
        value: the value to quote (usually a string from a request).
        shown: characters of a long string that are kept.

    Returns:
        ``'O1'``, or ``'xxxx…' (10000 characters)`` for a long string; at most
        ``shown + 30`` characters for a string, ``repr`` for anything else.
    """
    if isinstance(value, str) and len(value) > shown:
        return f"'{value[:shown]}…' ({len(value)} characters)"
    return repr(value)
