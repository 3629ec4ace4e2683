"""Replaying a bag at a high rate delivers every message, on the right topics, in order."""

from __future__ import annotations

import subprocess
import time

import numpy as np
import pytest

from tests.bag import ros_helpers as h
from tests.bag import samples
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context, "replay_test_client")
    yield c
    c.close()


def _replay(bag, *args) -> list[str]:
    return [*h.node_command("replay", "sgim_nodes.bag.replay"), str(bag), *args]


def test_replay_at_a_high_rate_delivers_everything(ros_processes, client, tmp_path):
    from sgim_nodes.bag.types import TOPICS
    from sgim_ros.interfaces import ros_message_class, topic_qos

    messages = samples.synthetic_run(120, seed=3)
    bag = samples.write_bag(tmp_path / "run", messages, chunk_messages=50)
    received = {name: client.capture(ros_message_class(t), f"/{name}",
                                     topic_qos(name, keep_all=True))
                for name, t in TOPICS.items()}
    start = time.monotonic()
    child = ros_processes.start("replay", _replay(bag, "--rate", "20", "--wait-subscribers", "30",
                                                  "--quiet"))
    expected = {}
    for topic, msg in messages:
        expected.setdefault(topic, []).append(msg)
    assert client.spin_until(
        lambda: all(len(received[t]) == len(v) for t, v in expected.items()), 60), {
        t: len(v) for t, v in received.items()}
    client.spin_until(lambda: child.poll() is not None, 30)
    assert child.returncode == 0
    assert time.monotonic() - start < 45
    got = [m.index for m in received["movements"]]
    assert got == list(range(1, 121))
    for a, b in zip(received["movements"], expected["movements"], strict=True):
        assert np.array_equal(np.asarray(a.action), b.action)
    assert [len(m.regions) for m in received["region_map"]] == [
        len(m.regions) for m in expected["region_map"]]
    assert received["run_status"][-1].message == "done"


def test_replay_refuses_bad_input_with_a_clear_message(ros_processes, tmp_path):
    (tmp_path / "junk.mcap").write_bytes(b"junk")
    bag = samples.write_bag(tmp_path / "run", samples.synthetic_run(10))
    for args, code, expected in (
        ([str(tmp_path / "junk.mcap")], 2, "junk.mcap"),
        ([str(tmp_path / "nowhere")], 2, "does not exist"),
        ([str(bag), "--rate", "0"], 2, "--rate must be > 0"),
        ([str(bag), "--topics", "nothing_here"], 1, "nothing to play"),
    ):
        child = ros_processes.start("replay_bad", [*_replay(args[0]), *args[1:]],
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        out, _ = child.communicate(timeout=60)
        assert child.returncode == code, out
        assert expected in out


def test_the_recorded_gaps_are_kept_divided_by_the_rate():
    from sgim_nodes.bag.reader import RawRecord
    from sgim_nodes.bag.replay import offsets

    records = [RawRecord("/movements", "sgim_msgs/msg/Movement", t, b"")
               for t in (5_000_000_000, 5_500_000_000, 7_000_000_000)]
    assert offsets(records, 2.0) == pytest.approx([0.0, 0.25, 1.0])
    assert offsets(records, 0.5) == pytest.approx([0.0, 1.0, 4.0])
    assert offsets([], 3.0) == []


def test_replay_waits_for_a_subscriber_that_comes_late_and_loses_nothing(
        ros_processes, client, tmp_path):
    from sgim_msgs.msg import Movement
    from sgim_ros import qos

    bag = samples.write_bag(tmp_path / "run", samples.synthetic_run(400, seed=5))
    child = ros_processes.start("replay_late", _replay(bag, "--rate", "50", "--topics",
                                                       "movements", "--quiet"),
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    client.spin_for(3.0)  # the subscriber starts 3 s after the replay
    assert child.poll() is None, "replay did not wait for its subscriber"
    received = client.capture(Movement, "/movements", qos.RECORDS)
    assert client.spin_until(lambda: len(received) == 400, 90), len(received)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 0, out
    assert [m.index for m in received] == list(range(1, 401))


def test_replay_refuses_to_play_to_nobody_unless_told(ros_processes, tmp_path):
    bag = samples.write_bag(tmp_path / "run", samples.synthetic_run(10))
    child = ros_processes.start("replay_nobody", _replay(bag, "--wait-subscribers", "1.5"),
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 3, out
    assert "too few subscribers on" in out and "/movements (0/1)" in out, out
    assert "--play-anyway" in out
    child = ros_processes.start("replay_anyway", _replay(
        bag, "--wait-subscribers", "0.5", "--play-anyway", "--quiet"),
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 0 and "playing anyway" in out, out


def test_replay_leaves_quarantined_records_out_unless_asked(tmp_path):
    from sgim_nodes.bag.replay import load

    rng = np.random.default_rng(0)
    messages = samples.synthetic_run(30)
    messages.insert(20, ("movements", samples.movement(2_000_000, rng)))
    bag = samples.write_bag(tmp_path / "run", messages)
    movements = [r for r in load(bag, ["movements"]) if r.topic == "/movements"]
    assert len(movements) == 30
    assert len(load(bag, ["movements"], include_quarantined=True)) == 31


def test_a_bag_of_an_older_version_replays_as_today_s_messages(ros_processes, client, tmp_path):
    """Movement before `attempt`, Demonstration before `content` and `help_request`, Region
    before `least_competent_goal`: the subscribers get well-formed messages of today's types,
    the recorded values, the new fields at their defaults."""
    from sgim_ros.interfaces import ros_message_class, topic_qos
    from tests.bag import old_bags

    store = old_bags.store_with(old_bags.OLDER)
    messages = old_bags.old_run(store)
    bag = old_bags.write_old_bag(tmp_path / "old", store, messages)
    topics = ("movements", "demonstrations", "demonstrations_taken", "region_map", "run_status")
    received = {name: client.capture(ros_message_class(old_bags.TOPICS[name]), f"/{name}",
                                     topic_qos(name, keep_all=True)) for name in topics}
    child = ros_processes.start("replay_old", _replay(bag, "--rate", "50", "--quiet"),
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    expected = {name: [m for t, m in messages if t == name] for name in topics}
    assert client.spin_until(
        lambda: all(len(received[t]) == len(expected[t]) for t in topics), 60), {
        t: len(v) for t, v in received.items()}
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 0, out
    for got, sent in zip(received["movements"], expected["movements"], strict=True):
        assert (got.index, got.process, got.status, got.goal_index, got.stamp.sec) == (
            sent.index, sent.process, sent.status, sent.goal_index, sent.stamp.sec)
        assert np.array_equal(np.asarray(got.action), sent.action)
        assert np.array_equal(np.asarray(got.outcome), sent.outcome)
        assert got.attempt == 0
    for name in ("demonstrations", "demonstrations_taken"):
        (got,), (sent,) = received[name], expected[name]
        assert (got.index, got.movement_index, got.teaching_set_index, got.source) == (
            sent.index, sent.movement_index, sent.teaching_set_index, sent.source)
        assert np.array_equal(np.asarray(got.action), sent.action)
        assert np.array_equal(np.asarray(got.outcome), sent.outcome)
        assert (got.content, got.help_request) == ("means-and-goal", 0)
    (region,) = received["region_map"][0].regions
    assert (region.interest, region.goal_count, list(region.upper)) == (0.25, 2, [1.0, 1.0])
    assert len(region.least_competent_goal) == 0
    assert received["run_status"][0].message == "done"


def test_the_fields_an_old_record_lacks_get_the_defaults_of_today_s_messages():
    """The upgrader's defaults (the readers' records, else zero) are those of the .msg files,
    for every recorded type: what an old record is given is what a fresh message holds."""
    from rclpy.serialization import deserialize_message

    from sgim_nodes.bag.schema import Upgrader
    from sgim_nodes.bag.types import RECORDED_TOPICS, typestore
    from sgim_ros.interfaces import ros_message_class

    upgrader, store = Upgrader(), typestore()
    for msgtype in set(RECORDED_TOPICS.values()):
        data = bytes(store.serialize_cdr(upgrader.default_message(msgtype), msgtype))
        cls = ros_message_class(msgtype)
        assert deserialize_message(data, cls) == cls(), msgtype
