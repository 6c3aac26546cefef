"""Typed exceptions of the qtree_scene package (no ROS import)."""

from __future__ import annotations


class ScenarioError(ValueError):
    """A scenario file, scene message or generated scenario is invalid.

    Attributes:
        source: file path or scenario name the problem was found in.
        field: dotted path of the offending field, e.g. ``'objects[2].radius'`` ('' if global).
        problem: what is wrong, in words.
    """

    def __init__(self, source: str, field: str, problem: str) -> None:
        self.source = source
        self.field = field
        self.problem = problem
        where = f'{source}: ' if source else ''
        what = f'{field}: ' if field else ''
        super().__init__(f'{where}{what}{problem}')
