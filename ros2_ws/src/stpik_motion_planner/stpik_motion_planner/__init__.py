"""Cartesian sampling planner with a Set-based Task-Priority IK check, served as qtree_msgs/srv/RelocateObject."""
