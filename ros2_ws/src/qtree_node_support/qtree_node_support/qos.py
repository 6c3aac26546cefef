"""QoS of every service, service client and action of the graph, chosen on purpose (docs/QOS.md).

rclpy's default for services is KEEP_LAST with depth 10: a burst of more than 10 requests (or 10
replies on the shared reply topic of a service) silently drops the oldest, and the clients wait
forever. Services here keep every sample until it is taken (KEEP_ALL, RELIABLE, VOLATILE): the
servers bound their work themselves (the motion planner answers PLANNER_BUSY at once when its
queue is full), so nothing is ever dropped by the middleware.
"""

from __future__ import annotations

from typing import Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

SERVICE_QOS = QoSProfile(  # requests and replies: never dropped by the history
    history=HistoryPolicy.KEEP_ALL,
    depth=1,  # ignored with KEEP_ALL
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,  # a request is for the server running now
)
LATCHED_QOS = QoSProfile(  # /scene, /qtree, /robot_description: a late joiner gets the last one
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
# Streams (reliable, volatile): a subscriber needs the samples from the time it matched on.
STATE_QOS = QoSProfile(depth=10)  # /joint_states and the closed loop's joint commands
TRAJECTORY_QOS = QoSProfile(depth=10)  # /joint_trajectory: the sim follows the newest
STATS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)  # episode bursts


def action_server_qos() -> dict[str, Any]:
    """Keyword arguments of ``rclpy.action.ActionServer``: its three services use SERVICE_QOS.

    Feedback (KEEP_LAST 10, reliable) and status (transient local, depth 1) keep rclpy's
    defaults: a client only needs the latest of each.
    """
    return {
        'goal_service_qos_profile': SERVICE_QOS,
        'result_service_qos_profile': SERVICE_QOS,
        'cancel_service_qos_profile': SERVICE_QOS,
    }


def action_client_qos() -> dict[str, Any]:
    """Keyword arguments of ``rclpy.action.ActionClient`` matching :func:`action_server_qos`."""
    return action_server_qos()
