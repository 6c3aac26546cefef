"""Typed exceptions of the qtree_scene package (no ROS import)."""

from __future__ import annotations

from qtree_node_support.text import clip

MAX_SOURCE_CHARS = 300  # longest file path or name quoted in the message [characters]


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
        where = f'{clip(source, MAX_SOURCE_CHARS)}: ' if source else ''  # a path may be huge
        what = f'{field}: ' if field else ''
        super().__init__(f'{where}{what}{problem}')
