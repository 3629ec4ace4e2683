"""Helpers for starting and isolating a node graph (domains, processes); no ROS imports."""
