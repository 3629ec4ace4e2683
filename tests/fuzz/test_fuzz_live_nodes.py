"""Fuzz two live nodes through rclpy: the simulator's execute_action and the explorer's
register_demonstration, the services every learner's movement and every demonstration pass.

Requests are drawn within what the wire can carry (field types are enforced by rclpy on the
client side) and are otherwise anything: sizes off by one or far off, NaN, infinities, values
outside [-1, 1], any index, any text. Each request is answered, with a refusal that says why
for a bad one, and both nodes are still alive at the end and serve a good request.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from sim_bridge.noise_cursor import MAX_SKIP
from tests.conftest import ROS2RUN
from tests.fuzz.tally import fuzz, tally
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros

UINT64 = st.integers(0, 2**64 - 1)
special = st.sampled_from([math.nan, math.inf, -math.inf, 1.0, -1.0, 1.0000001, 0.0, 1e308])


def vectors(size: int) -> st.SearchStrategy:
    """Mostly a vector of the right size in [-1, 1]; else another size or bad numbers."""
    good = st.lists(st.floats(-1, 1), min_size=size, max_size=size)
    sizes = st.sampled_from([0, 1, size - 1, size + 1, 200])
    bad_size = sizes.flatmap(lambda n: st.lists(st.floats(-1, 1), min_size=n, max_size=n))
    bad_value = st.tuples(good, st.integers(0, size - 1), special).map(
        lambda t: [*t[0][:t[1]], t[2], *t[0][t[1] + 1:]])
    return st.one_of(good, good, bad_size, bad_value, st.lists(st.floats(), max_size=30))


def _finite_in_box(values, size: int) -> bool:
    return len(values) == size and all(math.isfinite(x) and -1 <= x <= 1 for x in values)


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context, "fuzz_client")
    yield c
    c.close()


@pytest.fixture
def nodes(ros_processes):
    return {"sim_bridge": ros_processes.start(
                "sim_bridge", [ROS2RUN, "sim_bridge", "sim_bridge", "--ros-args", "-p",
                               "seed:=7"]),
            "explorer": ros_processes.start(
                "explorer", [ROS2RUN, "sgim_nodes", "low_level_explorer"])}


@pytest.fixture
def services(nodes, client):
    from sgim_msgs.srv import ExecuteAction, RegisterDemonstration

    execute = client.node.create_client(ExecuteAction, "/execute_action")
    register = client.node.create_client(RegisterDemonstration, "/register_demonstration")
    assert execute.wait_for_service(timeout_sec=60), "sim_bridge did not come up"
    assert register.wait_for_service(timeout_sec=60), "the explorer did not come up"
    return execute, register


requests = st.one_of(
    st.fixed_dictionaries({
        "service": st.just("execute_action"), "action": vectors(24),
        "process": st.integers(0, 255), "movement_index": UINT64, "goal": vectors(2),
        "goal_index": UINT64, "record": st.booleans(), "attempt": st.integers(0, 255)}),
    st.fixed_dictionaries({
        "service": st.just("register_demonstration"), "index": st.integers(0, 2**32 - 1),
        "movement_index": UINT64, "action": vectors(24), "outcome": vectors(2),
        "teaching_set_index": st.integers(-(2**31), 2**31 - 1),
        "source": st.one_of(st.sampled_from(["automatic", "human", "web"]), st.text(max_size=8)),
        "content": st.one_of(st.sampled_from(["means-and-goal", "goal-only", "means-only"]),
                             st.text(max_size=8)),
        "help_request": st.integers(0, 2**32 - 1)}),
)


# Found by this fuzzer: a recorded movement 40 million casts ahead held the simulator half a
# minute per request while it drew the skipped casts' noise.
FAR_AHEAD = {"service": "execute_action", "action": [0.5] * 24, "process": 0,
             "movement_index": 40_427_983, "goal": [0.0, 0.0], "goal_index": 0, "record": True,
             "attempt": 0}


@fuzz(150)
@given(request=requests)
@example(request=FAR_AHEAD)
@example(request={**FAR_AHEAD, "movement_index": 2**64 - 1})
def test_two_live_nodes_answer_every_request_and_stay_alive(nodes, client, services, request):
    from sgim_msgs.msg import Demonstration, Movement
    from sgim_msgs.srv import ExecuteAction, RegisterDemonstration

    execute, register = services
    request = dict(request)  # the examples above are shared between calls
    kind = request.pop("service")
    if kind == "execute_action":
        response = client.call(execute, ExecuteAction.Request(**request), timeout=30)
        good = _finite_in_box(request["action"], 24)
        if response.status == Movement.STATUS_INVALID_ACTION and "ahead" in response.message:
            # A recorded movement beyond the noise stream's reach (sim_bridge/noise_cursor.py)
            assert request["record"] and request["movement_index"] > MAX_SKIP, response.message
            tally("live sim_bridge execute_action", "refused (movement too far ahead)")
        elif response.status == Movement.STATUS_INVALID_ACTION:
            assert response.message and not good, (request, response.message)
            tally("live sim_bridge execute_action", "refused (invalid action)")
        else:
            assert good and response.status in (Movement.STATUS_OK, Movement.STATUS_NO_CONTACT,
                                                 Movement.STATUS_PHYSICS_FAILURE)
            assert response.status != Movement.STATUS_OK or _finite_in_box(response.outcome, 2)
            tally("live sim_bridge execute_action", "executed")
    else:
        demo = Demonstration(**request)
        response = client.call(register, RegisterDemonstration.Request(demonstration=demo),
                               timeout=30)
        if response.accepted:
            assert _finite_in_box(request["action"], 24) and _finite_in_box(request["outcome"], 2)
            tally("live explorer register_demonstration", "accepted")
        else:
            assert response.message and "\n" not in response.message
            tally("live explorer register_demonstration", "refused")
    for name, process in nodes.items():
        assert process.poll() is None, f"{name} died (exit code {process.returncode})"
