"""ament_python package of the learner's nodes and their ROS-free core.

colcon builds it into ros_ws as a ROS package; ``pip install ./sgim_nodes`` installs it into any
Python >= 3.11 environment without ROS, for the core (``sgim_nodes.core``, README "Using the
learner without ROS"). ``install_requires`` lists what the core and its runner import; the
nodes' ROS dependencies are in package.xml, and colcon installs nothing from this list.
"""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "sgim_nodes"

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
    zip_safe=False,
    maintainer="SGIM-ROS maintainers",
    maintainer_email="maintainers@sgim-ros.org",
    description="SGIM-D learner nodes over a pure-Python core.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "learn = sgim_nodes.core.runner:main",
            "interest_computer = sgim_nodes.nodes.interest_computer:main",
            "goal_generator = sgim_nodes.nodes.goal_generator:main",
            "low_level_explorer = sgim_nodes.nodes.low_level_explorer:main",
            "imitation = sgim_nodes.nodes.imitation:main",
            "social_interaction = sgim_nodes.nodes.social_interaction:main",
            "evaluator = sgim_nodes.nodes.evaluator:main",
            "recorder = sgim_nodes.nodes.recorder:main",
            "markers = sgim_nodes.nodes.markers:main",
            "replay = sgim_nodes.bag.replay:main",
            "rebuild = sgim_nodes.bag.rebuild:main",
            "repair = sgim_nodes.bag.repair:main",
            "analyze = sgim_nodes.analysis.cli:main",
        ],
    },
)
