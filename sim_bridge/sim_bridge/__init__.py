"""Fishing-rod world of the SGIM-D experiment: pure-Python core, importable without ROS."""
