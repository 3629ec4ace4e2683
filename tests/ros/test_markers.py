"""The markers node in a real run: its topics, live and in the bag, show the run's picture."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
MOVEMENTS = 200


def test_marker_topics_show_the_run_live_and_in_the_bag(ros_processes, ros_domain, tmp_path,
                                                      rclpy_context):
    from visualization_msgs.msg import Marker, MarkerArray

    from sgim_msgs.msg import Movement
    from sgim_nodes.bag.reader import load_run, read_messages
    from sgim_nodes.core.teaching import DEFAULT_TOLERANCE_NOISE, Teacher
    from sgim_nodes.view.picture import PROCESS_COLOURS, interest_colour
    from sgim_ros import qos
    from sim_bridge.data_files import load_teaching_set
    from sim_bridge.scaling import OUTCOME_NOISE
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "marker_viewer")
    seen: dict[str, list[MarkerArray]] = {}
    for name, profile in [("landings", qos.RECORDS), ("regions", qos.LATEST_STATE),
                          ("teaching_goals", qos.LATEST_STATE),
                          ("current_goal", qos.LATEST_STATE)]:
        seen[name] = client.capture(MarkerArray, f"/markers/{name}", profile)
    movements = client.capture(Movement, "/movements", qos.RECORDS)
    child = ros_processes.start("markers-run", [
        RUN, "sgim-d", "--seed", "3", "--movements", str(MOVEMENTS), "--eval-every", "100",
        "--demonstration-period", "100", "--runs-dir", str(tmp_path), "--name", "run", "--domain",
        str(ros_domain), "--quiet", "--timeout", "300"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert client.spin_until(lambda: child.poll() is not None, timeout=330), "run too long"
    output = child.stdout.read()
    assert child.returncode == 0, output[-3000:]
    client.spin_for(1.0)
    client.close()

    # Live: the landings, summed over the last full refresh and the batches after it, are
    # every landed movement, each coloured by its process.
    landed = [m for m in movements if m.status == Movement.STATUS_OK]
    assert len(movements) == MOVEMENTS and len(landed) > 50
    points, colours = _landings(seen["landings"])
    assert len(points) == len(landed)
    by_place = {(round(m.outcome[0], 9), round(m.outcome[1], 9)): m.process for m in landed}
    for (x, y), colour in zip(points, colours, strict=True):
        process = by_place[(round(x, 9), round(y, 9))]
        expected = np.array(PROCESS_COLOURS[process]) / 255.0
        assert np.allclose([colour.r, colour.g, colour.b], expected)
    assert {m.header.frame_id for a in seen["landings"] for m in a.markers} == {"outcome_space"}

    # The teaching goals are judged by the automatic teacher's rule on the learner's landings.
    teaching = load_teaching_set()
    rule = Teacher(teaching.actions, teaching.outcomes, np.random.default_rng(0),
                   tolerance=DEFAULT_TOLERANCE_NOISE * OUTCOME_NOISE)  # the teacher node's
    unreached = set(rule.unreached(np.array([m.outcome for m in landed])).tolist())
    spheres = [m for m in seen["teaching_goals"][-1].markers if m.type == Marker.SPHERE_LIST]
    (goals,) = spheres
    assert len(goals.points) == len(teaching.outcomes)
    red = {i for i, c in enumerate(goals.colors) if c.r > 0.8 and c.g < 0.3}
    assert red == unreached and 0 < len(red) < len(teaching.outcomes)

    # Regions: one filled quad (two triangles) per leaf of the latest region map.
    run = load_run(tmp_path / "run" / "bag")
    leaves = run.region_map[-1].leaves
    fills = [m for m in seen["regions"][-1].markers if m.type == Marker.TRIANGLE_LIST]
    assert len(fills[0].points) == 6 * len(leaves) >= 6
    # ... each coloured by its interest over the highest leaf interest (the page's palette).
    top = max(r.interest for r in leaves)
    interests = {tuple(np.round([*r.lower, *r.upper], 9)): r.interest for r in leaves}
    fill = fills[0]
    for k in range(0, len(fill.points), 6):
        low, high = fill.points[k], fill.points[k + 2]
        interest = interests[tuple(np.round([low.x, low.y, high.x, high.y], 9))]
        expected = np.array(interest_colour(interest / top if top > 0 else 0.0)) / 255.0
        c = fill.colors[k]
        assert np.allclose([c.r, c.g, c.b], expected)
    assert len({(c.r, c.g, c.b) for c in fill.colors}) > 1  # interest differs between leaves
    goal = seen["current_goal"][-1].markers[-1]
    assert goal.type == Marker.SPHERE and -1 <= goal.pose.position.x <= 1

    # Recorded: a replay shows the same markers (the last landings refresh is in the bag).
    recorded = {}
    for topic, _, msg in read_messages(tmp_path / "run" / "bag"):
        if topic.startswith("/markers/"):
            recorded.setdefault(topic, []).append(msg)
    assert set(recorded) == {"/markers/landings", "/markers/regions",
                             "/markers/teaching_goals", "/markers/current_goal"}
    bag_points, _ = _landings(recorded["/markers/landings"])
    assert len(bag_points) == len(landed)


def _landings(arrays) -> tuple[list[tuple[float, float]], list]:
    """The landings a viewer shows after these arrays: from the last DELETEALL on."""
    points, colours = [], []
    for array in arrays:
        for m in array.markers:
            if m.action == 3:  # DELETEALL (same value in rclpy's and rosbags' classes)
                points, colours = [], []
            elif m.ns == "landings":
                points += [(p.x, p.y) for p in m.points]
                colours += list(m.colors)
    return points, colours
