"""ament_python package of the learner's nodes and their ROS-free core.

colcon builds it into ros_ws as a ROS package; ``pip install ./sgim_nodes`` installs it into any
Python >= 3.11 environment without ROS, for the core (``sgim_nodes.core``, docs/guide.md, "Using
the learner without ROS"). ``install_requires`` lists what the core and its runner import; the
nodes' ROS dependencies are in package.xml, and colcon installs nothing from this list.
"""

import atexit
import shutil
import sys
import tempfile
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "sgim_nodes"

# colcon's commands, under their names in lib/sgim_nodes/: `ros2 run`, ros_ws/ros2run.sh, the
# launch files and graph/description.py find them there.
ROS_SCRIPTS = [
    "learn = sgim_nodes.core.runner:main",
    "interest_computer = sgim_nodes.nodes.interest_computer:main",
    "goal_generator = sgim_nodes.nodes.goal_generator:main",
    "low_level_explorer = sgim_nodes.nodes.low_level_explorer:main",
    "imitation = sgim_nodes.nodes.imitation:main",
    "social_interaction = sgim_nodes.nodes.social_interaction:main",
    "evaluator = sgim_nodes.nodes.evaluator:main",
    "recorder = sgim_nodes.nodes.recorder:main",
    "markers = sgim_nodes.nodes.markers:main",
    "composed = sgim_nodes.nodes.composed:main",
    "replay = sgim_nodes.bag.replay:main",
    "rebuild = sgim_nodes.bag.rebuild:main",
    "repair = sgim_nodes.bag.repair:main",
    "analyze = sgim_nodes.analysis.cli:main",
]
# pip's commands, on the user's PATH: only what runs from a pip install without ROS, each with
# the package's prefix, so that nothing generic (`learn`, `analyze`) shadows another tool. The
# nodes and replay need rclpy; rebuild, repair and analyze need rosbags, matplotlib, sim_bridge
# and sgim_msgs' .msg files, none of which a pip install of this package brings.
PIP_SCRIPTS = [
    "sgim-learn = sgim_nodes.core.runner:main",
]
# The route is told by the setup command. colcon runs `setup.py develop` (--symlink-install) or
# `setup.py ... install`; pip, which pyproject.toml sends through setuptools' PEP 517 backend
# whatever its version, runs only egg_info, dist_info, bdist_wheel or editable_wheel. An option
# would need every colcon build to pass it, and an environment variable every caller to set it.
COLCON_ROUTE = not {"develop", "install"}.isdisjoint(sys.argv[1:])


def outside_the_tree() -> dict[str, dict[str, str]]:
    """pip's build directories in a temporary folder, removed when the build ends: pip builds
    in the source folder, where setuptools would leave build/ and the egg-info behind. colcon
    names its own (in ros_ws/build), so its route keeps setuptools' defaults."""
    if COLCON_ROUTE:
        return {}
    scratch = tempfile.mkdtemp(prefix=f"{PACKAGE}-build-")
    atexit.register(shutil.rmtree, scratch, ignore_errors=True)
    return {"build": {"build_base": f"{scratch}/build"}, "egg_info": {"egg_base": scratch}}


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "tests"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
    ],
    python_requires=">=3.11",
    # setuptools: the ament_python template's; numpy, scipy: the core; tqdm: the runner's bar.
    install_requires=["setuptools", "numpy", "scipy", "tqdm"],
    options=outside_the_tree(),
    zip_safe=False,
    maintainer="SGIM-ROS maintainers",
    maintainer_email="maintainers@sgim-ros.org",
    description="SGIM-D learner nodes over a pure-Python core.",
    license="Apache-2.0",
    entry_points={"console_scripts": ROS_SCRIPTS if COLCON_ROUTE else PIP_SCRIPTS},
)
