"""Which nodes share a process (graph/process_plan.py), and how the launcher sees a node that
shares one (graph/processes.py, HostedNode)."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from sgim_nodes.graph.description import NODES
from sgim_nodes.graph.process_plan import (
    DEFAULT_GROUPS,
    parse_groups,
    process_plan,
    unknown_in_groups,
)
from sgim_nodes.graph.processes import HostedNode, node_log, write_members
from sgim_ros.ends import Ends, EndsReader
from sgim_ros.params import ParameterError

SGIM_D = ["recorder", "sim_bridge", "evaluator", "markers", "interest_computer",
          "goal_generator", "low_level_explorer", "imitation", "teacher", "social_interaction"]


def nodes(*names: str):
    return [NODES[name] for name in names]


def layout(plan) -> list[tuple[str, list[str]]]:
    return [(p.name, [spec.name for spec in p.members]) for p in plan]


def test_by_default_the_nodes_in_turn_share_one_process_and_the_observers_another():
    plan = process_plan(nodes(*SGIM_D))
    assert layout(plan) == [
        ("observers", ["recorder", "markers", "interest_computer"]),
        ("sim_bridge", ["sim_bridge"]), ("evaluator", ["evaluator"]),
        ("chain", ["goal_generator", "low_level_explorer", "imitation", "social_interaction"]),
        ("teacher", ["teacher"])]
    assert [p.composed for p in plan] == [True, False, False, True, False]
    assert {n for group in DEFAULT_GROUPS.values() for n in group} <= set(SGIM_D)


def test_separate_gives_every_node_its_own_process():
    plan = process_plan(nodes(*SGIM_D), separate=True)
    assert layout(plan) == [(name, [name]) for name in SGIM_D]


def test_a_prefixed_interactive_or_web_node_runs_alone():
    plan = process_plan(nodes("recorder", "markers", "human_input", "web_teacher",
                              "social_interaction"),
                        {"ui": ("recorder", "markers", "human_input", "web_teacher",
                                "social_interaction")}, alone={"markers"})
    assert layout(plan) == [("ui", ["recorder", "social_interaction"]), ("markers", ["markers"]),
                            ("human_input", ["human_input"]), ("web_teacher", ["web_teacher"])]


def test_a_group_left_with_one_node_runs_it_alone():
    plan = process_plan(nodes("recorder", "sim_bridge", "social_interaction"),
                        alone={"recorder"})
    assert layout(plan) == [("recorder", ["recorder"]), ("sim_bridge", ["sim_bridge"]),
                            ("social_interaction", ["social_interaction"])]


def test_namespaced_nodes_may_share_a_process_and_it_restarts_only_if_all_may():
    experts = [NODES["expert"].in_namespace(ns) for ns in ("centre", "west")]
    plan = process_plan([*experts, NODES["sim_bridge"]],
                        {"experts": ("centre/expert", "west/expert"),
                         "sims": ("sim_bridge",)})
    assert layout(plan) == [("experts", ["centre/expert", "west/expert"]),
                            ("sim_bridge", ["sim_bridge"])]
    assert not plan[0].respawn and plan[1].respawn


def test_groups_are_checked():
    with pytest.raises(ParameterError, match="two processes"):
        process_plan(nodes(*SGIM_D), {"a": ("recorder", "markers"), "b": ("markers",)})
    with pytest.raises(ParameterError, match="named like a node"):
        process_plan(nodes(*SGIM_D), {"recorder": ("markers", "imitation")})
    assert parse_groups(["fast=recorder, markers", "x=a"]) == {"fast": ("recorder", "markers"),
                                                              "x": ("a",)}
    for bad in ("fast", "=a,b", "fast=", "a/b=c,d"):
        with pytest.raises(ParameterError, match="--compose"):
            parse_groups([bad])
    with pytest.raises(ParameterError, match="twice"):
        parse_groups(["a=b,c", "a=d,e"])
    assert unknown_in_groups({"a": ("recorder", "recordr")}, NODES) == ["recordr"]


def child(body: str, *fds: int) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", body], pass_fds=fds)


def test_a_hosted_node_ends_with_its_line_or_with_its_process():
    read_end, write_end = os.pipe()
    process = child("import time; time.sleep(60)", write_end)
    told = Ends(write_end)  # the launcher's test stands in for the process's writes
    try:
        ends = EndsReader(read_end)
        arbiter = HostedNode(process, "social_interaction", ends)
        recorder = HostedNode(process, "recorder", ends)
        assert arbiter.poll() is None and recorder.poll() is None
        with pytest.raises(subprocess.TimeoutExpired):
            arbiter.wait(timeout=0.1)
        told.write("social_interaction", 0)
        assert arbiter.wait(timeout=5) == 0 and arbiter.returncode == 0
        assert not arbiter.killed_with_it
        assert recorder.poll() is None  # its process goes on
        os.close(write_end)
        process.kill()
        process.wait()
        assert recorder.wait(timeout=5) == -9 and recorder.killed_with_it
        assert arbiter.returncode == 0  # its own end stands
    finally:
        process.kill()
        process.wait()


def test_a_hosted_node_whose_line_came_as_its_process_ended_keeps_its_own_code():
    read_end, write_end = os.pipe()
    process = child(f"import os; os.write({write_end}, b'recorder 3\\n'); raise "
                    "SystemExit(3)", write_end)
    os.close(write_end)
    process.wait()
    recorder = HostedNode(process, "recorder", EndsReader(read_end))
    assert recorder.poll() == 3 and not recorder.killed_with_it


def test_the_ends_pipe_keeps_lines_split_across_reads():
    read_end, write_end = os.pipe()
    reader = EndsReader(read_end)
    os.write(write_end, b"centre/expert 0\nrecor")
    assert reader.read() == {"centre/expert": 0}
    os.write(write_end, b"der -9\ngarbage\n")
    os.close(write_end)
    assert reader.read() == {"centre/expert": 0, "recorder": -9} and reader.closed


def test_a_nodes_log_is_its_own_or_its_latest_hosts(tmp_path):
    assert node_log(tmp_path, "recorder") == tmp_path / "recorder.log"  # none yet
    write_members(tmp_path, "light", ["recorder", "markers"])
    assert node_log(tmp_path, "markers") == tmp_path / "light.log"
    time.sleep(0.01)
    write_members(tmp_path, "light.restart1", ["recorder", "markers"])
    assert node_log(tmp_path, "recorder") == tmp_path / "light.restart1.log"
    (tmp_path / "evaluator.log").write_text("alone\n")
    assert node_log(tmp_path, "evaluator") == tmp_path / "evaluator.log"


def test_compose_takes_a_runs_namespaced_nodes_and_refuses_unknown_names():
    from types import SimpleNamespace

    from sgim_nodes.graph.experiment import processes_of

    experts = [NODES["expert"].in_namespace(ns) for ns in ("centre", "west")]
    args = SimpleNamespace(compose=["experts=centre/expert,west/expert"], prefix=[],
                           separate=False)
    plan, _ = processes_of(args, [*experts, NODES["recorder"]])
    assert layout(plan) == [("experts", ["centre/expert", "west/expert"]),
                            ("recorder", ["recorder"])]
    args.compose = ["experts=centre/expert,east/expert"]
    with pytest.raises(ParameterError, match="names no node east/expert"):
        processes_of(args, [*experts, NODES["recorder"]])
