"""One checker of numeric settings against their ranges (no ROS import).

Every range table of the graph (the motion planner's ``RANGES``, the closed loop's
``EXECUTION_RANGES``, the task planner's timeouts, the simulator's disturbances) is checked by
:func:`range_problem`, and declared to ROS by
:func:`qtree_node_support.parameters.range_descriptor` with the same bounds, so a value a node
accepts from a parameter, a config built in code or a request is valid in all three (#27).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping

Range = tuple[float, float, str]  # (lowest, highest valid value, description with the unit)


def range_problem(value: object, low: float, high: float, *, integer: bool = False) -> str | None:
    """Why ``value`` is not a valid setting in [``low``, ``high``], or None when it is.

    Args:
        value: the value given (any type: parameters, YAML and requests reach here unchecked).
        low: lowest valid value (inclusive).
        high: highest valid value (inclusive).
        integer: the setting counts something (a float with an integer value is accepted).

    Returns:
        ``'must be a number'`` (also for booleans), ``'must be an integer'`` (also NaN for an
        integer setting), ``'must be in [low, high]'`` (also NaN and infinities), or None.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return 'must be a number'
    if integer and not float(value).is_integer():
        return 'must be an integer'
    if not math.isfinite(value) or not low <= value <= high:
        return f'must be in [{low}, {high}]'
    return None


def setting_problem(
    table: Mapping[str, Range],
    name: str,
    value: object,
    *,
    kind: str,
    integer_fields: Collection[str] = (),
) -> str | None:
    """Why ``value`` is not valid for setting ``name`` of ``table``, or None when it is.

    Args:
        table: setting name -> :data:`Range`.
        name: the setting.
        value: the value given.
        kind: what the table configures, for the message (``'unknown planner setting'``).
        integer_fields: the settings of ``table`` that count something.
    """
    if name not in table:
        return f'unknown {kind} setting'
    low, high, _ = table[name]
    return range_problem(value, low, high, integer=name in integer_fields)
