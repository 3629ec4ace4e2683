"""Every sgim_msgs type survives a bag round trip without rclpy; the bag embeds definitions."""

from __future__ import annotations

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import StoragePlugin, Writer

from sgim_nodes.bag.types import SOURCE_MSG_DIR, sgim_types, typestore
from tests.bag import samples


def _one_of_each() -> dict[str, object]:
    rng = np.random.default_rng(1)
    return {
        "sgim_msgs/msg/Movement": samples.movement(3, rng, process=2),
        "sgim_msgs/msg/Goal": samples.goal(2, 9, rng),
        "sgim_msgs/msg/Competence": samples.competence(2, 10, rng, True),
        "sgim_msgs/msg/Region": samples.region(1, 0, [-1, 0], [0, 1], True),
        "sgim_msgs/msg/RegionMap": samples.region_map(15, split=True),
        "sgim_msgs/msg/Demonstration": samples.demonstration(1, 4, rng),
        "sgim_msgs/msg/HelpRequest": samples.help_request(2, 150, rng, "west", "goal-only"),
        "sgim_msgs/msg/TeacherCheck": samples.teacher_checks(150, 2, [0.1, -0.2], 3, rng)[3],
        "sgim_msgs/msg/Evaluation": samples.evaluation(20, rng),
        "sgim_msgs/msg/RunStatus": samples.run_status(5, 10, 2, "stopped by a test"),
        "sgim_msgs/msg/PaceState": samples.pace_state(150, True, True, "teacher's turn"),
    }


def _equal(a, b) -> bool:
    """Field-by-field equality of rosbags messages, NaN equal to NaN."""
    if hasattr(a, "__dataclass_fields__"):
        return all(_equal(getattr(a, f), getattr(b, f)) for f in a.__dataclass_fields__)
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b, equal_nan=True)
    if isinstance(a, list):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def test_every_message_file_is_registered():
    names = {f"sgim_msgs/msg/{p.stem}" for p in SOURCE_MSG_DIR.glob("*.msg")}
    assert names == set(sgim_types(SOURCE_MSG_DIR)) & names
    assert names <= set(typestore().types)
    assert names == set(_one_of_each())  # the round trip below covers every type


@pytest.mark.parametrize("storage", [StoragePlugin.MCAP, StoragePlugin.SQLITE3])
def test_round_trip_of_every_type_through_a_bag(tmp_path, storage):
    ts = typestore()
    messages = _one_of_each()
    with Writer(tmp_path / "bag", version=9, storage_plugin=storage) as writer:
        for k, (msgtype, msg) in enumerate(messages.items()):
            conn = writer.add_connection(f"/t{k}", msgtype, typestore=ts)
            writer.write(conn, 100 + k, ts.serialize_cdr(msg, msgtype))
    # AnyReader with no typestore: everything comes from the definitions in the bag.
    with AnyReader([tmp_path / "bag"]) as reader:
        got = {c.msgtype: reader.deserialize(raw, c.msgtype)
               for c, _, raw in reader.messages()}
    assert set(got) == set(messages)
    for msgtype, msg in messages.items():
        assert _equal(got[msgtype], msg), msgtype
    assert got["sgim_msgs/msg/RegionMap"].regions[2].lower.tolist() == [0.0, -1.0]


def test_hashes_match_the_rosidl_ones_when_the_workspace_is_built():
    import json

    from sgim_nodes.bag.types import msg_dir

    directory = msg_dir()
    if directory == SOURCE_MSG_DIR:
        pytest.skip("workspace not built: no rosidl .json files to compare with")
    for path in directory.glob("*.json"):
        info = json.loads(path.read_text())
        expected = info["type_hashes"][0]["hash_string"]
        assert typestore().hash_rihs01(f"sgim_msgs/msg/{path.stem}") == expected, path.stem
