"""The results directory: what counts as finished, installing a run once, scratch cleaning."""

from __future__ import annotations

import io
import tarfile
from pathlib import Path

import pytest
import yaml

from sgim_nodes.bag.mcap_recovery import MAGIC
from sgim_nodes.sweep import results, task
from sgim_nodes.sweep.results import State, install, run_state
from sgim_nodes.sweep.sweep_file import expand, spec_fingerprint

SPEC = expand({"learner": "sgim-d", "movements": 100, "seeds": [2], "demonstration_period": 50,
               "param": {"imitation_count": 3}})[0]


def make_run(folder: Path, outcome: str = "finished", movements: int = 100, closed: bool = True,
             fingerprint: dict | None = None, spec=None, **overrides) -> Path:
    """A run folder as run_experiment leaves it (metadata and one recording), by default made
    by this checkout's learner (the spec's fingerprint)."""
    spec = spec or SPEC
    params = {**spec.expected_parameters(), **overrides}
    (folder / "bag").mkdir(parents=True)
    (folder / "metadata.yaml").write_text(yaml.safe_dump(
        {"learner": params["learner"], "seed": params["seed"], "outcome": outcome,
         "parameters": params,
         "fingerprint": spec_fingerprint(spec).to_dict() if fingerprint is None
         else fingerprint}))
    (folder / "bag" / "bag.mcap").write_bytes(MAGIC + b"records" + (MAGIC if closed else b""))
    (folder / "bag" / "metadata.yaml").write_text(yaml.safe_dump({
        "rosbag2_bagfile_information": {
            "relative_file_paths": ["bag.mcap"],
            "topics_with_message_count": [
                {"message_count": movements, "topic_metadata": {"name": "/movements"}},
                {"message_count": 7, "topic_metadata": {"name": "/goals"}}]}}))
    return folder


def test_states_of_a_run_folder(tmp_path):
    assert run_state(tmp_path / "none", SPEC).state is State.ABSENT
    assert run_state(make_run(tmp_path / "ok"), SPEC).state is State.FINISHED
    aborted = run_state(make_run(tmp_path / "aborted", outcome="aborted: x"), SPEC)
    assert aborted.state is State.UNFINISHED and "aborted" in aborted.reason
    short = run_state(make_run(tmp_path / "short", movements=60), SPEC)
    assert short.state is State.UNFINISHED and "60 movements recorded" in short.reason
    open_file = run_state(make_run(tmp_path / "open", closed=False), SPEC)
    assert open_file.state is State.UNFINISHED and "not closed" in open_file.reason
    other = run_state(make_run(tmp_path / "other", imitation_count=5), SPEC)
    assert other.state is State.MISMATCH and "imitation_count: 5 recorded, 3 asked" in other.reason
    (tmp_path / "bare").mkdir()
    assert run_state(tmp_path / "bare", SPEC).state is State.UNFINISHED


def unlike_fingerprint(**changes) -> dict:
    """SPEC's fingerprint as another checkout would have made it."""
    made = spec_fingerprint(SPEC).to_dict()
    made["fields"] = {**made["fields"], **changes}
    return made


def test_a_finished_run_of_another_learner_is_unlike_and_says_why(tmp_path):
    """Resume compares the whole learner, not only the swept settings: a run whose recorded
    defaults, code, nodes' code or numpy differ from this checkout's is not reused."""
    numpy_run = make_run(tmp_path / "numpy", fingerprint=unlike_fingerprint(numpy="1.26.4"))
    state = run_state(numpy_run, SPEC)
    assert state.state is State.UNLIKE and "numpy" in state.reason
    # a default that changed since (the run holds zeta 20 where today's default is 50)
    params = {node: dict(values) for node, values in
              spec_fingerprint(SPEC).parameters.items()}
    params["low_level_explorer"]["zeta"] = 20
    from sgim_nodes.provenance.fingerprint import fingerprint

    older = fingerprint(params).to_dict()
    state = run_state(make_run(tmp_path / "zeta", fingerprint=older), SPEC)
    assert state.state is State.UNLIKE and "parameters (zeta)" in state.reason
    nodes = make_run(tmp_path / "nodes", fingerprint=unlike_fingerprint(graph_code="0" * 16))
    state = run_state(nodes, SPEC)
    assert state.state is State.UNLIKE and "graph_code" in state.reason
    bare = make_run(tmp_path / "old", fingerprint={})
    assert "before learner fingerprints" in run_state(bare, SPEC).reason
    resumed = make_run(tmp_path / "resumed")
    meta = yaml.safe_load((resumed / "metadata.yaml").read_text())
    meta["resumed"] = [{"segment": "bag.resume1", "fingerprint_changed": ["code"]}]
    (resumed / "metadata.yaml").write_text(yaml.safe_dump(meta))
    assert "resumed by another learner (bag.resume1)" in run_state(resumed, SPEC).reason


def _archive(folder: Path, name: str, extra: tuple[str, bytes] | None = None) -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        tar.add(folder, arcname=name)
        if extra:
            info = tarfile.TarInfo(extra[0])
            info.size = len(extra[1])
            tar.addfile(info, io.BytesIO(extra[1]))
    return buffer.getvalue()


def test_install_replaces_an_unfinished_run_in_one_step(tmp_path):
    runs = tmp_path / "runs"
    make_run(runs / SPEC.name, outcome="interrupted by the user")
    made = make_run(tmp_path / "worker" / SPEC.name)
    folder = install(runs, SPEC, _archive(made, SPEC.name), {"attempts": 2})
    assert folder == runs / SPEC.name
    assert run_state(folder, SPEC).state is State.FINISHED
    assert yaml.safe_load((folder / results.RUN_RECORD).read_text()) == {"attempts": 2}
    assert list((runs / results.INCOMING).iterdir()) == []
    assert sorted(p.name for p in runs.iterdir()) == [results.INCOMING, SPEC.name]


def test_install_keeps_a_finished_run_and_counts_it_once(tmp_path):
    runs = tmp_path / "runs"
    first = make_run(runs / SPEC.name)
    (first / "mark").write_text("first")
    again = make_run(tmp_path / "worker" / SPEC.name)
    install(runs, SPEC, _archive(again, SPEC.name), {})
    assert (first / "mark").read_text() == "first"
    assert not (first / results.RUN_RECORD).exists()


@pytest.mark.parametrize("member", ["../evil", "other-run/file", "/etc/evil"])
def test_install_refuses_an_archive_that_leaves_its_run_folder(tmp_path, member):
    made = make_run(tmp_path / "worker" / SPEC.name)
    runs = tmp_path / "runs"
    with pytest.raises(ValueError, match="outside its run folder"):
        install(runs, SPEC, _archive(made, SPEC.name, (member, b"x")), {})
    assert not (runs / SPEC.name).exists() and not (tmp_path / "evil").exists()


def test_one_sweep_at_a_time_per_results_directory(tmp_path):
    held = results.lock_results(tmp_path)
    with pytest.raises(results.ResultsBusy, match="another sweep"):
        results.lock_results(tmp_path)
    held.close()
    results.lock_results(tmp_path).close()


def test_stale_scratch_folders_go_live_ones_stay(tmp_path):
    live = task._lock(tmp_path / "run-a.1.lock")
    (tmp_path / "run-a.1").mkdir()
    (tmp_path / "run-b.2.lock").touch()  # its task died: nobody holds the lock
    (tmp_path / "run-b.2" / "logs").mkdir(parents=True)
    assert task.clean_stale(tmp_path) == ["run-b.2"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run-a.1", "run-a.1.lock"]
    live.close()
    assert task.clean_stale(tmp_path) == ["run-a.1"]
    assert list(tmp_path.iterdir()) == []


def test_movements_done_reads_the_arbiters_last_progress_line(tmp_path):
    assert task.movements_done(tmp_path) == 0
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "social_interaction.log").write_text(
        "[INFO] [1.0] [social_interaction]: 40/100 movements (40 %, 9.0/s)\n" * 50
        + "[INFO] [2.0] [social_interaction]: 87/100 movements (87 %, 9.9/s)\n")
    assert task.movements_done(tmp_path) == 87
    with (tmp_path / "logs" / "social_interaction.log").open("a") as log:  # SGIM-ACTS's requests
        log.write("[INFO] [3.0] [social_interaction]: request 9 to west at movement 88\n" * 400)
    assert task.movements_done(tmp_path) == 87
