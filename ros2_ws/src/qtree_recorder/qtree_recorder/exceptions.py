"""Typed errors of the recorder core (no ROS import).

Every error carries the data needed to act on it and writes its own message, so the node can log
``str(error)`` and keep running.
"""

from __future__ import annotations


class RecorderError(Exception):
    """Base of every error raised by ``qtree_recorder``'s core."""


class DefinitionNotFoundError(RecorderError):
    """No ``.msg`` (or ``.action``) file could be found for a message type.

    Attributes:
        type_name: the type asked for, e.g. ``'foo_msgs/msg/Bar'``.
        reason: why the look-up failed (package not in the ament index, missing file...).
    """

    def __init__(self, type_name: str, reason: str) -> None:
        self.type_name = type_name
        self.reason = reason
        super().__init__(f'no message definition for {type_name}: {reason}')


class InvalidTypeNameError(RecorderError):
    """A type name is not of the form ``pkg/Type`` or ``pkg/(msg|srv|action)/Type``."""

    def __init__(self, type_name: str) -> None:
        self.type_name = type_name
        super().__init__(
            f'invalid ROS type name {type_name!r}: expected pkg/msg/Type (or pkg/Type)'
        )


class McapWriteError(RecorderError):
    """The MCAP file could not be created or written (unwritable directory, full disk...).

    Attributes:
        path: the file being written.
        operation: what was being done (``'open'``, ``'write'``, ``'close'``).
    """

    def __init__(self, path: str, operation: str, cause: BaseException) -> None:
        self.path = path
        self.operation = operation
        super().__init__(f'cannot {operation} MCAP file {path}: {cause}')


class WriterClosedError(RecorderError):
    """A message was written after the log was closed."""

    def __init__(self, path: str) -> None:
        self.path = path
        super().__init__(f'MCAP file {path} is already closed')


class RobotModelError(RecorderError):
    """The robot description (URDF) cannot be turned into a kinematic model for ``/tf``."""

    def __init__(self, reason: str) -> None:
        self.reason = reason
        super().__init__(f'cannot build the /tf model from the robot description: {reason}')


class EncodingError(RecorderError):
    """A message could not be encoded to CDR from its definition text."""

    def __init__(self, type_name: str, cause: BaseException) -> None:
        self.type_name = type_name
        super().__init__(f'cannot encode a {type_name} message: {cause}')
