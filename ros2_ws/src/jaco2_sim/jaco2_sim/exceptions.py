"""Typed exceptions of the jaco2_sim package, all under :class:`Jaco2SimError` (no ROS import).

Scenario and model errors live with their types (:mod:`qtree_scene.exceptions`,
:mod:`jaco2_description.exceptions`) and are re-exported here so ``except Jaco2SimError``-style
callers can name them from one place.
"""

from __future__ import annotations

from jaco2_description.exceptions import ModelError
from qtree_scene.exceptions import ScenarioError

__all__ = [
    'DisturbanceError',
    'Jaco2SimError',
    'ModelError',
    'ScenarioError',
    'SceneEventError',
    'TrajectoryError',
    'WorldError',
]


class Jaco2SimError(Exception):
    """Base class of every error raised by the jaco2_sim core."""


class TrajectoryError(Jaco2SimError):
    """A reference trajectory is malformed (wrong joint names, lengths, times or NaN values)."""


class WorldError(Jaco2SimError):
    """An attach/detach request does not fit the world state (unknown id, already attached)."""


class DisturbanceError(Jaco2SimError):
    """A disturbance parameter is NaN, negative or out of its range."""


class SceneEventError(Jaco2SimError):
    """A ``scene_events`` entry is malformed or would leave the scene invalid (#32)."""
