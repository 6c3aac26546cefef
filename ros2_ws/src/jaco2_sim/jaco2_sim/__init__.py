"""Kinova Jaco² 7-DoF model (URDF, Pinocchio, FCL), kinematic simulator and scenarios."""
