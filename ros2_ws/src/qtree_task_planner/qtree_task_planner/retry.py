"""Bounded exponential back-off of the feasibility oracle (no ROS import) (#18).

A busy motion planner (PLANNER_BUSY), a planning time-out (TIMEOUT: the time limit ran out,
usually because the machine was loaded; the planner does not cache it) and a reply lost in
transport are not answers about feasibility: learning them as -1 (eq. 8) makes the tree wrong.
The oracle asks again after ``delay(k)`` seconds for the k-th retry, at most ``retries`` times
then gives up and the goal aborts with MOTION_PLANNER_UNAVAILABLE. A reply that does not come is
asked again ``missing_retries`` times within the same call time-out (#26): a dead planner is
reported after one time-out.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Backoff:
    """Retry bounds of one feasibility question.

    Attributes:
        retries: most retries of a busy / timed-out answer [-].
        missing_retries: copies of a question sent again within its time-out if no reply [-].
        first_s: delay before the first retry [s].
        cap_s: longest delay between two attempts [s].
    """

    retries: int = 8
    missing_retries: int = 1
    first_s: float = 0.1
    cap_s: float = 2.0

    def __post_init__(self) -> None:
        """Check the bounds.

        Raises:
            ValueError: a negative count, or delays not 0 < first_s <= cap_s.
        """
        if self.retries < 0 or self.missing_retries < 0:
            raise ValueError('retry counts must be >= 0')
        if not 0.0 < self.first_s <= self.cap_s:
            raise ValueError(f'need 0 < first_s <= cap_s, got {self.first_s}, {self.cap_s}')

    def delay(self, retry: int) -> float:
        """Wait before retry number ``retry`` (0-based): ``min(cap_s, first_s * 2**retry)`` [s]."""
        return min(self.cap_s, self.first_s * 2.0 ** min(retry, 60))

    def total_s(self) -> float:
        """Sum of every delay of :attr:`retries` retries [s] (the back-off's bound)."""
        return sum(self.delay(k) for k in range(self.retries))
