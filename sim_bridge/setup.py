"""ament_python package of the fishing-rod world, its data sets, tools and node."""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "sim_bridge"

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
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="SGIM-ROS maintainers",
    maintainer_email="maintainers@sgim-ros.org",
    description="pybullet fishing-rod world and its ROS 2 node.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "sim_bridge = sim_bridge.sim_bridge_node:main",
            "map_reachable = sim_bridge.tools.map_reachable:main",
            "make_benchmark_set = sim_bridge.tools.make_benchmark_set:main",
            "make_teaching_set = sim_bridge.tools.make_teaching_set:main",
            "render_cast = sim_bridge.tools.render_cast:main",
        ],
    },
)
