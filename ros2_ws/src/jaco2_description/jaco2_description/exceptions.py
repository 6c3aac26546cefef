"""Typed exceptions of the jaco2_description package (no ROS import)."""

from __future__ import annotations


class ModelError(Exception):
    """The robot model cannot be built or was given a bad configuration."""
