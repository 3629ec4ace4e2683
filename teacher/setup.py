"""ament_python package of the automatic teacher and the human-input node."""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "teacher"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "tests"]),
    # The web teacher's page (teacher/web/static) is served from beside its module.
    package_data={"teacher.web": ["static/*"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="SGIM-ROS maintainers",
    maintainer_email="maintainers@sgim-ros.org",
    description="Automatic and human teachers for SGIM-D: terminal prompt and web page.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "teacher = teacher.teacher_node:main",
            "human_input = teacher.human_input_node:main",
            "web_teacher = teacher.web_teacher_node:main",
            "expert = teacher.expert_node:main",
        ],
    },
)
