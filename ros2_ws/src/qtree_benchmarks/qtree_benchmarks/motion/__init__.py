"""Motion-planner benchmark, importable (used by scripts/bench_motion_planner.py). No ROS."""
