"""ament_python package of the fishing-rod world, its data sets, tools and node.

colcon builds it into ros_ws as a ROS package; ``pip install ./sim_bridge`` installs the world
into any Python >= 3.11 environment without ROS, for the runner's ``--env fishing``
(docs/guide.md, "Using the learner without ROS"). ``install_requires`` lists what the world
imports (the tools' and the node's other needs are in package.xml; colcon installs nothing
from this list).
"""

import atexit
import shutil
import sys
import tempfile
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "sim_bridge"

# The route is told by the setup command, as in sgim_nodes/setup.py: colcon runs `setup.py
# develop` (--symlink-install) or `setup.py ... install`; pip, which pyproject.toml sends
# through setuptools' PEP 517 backend, runs only egg_info, dist_info, bdist_wheel or
# editable_wheel.
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
        # The reachable map, benchmark goals, teaching set and floor (data_files.data_dir).
        (f"share/{PACKAGE}/data", glob("data/*.npz")),
    ],
    python_requires=">=3.11",
    # setuptools: the ament_python template's; numpy and pybullet: the world. The lower bounds
    # are requirements.txt's pins, the versions the world's data sets were made with.
    install_requires=["setuptools", "numpy>=2.4.6", "pybullet>=3.2.7"],
    options=outside_the_tree(),
    zip_safe=False,
    maintainer="SGIM-ROS maintainers",
    maintainer_email="maintainers@sgim-ros.org",
    description="pybullet fishing-rod world and its ROS 2 node.",
    license="Apache-2.0",
    # pip's route installs no command: the node needs ROS, and the tools' generic names
    # (render_cast, map_reachable) would land on the user's PATH; they run as
    # `python -m sim_bridge.tools.NAME` from any install.
    entry_points={
        # The runner's --env fishing, found by the learner core (sgim_nodes/core/worlds.py)
        # on either route.
        "sgim_nodes.worlds": ["fishing = sim_bridge.core_world:fishing_world"],
        "console_scripts": [
            "sim_bridge = sim_bridge.sim_bridge_node:main",
            "map_reachable = sim_bridge.tools.map_reachable:main",
            "make_benchmark_set = sim_bridge.tools.make_benchmark_set:main",
            "make_teaching_set = sim_bridge.tools.make_teaching_set:main",
            "render_cast = sim_bridge.tools.render_cast:main",
        ] if COLCON_ROUTE else [],
    },
)
