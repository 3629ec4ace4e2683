"""Bad input on the learner's interfaces gets a clear refusal, never a crash or a record."""

from __future__ import annotations

import subprocess

import pytest

from tests.conftest import ROS2RUN
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context, "bad_input")
    yield c
    c.close()


def test_explorer_refuses_bad_demonstrations_and_goals(ros_processes, client):
    from action_msgs.msg import GoalStatus
    from rclpy.action import ActionClient

    from sgim_msgs.action import ReachGoal
    from sgim_msgs.msg import Demonstration
    from sgim_msgs.srv import RegisterDemonstration

    ros_processes.start("explorer", [ROS2RUN, "sgim_nodes", "low_level_explorer"])
    register = client.node.create_client(RegisterDemonstration, "/register_demonstration")
    assert register.wait_for_service(timeout_sec=30)

    def send(action, outcome):
        demo = Demonstration(action=action, outcome=outcome)
        # Refused demonstrations store nothing: asked again if a reply is lost.
        return client.ask(register, RegisterDemonstration.Request(demonstration=demo))

    short = send([0.1] * 5, [0.0, 0.0])
    assert not short.accepted and "24" in short.message
    nan = send([0.1] * 24, [float("nan"), 0.0])
    assert not nan.accepted and "NaN" in nan.message
    outside = send([1.5] + [0.0] * 23, [0.0, 0.0])
    assert not outside.accepted and "[-1, 1]" in outside.message

    reach = ActionClient(client.node, ReachGoal, "/reach_goal")
    assert reach.wait_for_server(timeout_sec=30)
    sent = reach.send_goal_async(ReachGoal.Goal(demonstrated=[1.5, 0.0], max_movements=5))
    assert client.spin_until(sent.done)
    result = sent.result().get_result_async()
    assert client.spin_until(result.done)
    assert result.result().status == GoalStatus.STATUS_ABORTED
    # Still alive and well: a good demonstration is taken.
    assert send([0.1] * 24, [0.2, -0.3]).accepted


def test_interest_computer_ignores_records_outside_the_space(ros_processes, client):
    from sgim_msgs.msg import Competence, RegionMap
    from sgim_ros import qos

    ros_processes.start("interest", [ROS2RUN, "sgim_nodes", "interest_computer"])
    maps = client.capture(RegionMap, "/region_map", qos.LATEST_STATE)
    publisher = client.node.create_publisher(Competence, "/competences", qos.RECORDS)
    assert client.spin_until(lambda: maps and publisher.get_subscription_count() > 0)
    for goal, value in (([2.0, 0.0], -0.5), ([0.1, 0.1], 0.5),  # competence must be <= 0
                        ([0.1], -0.5), ([0.1, 0.1, 0.1], -0.5), ([0.1, 0.1], float("nan")),
                        ([0.1, 0.1], -1e300), ([float("inf"), 0.1], -0.5)):
        publisher.publish(Competence(goal=goal, competence=value, movements_used=3))
    publisher.publish(Competence(goal=[0.1, 0.1], competence=-0.5, movements_used=3))
    assert client.spin_until(lambda: maps[-1].goal_count >= 1)
    client.spin_for(0.5)
    assert maps[-1].goal_count == 1  # only the good record was folded in


def test_a_parameter_file_of_the_wrong_type_is_refused_by_name(ros_processes, tmp_path):
    params = tmp_path / "bad.yaml"
    params.write_text("/**:\n  ros__parameters:\n    zeta: twenty\n")
    child = ros_processes.start(
        "interest-bad-file",
        [ROS2RUN, "sgim_nodes", "interest_computer", "--ros-args", "--params-file", str(params)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output, _ = child.communicate(timeout=60)
    assert child.returncode == 2 and "zeta" in output and "int" in output, output


def test_a_job_that_does_not_start_at_the_runs_count_is_refused(ros_processes, client):
    """A rogue client's imitate or reach_goal job would re-record movements the run already
    made; the job servers know the run's count from the movement stream and refuse it."""
    from action_msgs.msg import GoalStatus
    from rclpy.action import ActionClient

    from sgim_msgs.action import Imitate, ReachGoal
    from sgim_msgs.msg import Movement
    from sgim_ros import qos

    ros_processes.start("imitation", [ROS2RUN, "sgim_nodes", "imitation"])
    ros_processes.start("explorer", [ROS2RUN, "sgim_nodes", "low_level_explorer"])
    movements = client.node.create_publisher(Movement, "/movements", qos.RECORDS)
    assert client.spin_until(lambda: movements.get_subscription_count() >= 2)
    for k in range(1, 11):
        movements.publish(Movement(index=k, process=Movement.PROCESS_RANDOM,
                                   status=Movement.STATUS_OK, action=[0.1] * 24,
                                   outcome=[0.2, 0.3]))
    client.spin_for(1.0)

    def status_of(action_type, name, goal):
        action = ActionClient(client.node, action_type, name)
        assert action.wait_for_server(timeout_sec=30)
        sent = action.send_goal_async(goal)
        assert client.spin_until(sent.done)
        result = sent.result().get_result_async()
        assert client.spin_until(result.done)
        return result.result().status

    assert status_of(Imitate, "/imitate", Imitate.Goal(
        action=[0.1] * 24, outcome=[0.2, 0.3], repetitions=2, movements_before=3)) == \
        GoalStatus.STATUS_ABORTED
    assert status_of(ReachGoal, "/reach_goal", ReachGoal.Goal(
        max_movements=5, movements_before=3)) == GoalStatus.STATUS_ABORTED


def test_a_non_finite_demonstrated_outcome_is_refused_once_the_memory_has_a_tree(
        ros_processes, client):
    """Found by fuzzing (tests/fuzz/test_fuzz_live_nodes.py): the explorer measured a NaN
    outcome's distance to its memory before refusing it, and the memory's KD-tree (built once
    enough is stored) raised, which stopped the node."""
    from sgim_msgs.msg import Demonstration
    from sgim_msgs.srv import RegisterDemonstration

    explorer = ros_processes.start(
        "explorer", [ROS2RUN, "sgim_nodes", "low_level_explorer", "--ros-args",
                     "-p", "memory_min_tail:=1", "-p", "memory_max_tail:=1"])
    register = client.node.create_client(RegisterDemonstration, "/register_demonstration")
    assert register.wait_for_service(timeout_sec=30)

    def send(outcome):
        demo = Demonstration(action=[0.1] * 24, outcome=outcome)
        return client.call(register, RegisterDemonstration.Request(demonstration=demo))

    # The first reply right after discovery can be lost (GraphClient.try_call); a refused
    # demonstration, which stores nothing, may be asked again until one comes.
    short = Demonstration(action=[0.1] * 5, outcome=[0.0, 0.0])
    assert not client.ask(register, RegisterDemonstration.Request(demonstration=short)).accepted
    for k in range(3):  # the memory builds its tree
        assert send([0.1 * k, -0.2]).accepted
    for bad in ([float("nan"), 0.0], [float("inf"), 0.0], [0.0, -float("inf")]):
        refused = send(bad)
        assert not refused.accepted and "NaN or infinite" in refused.message
    assert send([0.3, 0.3]).accepted and explorer.poll() is None


@pytest.mark.parametrize(("node", "setting", "content", "message"), [
    ("imitation", "imitation_epsilon:=.inf", None, "'imitation_epsilon' = inf is invalid"),
    ("recorder", None, "/**:\n  ros__parameters:\n    teaching_set: /etc/passwd\n",
     "'teaching_set' = '/etc/passwd' is invalid: not a teaching set"),
    ("recorder", None, "/**:\n  ros__parameters:\n    chunk_messages: 9\n    chunk_messages: 1\n",
     "line 4: key 'chunk_messages' given twice (first at line 3)"),
    ("recorder", None, b"/**:\n  ros__parameters:\n    storage: \xff\xfe\n",
     "not UTF-8 text (byte 0xff at line 3)"),
])
def test_a_node_refuses_what_the_launcher_refuses_in_one_line(ros_processes, tmp_path, node,
                                                              setting, content, message):
    """The nodes share the launcher's checks (sgim_ros.params, sgim_ros.command_line): given
    the same value or file directly (`ros2 run`), a node stops at once with exit code 2 and
    the same line."""
    argv = [ROS2RUN, "sgim_nodes", node, "--ros-args"]
    if node == "recorder":
        argv += ["-p", f"output:={tmp_path / 'bag'}"]
    if setting:
        argv += ["-p", setting]
    if content is not None:
        path = tmp_path / "params.yaml"
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        argv += ["--params-file", str(path)]
    child = ros_processes.start(f"{node}-refuses", argv, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    try:
        output, _ = child.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{node} started with {setting or content!r} instead of refusing it")
    assert child.returncode == 2 and message in output, output
    assert "Traceback" not in output
