"""A run folder: one launcher at a time, metadata that must say what it is, and a resume that
says what the recording lost."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
import yaml

from sgim_nodes.graph.run_folder import (
    RUNNING,
    RunFolderError,
    RunLock,
    check_resume,
    read_claim,
    read_metadata,
    write_claim,
    write_metadata,
)
from tests.bag.samples import synthetic_run, write_bag

META = {"learner": "sgim-d", "seed": 3, "movements": 60, "outcome": "failed: x"}


def test_a_second_launcher_cannot_take_a_locked_run_folder(tmp_path):
    first = RunLock.take(tmp_path)
    with pytest.raises(RunFolderError, match=rf"in use by another launcher \(pid {os.getpid()}"):
        RunLock.take(tmp_path)
    first.release()
    RunLock.take(tmp_path).release()  # free again once released


def test_the_lock_stays_held_while_a_child_that_inherited_it_lives(tmp_path):
    lock = RunLock.take(tmp_path)
    child = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"],
                             stdin=subprocess.PIPE, pass_fds=(lock.fd,))
    try:
        lock.release()  # the launcher is gone; its node still runs
        with pytest.raises(RunFolderError):
            RunLock.take(tmp_path)
    finally:
        child.communicate(b"", timeout=30)
    RunLock.take(tmp_path).release()


def test_metadata_without_learner_is_refused_with_what_to_fix(tmp_path):
    write_metadata(tmp_path, {"seed": 3, "movements": 60})
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(
        {"/**": {"ros__parameters": {"learner": "saggriac", "seed": 3}}}))
    with pytest.raises(RunFolderError) as refused:
        read_metadata(tmp_path)
    message = str(refused.value)
    assert "no 'learner'" in message and "params.yaml says learner: saggriac" in message
    assert "\n" not in message


@pytest.mark.parametrize(("text", "expected"), [
    ("learner: sgimd\nseed: 1\nmovements: 5", "'learner' must be one of"),
    ("learner: random\nseed: -1\nmovements: 5", r"'seed' must be an integer in 0\.\.4294967295"),
    ("learner: random\nseed: 4294967296\nmovements: 5", "'seed' must be an integer in 0"),
    ("learner: random\nseed: 1\nseed: 2\nmovements: 5", "line 3: key 'seed' given twice"),
    (b"learner: random\nseed: \xff\n", r"not UTF-8 text \(byte 0xff at line 2\)"),
    ("just a string", "must be a mapping"),
    ("learner: [unclosed", "not valid YAML"),
])
def test_bad_metadata_is_named(tmp_path, text, expected):
    path = tmp_path / "metadata.yaml"
    path.write_bytes(text) if isinstance(text, bytes) else path.write_text(text)
    with pytest.raises(RunFolderError, match=expected):
        read_metadata(tmp_path)


def test_a_folder_without_metadata_is_not_a_run_folder(tmp_path):
    with pytest.raises(RunFolderError, match="not a run folder"):
        read_metadata(tmp_path)


def test_resume_sees_movements_the_recording_lost(tmp_path):
    write_bag(tmp_path / "bag", synthetic_run(n=40))
    state = check_resume(tmp_path, dict(META, movements_done=52))
    assert (state.recorded, state.claimed) == (40, 52)
    assert state.lost == (41, 52) and not state.complete


def test_the_claim_of_the_last_segment_names_what_a_full_disk_lost(tmp_path):
    """metadata.yaml could not be written (it still says 'running', no count): the claim file,
    written in place, says what the segment made; a claim of an earlier segment (its resume
    was killed before it said anything) does not count."""
    write_bag(tmp_path / "bag", synthetic_run(n=40))
    running = dict(META, outcome=RUNNING)
    assert write_claim(tmp_path, "bag", 0) == ""
    size = (tmp_path / ".made").stat().st_size
    assert check_resume(tmp_path, running).lost is None
    assert write_claim(tmp_path, "bag", 57) == "" and read_claim(tmp_path) == ("bag", 57)
    assert (tmp_path / ".made").stat().st_size == size  # in place: no block to find
    assert check_resume(tmp_path, running).lost == (41, 57)
    write_bag(tmp_path / "bag.resume1", synthetic_run(n=40))
    assert check_resume(tmp_path, running).claimed == 0
    (tmp_path / ".made").write_text("nonsense")
    assert read_claim(tmp_path) is None


def test_a_finished_run_whose_bag_is_short_is_not_complete(tmp_path):
    # What a full disk did to the old launcher: "finished", but the bag ends early.
    write_bag(tmp_path / "bag", synthetic_run(n=40))
    state = check_resume(tmp_path, dict(META, outcome="finished"))
    assert state.lost == (41, 60) and not state.complete


def test_a_complete_recording_loses_nothing(tmp_path):
    write_bag(tmp_path / "bag", synthetic_run(n=60))
    state = check_resume(tmp_path, dict(META, outcome="finished", movements_done=60))
    assert state.lost is None and state.complete


def test_metadata_is_replaced_whole(tmp_path):
    write_metadata(tmp_path, dict(META, outcome=RUNNING))
    write_metadata(tmp_path, dict(META, outcome="finished"))
    assert yaml.safe_load((tmp_path / "metadata.yaml").read_text())["outcome"] == "finished"
    assert [p.name for p in tmp_path.iterdir()] == ["metadata.yaml"]


def test_a_run_folder_without_any_recording_resumes_from_the_start(tmp_path):
    # The launcher was stopped before the recorder made its bag.
    state = check_resume(tmp_path, dict(META, movements_done=0))
    assert (state.recorded, state.lost, state.complete) == (0, None, False)
