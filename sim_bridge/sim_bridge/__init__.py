"""Fishing-rod world of the SGIM-D experiment: pure-Python core, importable without ROS."""

from sim_bridge.pybullet_import import import_pybullet

import_pybullet()  # now, so that no command shows pybullet's build-time line
