"""Cartesian sampling planner with a Set-based Task-Priority IK (STPIK) check."""
