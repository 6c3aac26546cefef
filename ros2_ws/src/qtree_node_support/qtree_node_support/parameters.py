"""ROS parameter descriptors of range-checked settings (see :mod:`qtree_node_support.ranges`)."""

from __future__ import annotations

from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor


def range_descriptor(
    text: str,
    low: float | None = None,
    high: float | None = None,
    *,
    integer: bool | None = None,
    **fields: Any,
) -> ParameterDescriptor:
    """Descriptor with ``text`` and the range [``low``, ``high``] (no range when ``low`` is None).

    Args:
        text: description, with the unit.
        low: lowest valid value (inclusive); None: no range.
        high: highest valid value (inclusive).
        integer: an integer range (step 1); None: integer when both bounds are ``int``.
        fields: other ``ParameterDescriptor`` fields (e.g. ``read_only=True``).
    """
    if low is not None and high is not None:
        if integer is None:
            integer = isinstance(low, int) and isinstance(high, int)
        if integer:
            rng = IntegerRange(from_value=int(low), to_value=int(high), step=1)
            fields['integer_range'] = [rng]
        else:
            fields['floating_point_range'] = [
                FloatingPointRange(from_value=float(low), to_value=float(high))
            ]
    return ParameterDescriptor(description=text, **fields)
