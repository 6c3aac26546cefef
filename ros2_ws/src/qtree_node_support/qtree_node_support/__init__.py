"""Shared by every qtree-tamp node: :mod:`.lifecycle` (run until SIGINT/SIGTERM, exit 0),
:mod:`.qos` (service and action QoS, see docs/QOS.md) and :mod:`.text` (clipping of echoed text,
no ROS import).
"""
