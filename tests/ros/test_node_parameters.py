"""Every node refuses a bad parameter at start-up with a message naming it."""

from __future__ import annotations

import subprocess

import pytest

from tests.conftest import ROS2RUN

pytestmark = pytest.mark.ros


CASES = [
    ("sgim_nodes", "interest_computer", "zeta:=7", "zeta"),  # must be even
    ("sgim_nodes", "goal_generator", "p_mode1:=0.9", "p_mode1"),  # modes must sum to 1
    ("sgim_nodes", "low_level_explorer", "goal_budget:=0", "goal_budget"),
    ("sgim_nodes", "imitation", "imitation_epsilon:=-0.1", "imitation_epsilon"),
    ("sgim_nodes", "social_interaction", "learner:=sgimd", "learner"),
    ("sgim_nodes", "evaluator", "eval_every:=-5", "eval_every"),
    ("sgim_nodes", "social_interaction", "movements:=many", "movements"),  # wrong type
    ("teacher", "teacher", "demonstration_period:=0", "demonstration_period"),
    ("sgim_nodes", "recorder", "storage:=zip", "storage"),
]


@pytest.mark.parametrize(("package", "node", "setting", "name"), CASES)
def test_bad_parameter_is_named_and_stops_the_node(ros_processes, tmp_path, package, node,
                                                   setting, name):
    argv = [ROS2RUN, package, node, "--ros-args", "-p", setting]
    if node == "recorder":
        argv += ["-p", f"output:={tmp_path / 'bag'}"]
    child = ros_processes.start(f"{node}-bad", argv, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    output, _ = child.communicate(timeout=60)
    assert child.returncode == 2, output
    assert name in output
    assert "Traceback" not in output
