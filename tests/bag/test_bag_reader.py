"""Split bags read back in order; damaged parts are skipped with a warning, never a crash."""

from __future__ import annotations

import json
import shutil
import warnings

import numpy as np
import pytest

from sgim_nodes.bag.reader import (
    BagReadWarning,
    NotABagError,
    load_run,
    read_messages,
    read_raw,
    storage_files,
)
from sgim_nodes.bag.writer import BagWriteError, SplitBagWriter
from tests.bag import samples


@pytest.fixture(scope="module")
def run_messages():
    return samples.synthetic_run(60)


@pytest.fixture
def split_bag(tmp_path, run_messages):
    return samples.write_bag(tmp_path / "run", run_messages, split_messages=20)


def test_a_split_bag_reads_back_every_message_in_order(split_bag, run_messages):
    files = storage_files(split_bag)
    assert len(files) == -(-len(run_messages) // 20)
    assert [f.name for f in files[:2]] == ["run_0.mcap", "run_1.mcap"]
    got = list(read_messages(split_bag))
    assert [t for t, _, _ in got] == [f"/{t}" for t, _ in run_messages]
    assert [ts for _, ts, _ in got] == sorted(ts for _, ts, _ in got)
    assert [m.index for t, _, m in got if t == "/movements"] == list(range(1, 61))
    # rosbags' own reader sees one ordinary multi-file rosbag2 bag.
    from rosbags.highlevel import AnyReader

    with AnyReader([split_bag]) as reader:
        assert reader.message_count == len(run_messages)


def test_load_run_converts_every_topic(split_bag, run_messages):
    run = load_run(split_bag)
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


def test_a_truncated_last_part_warns_and_the_rest_is_read(split_bag):
    *_, last, after = storage_files(split_bag)
    after.unlink()  # the run ended inside `last` (and metadata.yaml still lists `after`)
    data = last.read_bytes()
    last.write_bytes(data[: len(data) // 2])
    with pytest.warns(BagReadWarning) as caught:
        run = load_run(split_bag)
    messages = [str(w.message) for w in caught]
    assert any(last.name in m and "unreadable" in m for m in messages), messages
    assert any(after.name in m and "missing" in m for m in messages), messages
    assert [m.index for m in run.movements] == list(range(1, len(run.movements) + 1))
    assert 40 < len(run.movements) < 60


def test_a_corrupted_middle_part_is_skipped(split_bag):
    middle = storage_files(split_bag)[1]
    middle.write_bytes(b"\x89MCAP0\r\n" + bytes(500))
    with pytest.warns(BagReadWarning, match=middle.name):
        records = list(read_raw(split_bag))
    assert len(records) == sum(1 for _ in samples.synthetic_run(60)) - 20


def test_an_unfinished_part_and_unlisted_files_are_handled(split_bag):
    # What a SIGKILL leaves: metadata listing the first parts only, a staging dir.
    meta = json.loads((split_bag / "metadata.yaml").read_text())
    info = meta["rosbag2_bagfile_information"]
    info["relative_file_paths"] = info["relative_file_paths"][:2]
    (split_bag / "metadata.yaml").write_text(json.dumps(meta))
    staging = split_bag / ".part_9"
    staging.mkdir()
    (staging / ".part_9.mcap").write_bytes(b"\x89MCAP0\r\n\x01")
    with pytest.warns(BagReadWarning, match="unfinished part"):
        run = load_run(split_bag)
    assert len(run.movements) == 60  # the unlisted but complete files are read too


def test_a_missing_or_broken_metadata_file_falls_back_to_the_storage_files(split_bag):
    (split_bag / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed")
    with pytest.warns(BagReadWarning, match="metadata.yaml is unreadable"):
        assert len(load_run(split_bag).movements) == 60
    (split_bag / "metadata.yaml").unlink()
    assert len(load_run(split_bag).movements) == 60


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


def test_a_single_storage_file_can_be_read(split_bag):
    first = storage_files(split_bag)[0]
    assert len(list(read_raw(first))) == 20


def test_the_writer_refuses_an_existing_output_and_bad_settings(tmp_path, split_bag):
    with pytest.raises(BagWriteError, match="exists already"):
        SplitBagWriter(split_bag)
    with pytest.raises(BagWriteError, match="storage"):
        SplitBagWriter(tmp_path / "new", storage="rosbag1")
    bag = SplitBagWriter(tmp_path / "empty")
    bag.close()
    bag.close()  # idempotent
    assert list(read_raw(tmp_path / "empty")) == []


def test_sqlite3_storage_splits_too(tmp_path, run_messages):
    bag = samples.write_bag(tmp_path / "db", run_messages, storage="sqlite3", split_messages=50)
    assert [f.suffix for f in storage_files(bag)] == [".db3"] * 3
    assert len(load_run(bag).movements) == 60
    shutil.rmtree(bag)
