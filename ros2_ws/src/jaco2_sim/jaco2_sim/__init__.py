"""Kinova Jaco2 7-DoF model (URDF, Pinocchio, FCL), kinematic simulator node and the scenarios of the paper."""
