"""Kinova Jaco² j2s7s300 description: URDF, Pinocchio/FCL loader, limits, self-collision pairs.

Read by the simulator, the motion planner, the recorder and the viewers; imports no ROS package.
"""
