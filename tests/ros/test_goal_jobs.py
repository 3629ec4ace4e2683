"""The explorer's reach_goal jobs: one job goes from goal to goal, asking the goal generator for
each, up to its movement cap, its goal count or a cancel, and its result accounts for every
movement and every attempted goal it made (the arbiter's count and goals_folded rely on it)."""

from __future__ import annotations

import itertools

import pytest

from tests.conftest import ROS2RUN
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context, "goal_jobs")
    yield c
    c.close()


def test_a_job_spans_goals_up_to_its_cap_its_goal_count_or_a_cancel(ros_processes, client):
    from action_msgs.msg import GoalStatus
    from rclpy.action import ActionClient
    from rclpy.qos import QoSProfile

    from sgim_msgs.action import ReachGoal
    from sgim_msgs.msg import Competence, Goal, Movement
    from sgim_msgs.srv import ChooseGoal, RecorderReady
    from sgim_ros import qos

    moves = client.capture(Movement, "/movements", qos.RECORDS)
    competences = client.capture(Competence, "/competences", qos.RECORDS)
    goals = client.capture(Goal, "/goals", qos.RECORDS)
    # The simulator serves only once this test and the explorer hear its movements (a
    # listener that has matched a publisher is not yet known to it: discovery runs on each
    # side), as the launcher has it wait for the recorder.
    ros_processes.start("sim", [ROS2RUN, "sim_bridge", "sim_bridge", "--ros-args", "-p",
                                "wait_for_recorder:=true", "-p",
                                "movement_listeners:=goal_jobs,low_level_explorer"])
    ros_processes.start("explorer", [ROS2RUN, "sgim_nodes", "low_level_explorer"])
    # The explorer says it is ready only once it sees the goal generator it calls mid-job.
    ready = client.node.create_client(RecorderReady, "/explorer_ready")
    assert ready.wait_for_service(timeout_sec=60)
    alone = client.ask(ready, RecorderReady.Request())
    assert not alone.ready and "choose_goal" in alone.message
    ros_processes.start("goals", [ROS2RUN, "sgim_nodes", "goal_generator"])
    assert client.spin_until(lambda: client.ask(ready, RecorderReady.Request()).ready, 60)
    reach = ActionClient(client.node, ReachGoal, "/reach_goal")
    assert reach.wait_for_server(timeout_sec=60)
    # Likewise the goal generator, started last, must know this test's listener before the
    # jobs: goals are drawn until one is heard (probe goals, never attempted).
    chooser = client.node.create_client(ChooseGoal, "/choose_goal")
    assert chooser.wait_for_service(timeout_sec=60)
    for _ in range(100):
        answer = client.try_call(chooser, ChooseGoal.Request(), timeout=5.0)
        assert answer is None or answer.ok  # a probe's reply may be lost: probe again
        if client.spin_until(lambda: bool(goals), 0.5):
            break
    assert goals, "the goal generator's goals never reached the test"
    state = {"count": 0, "goals": 0}

    # The action's feedback read from its topic: rclpy's ActionClient drops a goal's
    # feedback that comes after its result, and the last one may (they travel apart).
    heard: list = client.capture(ReachGoal.Impl.FeedbackMessage, "/reach_goal/_action/feedback",
                                 QoSProfile(depth=10))

    def run_job(cancel_after: int | None = None, **fields):
        sent = reach.send_goal_async(ReachGoal.Goal(
            movements_before=state["count"], goals_before=state["goals"], **fields))
        assert client.spin_until(sent.done)
        handle = sent.result()
        assert handle.accepted
        job = bytes(handle.goal_id.uuid)

        def feedback_of_job() -> list[int]:
            return [f.feedback.movements_done for f in heard if bytes(f.goal_id.uuid) == job]
        if cancel_after is not None:
            assert client.spin_until(lambda: len(moves) >= state["count"] + cancel_after, 120)
            handle.cancel_goal_async()
        done = handle.get_result_async()
        assert client.spin_until(done.done, 120)
        response = done.result()
        result = response.result

        def all_in() -> bool:
            """The job's records and last feedback have come: they travel on topics of their
            own, and a sample lost on a loaded machine comes again only at the next
            heartbeat, after the result."""
            return (sum(m.index > state["count"] for m in moves) >= result.movements_used
                    and sum(c.movement_index > state["count"] for c in competences)
                    >= result.goals_attempted
                    and bool(feedback_of_job())
                    and feedback_of_job()[-1] >= result.movements_used)

        client.spin_until(all_in, 30)
        client.spin_for(0.2)  # and nothing more (a record too many would show below)
        feedback = feedback_of_job()
        made = [m for m in moves if m.index > state["count"]]
        attempted = [c for c in competences if c.movement_index > state["count"]]
        # The result accounts for every movement, in order, and every attempted goal.
        assert [m.index for m in made] == list(range(state["count"] + 1,
                                                     state["count"] + 1 + result.movements_used))
        assert result.goals_attempted == len(attempted) == len({m.goal_index for m in made})
        assert sum(c.movements_used for c in attempted) == result.movements_used
        # Each goal waited for the competences of every goal before it (the tree's count),
        # and its movements follow it; the last one is the result's.
        for c in attempted:
            goal = next(g for g in goals if g.index == c.goal_index)
            assert goal.movement_index == c.movement_index - c.movements_used
        last = attempted[-1]
        if result.goal_movements == 0:  # a cancel came between a goal's choice and its first
            assert result.cancelled and result.goal_index > last.goal_index  # movement
        else:
            assert (result.goal_index, result.goal_movements) == (last.goal_index,
                                                                  last.movements_used)
            assert list(result.goal) == pytest.approx(list(last.goal))
            assert result.competence == pytest.approx(last.competence)
        # Feedback after each goal: the job's movements so far (the arbiter's progress), at
        # goal ends only, up to the job's whole count.
        ends = set(itertools.accumulate(c.movements_used for c in attempted))
        assert feedback and feedback == sorted(feedback) and set(feedback) <= ends
        assert feedback[-1] == result.movements_used
        state["count"] += result.movements_used
        state["goals"] += result.goals_attempted
        return response.status, result

    # The cap cuts the goal under way; the job went through several goals to get there.
    status, result = run_job(max_movements=25)
    assert status == GoalStatus.STATUS_SUCCEEDED and not result.cancelled
    assert result.movements_used == 25 and result.goals_attempted >= 2
    # A goal count ends the job after that many goals, each ended by itself.
    status, result = run_job(max_movements=200, max_goals=2)
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.goals_attempted == 2 and result.finished and result.movements_used < 200
    # A cancel is honoured at the next movement boundary: the movement under way completes,
    # and the job stops there, whichever goal it was on.
    status, result = run_job(cancel_after=12, max_movements=1000)
    assert status == GoalStatus.STATUS_CANCELED and result.cancelled
    assert 12 <= result.movements_used <= 14 and result.goals_attempted >= 2
    # A job that does not start at the run's count, or has no cap, is refused.
    for bad in (ReachGoal.Goal(max_movements=5, movements_before=state["count"] - 1),
                ReachGoal.Goal(max_movements=0, movements_before=state["count"])):
        sent = reach.send_goal_async(bad)
        assert client.spin_until(sent.done)
        done = sent.result().get_result_async()
        assert client.spin_until(done.done)
        assert done.result().status == GoalStatus.STATUS_ABORTED
    client.spin_for(0.5)
    assert moves[-1].index == state["count"]
