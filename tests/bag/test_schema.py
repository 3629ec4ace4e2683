"""Records of a bag recorded before its types gained fields become today's messages: the
recorded values, the new fields at the defaults the readers give them; a field removed or
retyped since is refused, naming the topic and the field."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from sgim_nodes.bag.reader import load_run, read_raw
from sgim_nodes.bag.records import DemonstrationRecord, MovementRecord
from sgim_nodes.bag.schema import SchemaError, Upgrader
from sgim_nodes.bag.types import typestore
from tests.bag import old_bags, samples


@pytest.fixture
def old_bag(tmp_path):
    store = old_bags.store_with(old_bags.OLDER)
    messages = old_bags.old_run(store)
    return old_bags.write_old_bag(tmp_path / "old", store, messages), messages


def test_an_old_schema_record_is_re_encoded_as_today_s_type(old_bag):
    bag, messages = old_bag
    upgrader, current = Upgrader(), typestore()
    records = list(read_raw(bag))
    assert len(records) == len(messages)
    for record, (topic, recorded) in zip(records, messages, strict=True):
        changed = topic in ("movements", "demonstrations", "demonstrations_taken", "region_map")
        assert upgrader.is_current(record) is not changed, topic
        upgraded = upgrader.upgrade(record)
        assert (upgraded.data != record.data) is changed, topic
        message = current.deserialize_cdr(upgraded.data, record.msgtype)  # today's layout
        assert bytes(current.serialize_cdr(upgrader.decode(record), record.msgtype)) == (
            upgraded.data)
        for name in recorded.__dataclass_fields__:
            if name in ("action", "outcome", "goal", "lower", "upper"):
                assert np.array_equal(getattr(message, name), getattr(recorded, name))
            elif name != "regions":
                assert getattr(message, name) == getattr(recorded, name), (topic, name)
        if topic == "movements":
            assert message.attempt == MovementRecord.attempt == 0
        if topic.startswith("demonstrations"):
            assert message.content == DemonstrationRecord.content == "means-and-goal"
            assert message.help_request == DemonstrationRecord.help_request == 0
        if topic == "region_map":  # a nested type that gained a field
            (region,) = message.regions
            assert region.interest == 0.25 and np.array_equal(region.upper, [1.0, 1.0])
            assert len(region.least_competent_goal) == 0


def test_replay_and_the_readers_agree_on_an_old_bag(old_bag):
    from sgim_nodes.bag.replay import load

    bag, _ = old_bag
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing quarantined, nothing skipped
        run = load_run(bag)
    played = load(bag, None)
    assert len(played) == len(list(read_raw(bag)))
    current = typestore()
    movements = [current.deserialize_cdr(r.data, r.msgtype) for r in played
                 if r.topic == "/movements"]
    assert [m.index for m in movements] == [m.index for m in run.movements]
    for message, record in zip(movements, run.movements, strict=True):
        assert message.attempt == record.attempt
        assert np.array_equal(message.action, record.action)
    (taken,) = [current.deserialize_cdr(r.data, r.msgtype) for r in played
                if r.topic == "/demonstrations_taken"]
    (record,) = run.demonstrations_taken
    assert (taken.content, taken.help_request, taken.source) == (
        record.content, record.help_request, record.source)
    (region,) = run.region_map[0].regions  # read although Region had fewer fields then
    assert region.interest == 0.25 and len(region.least_competent_goal) == 0


def test_records_of_today_s_schema_keep_their_bytes(tmp_path):
    bag = samples.write_bag(tmp_path / "new", samples.synthetic_run(20))
    upgrader = Upgrader()
    for record in read_raw(bag):
        assert upgrader.is_current(record)
        assert upgrader.upgrade(record) is record


@pytest.mark.parametrize(("topic", "definitions", "field"), [
    ("/demonstrations", {"sgim_msgs/msg/Demonstration": old_bags.DEMONSTRATION_BEFORE_CONTENT
                         .replace("string source", "string giver")}, "'giver' (string)"),
    ("/movements", {"sgim_msgs/msg/Movement": old_bags.MOVEMENT_BEFORE_ATTEMPT
                    .replace("uint64 goal_index", "float64 goal_index")},
     "'goal_index' was float64, is now uint64"),
    ("/region_map", {"sgim_msgs/msg/Region": old_bags.REGION_BEFORE_LEAST_COMPETENT_GOAL
                     .replace("uint32 goal_count", "int32 goal_count")},
     "'regions[].goal_count' was int32, is now uint32"),
])
def test_a_field_removed_or_retyped_since_is_refused_naming_topic_and_field(
        tmp_path, capsys, topic, definitions, field):
    from sgim_nodes.bag.replay import main

    store = old_bags.store_with(definitions)
    messages = [(t, m) for t, m in old_bags.old_run(store) if f"/{t}" == topic]
    bag = old_bags.write_old_bag(tmp_path / "bad", store, messages)
    with pytest.raises(SchemaError) as error:
        for record in read_raw(bag):
            Upgrader().upgrade(record)
    assert topic in str(error.value) and field in str(error.value), str(error.value)
    assert main([str(bag), "--quiet"]) == 2
    out = capsys.readouterr().err
    assert topic in out and field in out and "cannot be replayed" in out, out


def test_a_type_that_no_longer_exists_is_refused_naming_topic_and_type(tmp_path, capsys):
    from sgim_nodes.bag.replay import main

    store = old_bags.store_with({"sgim_msgs/msg/Cast": "uint64 index\nfloat64[] hook"})
    cast = store.types["sgim_msgs/msg/Cast"](index=1, hook=np.zeros(2))
    bag = old_bags.write_old_bag(tmp_path / "gone", store, [("casts", cast)],
                                 {"casts": "sgim_msgs/msg/Cast"})
    assert main([str(bag), "--quiet"]) == 2
    out = capsys.readouterr().err
    assert "/casts" in out and "sgim_msgs/msg/Cast no longer exists" in out, out


def test_a_damaged_recorded_definition_is_refused_naming_topic_and_type(tmp_path):
    from dataclasses import replace

    bag = samples.write_bag(tmp_path / "new", samples.synthetic_run(5))
    record = next(r for r in read_raw(bag) if r.topic == "/movements")
    with pytest.raises(SchemaError, match="/movements: the recorded definition of "
                                          "sgim_msgs/msg/Movement is unreadable"):
        Upgrader().upgrade(replace(record, msgdef="uint64 index\nfloat64[ broken"))
