"""Checks of one field of an outside input (scenario file, scene message, scene event) and the
quoting of a bad value in the error message, shared by every reader of outside data (no ROS).
"""

from __future__ import annotations

import math
import numbers
import reprlib
from collections.abc import Callable
from typing import Any, NoReturn

from qtree_scene.exceptions import ScenarioError

MAX_SHOWN = 60  # characters of a bad value quoted in an error message
_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxstring, _REPR.maxother = 3, MAX_SHOWN, MAX_SHOWN

Fail = Callable[[str, str], NoReturn]
"""``fail(field, problem)``: raise the reader's error naming the field; never returns."""


def failer(source: str) -> Fail:
    """``fail(field, problem)`` raising :class:`ScenarioError` for ``source``."""

    def fail(field: str, problem: str) -> NoReturn:
        raise ScenarioError(source, field, problem)

    return fail


def brief(value: Any) -> str:
    """``repr(value)``, cut to :data:`MAX_SHOWN` characters (a bad value may be huge)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**MAX_SHOWN:
        return f'an integer of {value.bit_length()} bits'  # str() fails beyond 4300 digits
    try:
        text = _REPR.repr(value)  # depth and length limited: fast on huge or deep values
    except (ValueError, RecursionError):  # e.g. an int of > 4300 digits inside a list
        return f'a {type(value).__name__}'
    return text if len(text) <= MAX_SHOWN else f'{text[: MAX_SHOWN - 3]}...'


def number(value: Any, field: str, fail: Fail, positive: bool = False) -> float:
    """``value`` as a finite float (> 0 when ``positive``), else ``fail(field, problem)``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        fail(field, f'expected a number, got {type(value).__name__} {brief(value)}')
    try:
        result = float(value)
    except (OverflowError, TypeError, ValueError):
        fail(field, f'{brief(value)} is too large for a float')
    if not math.isfinite(result):
        fail(field, f'must be finite, got {result}')
    if positive and result <= 0:
        fail(field, f'must be > 0, got {result}')
    return result
