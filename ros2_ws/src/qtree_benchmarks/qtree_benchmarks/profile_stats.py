"""The raw table of a cProfile run, typed (no ROS import)."""

from __future__ import annotations

import cProfile
import pstats

FunctionKey = tuple[str, int, str]  # (file, line, function name)
# (primitive calls, all calls, own time [s], cumulative time [s], callers)
FunctionRow = tuple[int, int, float, float, dict]


def raw_stats(profiler: cProfile.Profile) -> dict[FunctionKey, FunctionRow]:
    """Every profiled function's row, keyed by where it is defined.

    ``pstats.Stats.stats`` is the documented content of a profile (``pstats`` docs,
    "The Stats Class") but typeshed does not declare it; ``get_stats_profile`` keys by
    function name alone and would merge same-named functions of different files.
    """
    return pstats.Stats(profiler).stats  # type: ignore[attr-defined]
