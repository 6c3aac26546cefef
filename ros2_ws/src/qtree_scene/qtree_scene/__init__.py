"""Scene types, the scenario YAML loader/validator and the clutter generator (no ROS import).

Shared by the simulator and the motion planner without either depending on the other.
"""
