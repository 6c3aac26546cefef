"""Typed exceptions of the Q-Tree task planner (no ROS import).

All derive from :class:`QTreeError`, so a caller can catch the whole family at once. Each carries
the data that explains it and builds its own message.
"""

from __future__ import annotations

from qtree_node_support.text import quote


class QTreeError(Exception):
    """Base class of every error raised by ``qtree_task_planner``."""


class InvalidParameterError(QTreeError, ValueError):
    """A training parameter (or goal field) is out of its valid range.

    Attributes:
        field: name of the offending parameter, as in the RetrieveTarget goal.
        value: the rejected value.
        reason: what the valid range is.
    """

    def __init__(self, field: str, value: object, reason: str) -> None:
        self.field = field
        self.value = value
        self.reason = reason
        super().__init__(f'invalid {field}={quote(value)}: {reason}')  # a policy may be huge


class UnknownPolicyError(InvalidParameterError):
    """The policy name is not one of the known exploration policies."""

    def __init__(self, name: str, known: tuple[str, ...]) -> None:
        super().__init__('policy', name, f'unknown policy, expected one of {", ".join(known)}')


class InvalidScenarioError(QTreeError, ValueError):
    """The object list cannot be planned on (no target, duplicate ids, ...)."""


class OracleUnavailableError(QTreeError, RuntimeError):
    """The feasibility oracle (motion planner) did not answer.

    Attributes:
        object_id: object whose relocation was asked about.
        relocated: objects already relocated in the query.
        detail: why there was no answer (timeout, service absent, ...).
    """

    def __init__(self, object_id: str, relocated: tuple[str, ...], detail: str) -> None:
        self.object_id = object_id
        self.relocated = relocated
        self.detail = detail
        super().__init__(
            f'motion planner gave no answer for {object_id!r} after {list(relocated)}: {detail}'
        )


class SearchLimitExceededError(QTreeError, RuntimeError):
    """The exact search exceeded its budget of explored sets.

    Attributes:
        limit: the budget [sets].
    """

    def __init__(self, limit: int) -> None:
        self.limit = limit
        super().__init__(f'exact search explored more than {limit} sets')


class BudgetExceededError(OracleUnavailableError):
    """A planner-run or wall-time budget is used up: the oracle answers no more questions.

    An :class:`OracleUnavailableError`, so a trainer stops as it does when the planner is gone.

    Attributes:
        which: the budget, e.g. ``'planner_runs'`` or ``'time'``.
    """

    def __init__(self, which: str, detail: str = '') -> None:
        super().__init__('?', (), detail or f'{which} budget used up')
        self.which = which

    def __str__(self) -> str:
        return self.detail
