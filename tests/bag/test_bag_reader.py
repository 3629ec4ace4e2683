"""A bag is one storage file, read back in order by us, rosbags and the mcap library; what a
kill or a damaged disk leaves is read as far as it goes, with a warning, never a crash."""

from __future__ import annotations

import json
import shutil
import struct
import warnings

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from sgim_nodes.bag.reader import (
    BagReadWarning,
    NotABagError,
    load_run,
    read_messages,
    read_raw,
    storage_files,
)
from sgim_nodes.bag.repair import TRUNCATED_SUFFIX, repair
from sgim_nodes.bag.types import TOPICS
from sgim_nodes.bag.writer import BagWriteError, BagWriter
from tests.bag import samples


@pytest.fixture(scope="module")
def run_messages():
    return samples.synthetic_run(60)


@pytest.fixture
def bag(tmp_path, run_messages):
    return samples.write_bag(tmp_path / "run", run_messages, chunk_messages=20)


def _killed_copy(tmp_path, run_messages, chunk_messages=20, stop_after=None):
    """What a SIGKILL leaves: the file as it stood, without summary nor metadata.yaml."""
    writer = BagWriter(tmp_path / "live", chunk_messages=chunk_messages)
    for topic, msgtype in TOPICS.items():
        writer.add_topic(f"/{topic}", msgtype)
    for k, (topic, msg) in enumerate(run_messages[:stop_after]):
        writer.write(f"/{topic}", 1_000_000 + k, samples.TS.serialize_cdr(msg, msg.__msgtype__))
    killed = tmp_path / "killed"
    killed.mkdir()
    shutil.copy(writer.file, killed / "killed.mcap")
    durable = writer.messages_durable
    writer.close()
    return killed, durable


def _chunk_offsets(file) -> list[int]:
    data = file.read_bytes()
    at, offsets = 8, []
    while at + 9 <= len(data):
        op, length = data[at], struct.unpack_from("<Q", data, at + 1)[0]
        if op == 0x06:
            offsets.append(at)
        if op == 0x0F:
            break
        at += 9 + length
    return offsets


def test_a_bag_is_one_storage_file_that_every_reader_reads(bag, run_messages):
    assert [f.name for f in storage_files(bag)] == ["run.mcap"]
    assert sorted(p.name for p in bag.iterdir()) == ["metadata.yaml", "run.mcap"]
    got = list(read_messages(bag))
    assert [t for t, _, _ in got] == [f"/{t}" for t, _ in run_messages]
    assert [m.index for t, _, m in got if t == "/movements"] == list(range(1, 61))
    with AnyReader([bag]) as reader:  # rosbags, no ROS install
        assert reader.message_count == len(run_messages)
    with (bag / "run.mcap").open("rb") as stream:  # the MCAP library, as Foxglove reads it
        mcap = make_reader(stream, validate_crcs=True)
        summary = mcap.get_summary()
        assert summary.statistics.message_count == len(run_messages)
        assert summary.statistics.chunk_count == -(-len(run_messages) // 20)
        assert sum(1 for _ in mcap.iter_messages()) == len(run_messages)
        embedded = [m.metadata["serialized_metadata"] for m in mcap.iter_metadata()]
    # the file's own metadata names the file as it is in the bag
    assert len(embedded) == 1 and "- run.mcap" in embedded[0] and ".part_" not in embedded[0]


def test_load_run_converts_every_topic(bag, run_messages):
    run = load_run(bag)
    expected = {}
    for topic, _ in run_messages:
        expected[topic] = expected.get(topic, 0) + 1
    assert run.counts() == expected
    m = run.movements[6]  # index 7: a failed cast has no outcome
    assert m.index == 7 and m.status == 1 and m.outcome.shape == (0,)
    assert run.movements[0].action.shape == (24,)
    e = run.evaluations[0]
    assert e.goals.shape == (3, 2) and np.isnan(e.reached[1]).all()
    assert run.region_map[-1].leaves[0].upper.tolist() == [0.0, 1.0]
    assert run.run_status[-1].state == 1 and run.run_status[-1].message == "done"
    assert run.demonstrations[0].source == "automatic"


def test_what_a_kill_leaves_is_read_to_its_last_chunk_and_repaired(tmp_path, run_messages):
    killed, durable = _killed_copy(tmp_path, run_messages, stop_after=55)
    assert 0 < durable < 55
    with pytest.warns(BagReadWarning, match="was not closed"):
        records = list(read_raw(killed))
    assert len(records) == durable
    with pytest.warns(BagReadWarning):
        movements = load_run(killed).movements
    assert [m.index for m in movements] == list(range(1, len(movements) + 1))
    assert "rewrote" in repair(killed)
    assert (killed / f"killed.mcap{TRUNCATED_SUFFIX}").exists()  # nothing thrown away
    with AnyReader([killed]) as reader:
        assert reader.message_count == durable
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # complete now: no warning
        assert len(list(read_raw(killed))) == durable
    assert "nothing to do" in repair(killed)


def test_a_damaged_chunk_is_skipped_and_the_chunks_after_it_are_read(bag, run_messages):
    file = bag / "run.mcap"
    second = _chunk_offsets(file)[1]
    data = bytearray(file.read_bytes())
    # the chunk's first inner record claims more bytes than the chunk holds
    inner = second + 9 + 8 * 3 + 4 + 4 + 8
    data[inner + 1: inner + 9] = struct.pack("<Q", 10**6)
    file.write_bytes(bytes(data))
    with pytest.warns(BagReadWarning) as caught:
        records = list(read_raw(bag))
    assert len(records) == len(run_messages) - 20
    assert any("damaged chunk" in str(w.message) for w in caught)


def test_a_truncated_file_reads_up_to_the_cut(bag, run_messages):
    file = bag / "run.mcap"
    file.write_bytes(file.read_bytes()[: file.stat().st_size // 2])
    with pytest.warns(BagReadWarning, match="was not closed"):
        run = load_run(bag)
    assert [m.index for m in run.movements] == list(range(1, len(run.movements) + 1))
    assert 10 < len(run.movements) < 60


def test_the_older_layout_of_many_parts_and_staging_folders_still_reads(tmp_path,
                                                                       run_messages):
    old = tmp_path / "old"
    old.mkdir()
    halves = (run_messages[:40], run_messages[40:])
    for k, half in enumerate(halves):
        part = samples.write_bag(tmp_path / f"p{k}", half)
        shutil.copy(part / f"p{k}.mcap", old / f"old_{k}.mcap")
    (old / "metadata.yaml").write_text(json.dumps({"rosbag2_bagfile_information": {
        "version": 9, "relative_file_paths": ["old_0.mcap"]}}))  # the second: not yet listed
    staging = old / ".part_2"
    staging.mkdir()
    (staging / ".part_2.mcap").write_bytes(b"\x89MCAP0\r\n\x01")
    with pytest.warns(BagReadWarning, match="unfinished part"):
        run = load_run(old)
    assert len(run.movements) == 60


def test_a_missing_or_broken_metadata_file_falls_back_to_the_storage_file(bag):
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed")
    with pytest.warns(BagReadWarning, match="metadata.yaml is unreadable"):
        assert len(load_run(bag).movements) == 60
    (bag / "metadata.yaml").unlink()
    assert len(load_run(bag).movements) == 60


@pytest.mark.parametrize("kind", ["missing", "empty_dir", "text_file", "garbage_mcap"])
def test_a_path_that_is_not_a_bag_gives_a_clear_error(tmp_path, kind):
    path = tmp_path / "x"
    if kind == "empty_dir":
        path.mkdir()
    elif kind == "text_file":
        path = tmp_path / "notes.txt"
        path.write_text("hello")
    elif kind == "garbage_mcap":
        path = tmp_path / "bag.mcap"
        path.write_bytes(b"not an mcap file at all")
    with pytest.raises(NotABagError, match=str(path.name)), warnings.catch_warnings():
        warnings.simplefilter("ignore", BagReadWarning)  # the garbage file is also warned about
        list(read_raw(path))


def test_a_run_folder_given_as_a_bag_is_named_as_such(tmp_path, run_messages):
    run = tmp_path / "myrun"
    samples.write_bag(run / "bag", run_messages)
    with pytest.raises(NotABagError, match="run folder: its first recording is"):
        storage_files(run)


def test_a_single_storage_file_can_be_read(bag):
    assert len(list(read_raw(bag / "run.mcap"))) == len(list(read_raw(bag)))


def test_the_writer_refuses_an_existing_output_and_bad_settings(tmp_path, bag):
    with pytest.raises(BagWriteError, match="exists already"):
        BagWriter(bag)
    with pytest.raises(BagWriteError, match="storage"):
        BagWriter(tmp_path / "new", storage="rosbag1")
    with pytest.raises(BagWriteError, match="chunk_seconds"):
        BagWriter(tmp_path / "new2", chunk_messages=0)
    empty = BagWriter(tmp_path / "empty")
    empty.close()
    empty.close()  # idempotent
    assert list(read_raw(tmp_path / "empty")) == []


def test_sqlite3_storage_is_one_file_committed_at_each_checkpoint(tmp_path, run_messages):
    bag = samples.write_bag(tmp_path / "db", run_messages, storage="sqlite3",
                            chunk_messages=50)
    assert [f.suffix for f in storage_files(bag)] == [".db3"]
    assert len(load_run(bag).movements) == 60
    writer = BagWriter(tmp_path / "live", storage="sqlite3", chunk_messages=50)
    for topic, msgtype in TOPICS.items():
        writer.add_topic(f"/{topic}", msgtype)
    for k, (topic, msg) in enumerate(run_messages):
        writer.write(f"/{topic}", k, samples.TS.serialize_cdr(msg, msg.__msgtype__))
    killed = tmp_path / "killed"
    killed.mkdir()
    for file in (tmp_path / "live").iterdir():  # the database and its journal, as left
        shutil.copy(file, killed / file.name.replace("live", "killed"))
    writer.close()
    assert len(list(read_raw(killed))) == writer.checkpoints * 50
