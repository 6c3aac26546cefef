"""Typed exceptions of the jaco2_sim package, all under :class:`Jaco2SimError` (no ROS import)."""

from __future__ import annotations


class Jaco2SimError(Exception):
    """Base class of every error raised by the jaco2_sim core."""


class ModelError(Jaco2SimError):
    """The robot model cannot be built or was given a bad configuration."""


class ScenarioError(Jaco2SimError):
    """A scenario file or generated scenario is invalid.

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


class TrajectoryError(Jaco2SimError):
    """A reference trajectory is malformed (wrong joint names, lengths, times or NaN values)."""


class WorldError(Jaco2SimError):
    """An attach/detach request does not fit the world state (unknown id, already attached)."""
