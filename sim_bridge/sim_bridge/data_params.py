"""The checks of node parameters that name one of the world's data files.

Apart from data_files.py, which the analysis reads without ROS: these are sgim_ros.params
checks, for the nodes and the launcher. Every node that takes a `teaching_set` declares it with
TEACHING_SET_FILE, so the launcher refuses a wrong file before any node starts, whichever node
it is given to (graph/description.py checks a value against every node that declares it).
"""

from __future__ import annotations

from sgim_ros.params import DataFile
from sim_bridge.data_files import TEACHING_SET_FORMAT, teaching_set_problem

TEACHING_SET_FILE = DataFile(TEACHING_SET_FORMAT, teaching_set_problem)
