"""SGIM-ACTS's teachers as nodes (issue 33): an expert in its namespace answers the requests
that name it, as the core's Expert of the same seed does, number for number."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from tests.conftest import ROS2RUN

pytestmark = pytest.mark.ros

SEED = 5


def core_answers(name: str, asks: list[tuple[np.ndarray, bool]]):
    """What the runner's expert `name` answers to `asks` (goal, wants the action)."""
    from sgim_nodes.core.acts_runner import experts_for
    from sgim_nodes.core.experts import FISHING_EXPERTS
    from sgim_nodes.core.runner import build_world

    world = build_world("fishing", SEED)
    [spec] = [s for s in FISHING_EXPERTS if s.name == name]
    expert = experts_for("fishing", world, SEED, [spec])[name]
    return [expert.answer(goal, wants) for goal, wants in asks]


def ask_and_collect(rclpy_context, asks: list[tuple[str, np.ndarray, str]], experts: set[str]):
    """Publish HelpRequests (teacher, goal, content) once every expert in `experts` hears
    them; return the Demonstrations answering them, by request index."""
    from sgim_msgs.msg import Demonstration, HelpRequest
    from sgim_ros import qos
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "learner_asking")
    try:
        answers = client.capture(Demonstration, "/demonstrations", qos.RECORDS)
        requests = client.node.create_publisher(HelpRequest, "/help_requests", qos.RECORDS)
        heard = client.spin_until(lambda: all(
            any(i.node_namespace == f"/{name}" and i.node_name == "expert"
                for i in client.node.get_subscriptions_info_by_topic("/help_requests"))
            for name in experts), 60)
        assert heard, "the experts never subscribed to /help_requests"
        assert client.spin_until(
            lambda: client.node.count_publishers("/demonstrations") >= len(experts)
            and requests.get_subscription_count() >= len(experts), 30)
        client.spin_for(0.5)  # the experts' writers match this reader too
        for index, (teacher, goal, content) in enumerate(asks, 1):
            requests.publish(HelpRequest(index=index, movement_index=10 * index,
                                         goal=[float(x) for x in goal], teacher=teacher,
                                         content=content))
        wanted = {i for i, (t, _, _) in enumerate(asks, 1) if t in experts}
        assert client.spin_until(lambda: {a.help_request for a in answers} >= wanted, 60), (
            [a.help_request for a in answers])
        client.spin_for(0.5)  # nothing more comes: a request to another teacher is not ours
        return {a.help_request: a for a in answers}
    finally:
        client.close()


def test_experts_answer_their_own_requests_as_the_core_does(ros_processes, rclpy_context):
    from sgim_nodes.core.experts import FISHING_EXPERTS
    from sgim_nodes.core.teaching import GOAL_ONLY, MEANS_AND_GOAL
    from sim_bridge.data_files import load_teaching_set
    from sim_bridge.lake import Lake

    for name in ("rough", "centre"):  # named by their namespace alone
        ros_processes.start(name, [ROS2RUN, "teacher", "expert", "--ros-args", "-r",
                                   f"__ns:=/{name}", "-p", f"seed:={SEED}"])
    teaching = load_teaching_set()
    pond, _ = Lake().isolated_centre_radius()
    rng = np.random.default_rng(1)
    goals = [*teaching.outcomes[[0, 5, 12]], *rng.uniform(-1, 1, (3, 2)), pond]
    asks = [("rough", g, MEANS_AND_GOAL if i % 2 else GOAL_ONLY) for i, g in enumerate(goals)]
    asks += [("centre", g, MEANS_AND_GOAL) for g in goals]
    asks += [("west", goals[0], MEANS_AND_GOAL)]  # no such expert here: nobody answers
    got = ask_and_collect(rclpy_context, asks, {"rough", "centre"})
    assert len(asks) not in got

    for name in ("rough", "centre"):
        mine = [(i, goal, content) for i, (t, goal, content) in enumerate(asks, 1) if t == name]
        expected = core_answers(name, [(goal, content == MEANS_AND_GOAL)
                                       for _, goal, content in mine])
        [spec] = [s for s in FISHING_EXPERTS if s.name == name]
        shown = 0
        for (index, goal, content), want in zip(mine, expected, strict=True):
            demo = got[index]
            assert demo.source == f"expert:{name}" and demo.movement_index == 10 * index
            if want is None or (content == GOAL_ONLY and want.outcome is None):
                assert (len(demo.action), len(demo.outcome), demo.teaching_set_index) == (
                    0, 0, -1), index
                continue
            shown += 1
            assert demo.index == shown
            row = teaching.outcomes[demo.teaching_set_index]
            assert np.linalg.norm(row - goal) == pytest.approx(want.distance, abs=1e-12)
            if content == MEANS_AND_GOAL:
                assert np.array_equal(demo.action, want.action), index
            else:
                assert len(demo.action) == 0 and demo.content == GOAL_ONLY
            assert np.array_equal(demo.outcome, [] if want.outcome is None else want.outcome)
            if spec.precision == 0.0 and content == MEANS_AND_GOAL:
                assert np.array_equal(demo.action, teaching.actions[demo.teaching_set_index])
        if name == "rough":  # knows everything: always answers, actions perturbed
            assert shown >= len(mine) - 2 and spec.precision > 0
        else:  # the centre knows neither the pond nor goals far from its demonstrations
            assert len(got[mine[-1][0]].action) == 0 and 0 < shown < len(mine)


@pytest.mark.parametrize(("args", "expected"), [
    (["-r", "__ns:=/north"], "the fishing world has no expert 'north'"),
    (["-r", "__ns:=/west", "-p", "precision:=0.1"], "set part too"),
    (["-p", "name:=no-dash"], "bad teacher name 'no-dash'"),
    (["-p", "name:=mine", "-p", "part:=parts:nowhere"], "no demonstration in part"),
])
def test_an_expert_refuses_what_it_cannot_be(ros_processes, args, expected):
    child = ros_processes.start("expert-bad", [ROS2RUN, "teacher", "expert", "--ros-args",
                                               *args], stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    output, _ = child.communicate(timeout=60)
    assert child.returncode == 2, output
    assert expected in output and "Traceback" not in output
