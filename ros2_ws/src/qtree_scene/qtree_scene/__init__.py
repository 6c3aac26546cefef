"""Scene types, the scenario YAML loader/validator, the clutter generator and Scene conversions.

Shared by the simulator and the motion planner without either depending on the other.
"""
