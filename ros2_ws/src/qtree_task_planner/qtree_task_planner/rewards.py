"""Reward function of the Q-Tree, eq. (8) of the paper.

Implements eq. (8)::

    r(s, a) =   0   if the obstacle can be relocated (grasp_O)
               -1   if the obstacle or the target cannot be relocated
              100   if a = a_T and the target can be grasped and relocated (grasp_T)
"""

from __future__ import annotations

REWARD_OBSTACLE = 0.0  # eq. (8): obstacle relocated
REWARD_INFEASIBLE = -1.0  # eq. (8): obstacle or target cannot be relocated
REWARD_TARGET = 100.0  # eq. (8): target relocated, r_T of eq. (17)


def reward(object_id: str, target_id: str, feasible: bool) -> float:
    """Reward of relocating ``object_id`` as answered by the motion planner, eq. (8).

    Args:
        object_id: the object the action relocates.
        target_id: id of the target T.
        feasible: motion-planner answer: can the object be grasped and relocated.

    Returns:
        0, -1 or 100 [reward units].
    """
    if not feasible:
        return REWARD_INFEASIBLE
    return REWARD_TARGET if object_id == target_id else REWARD_OBSTACLE
