"""`analyze STUDY_DIR` writes every figure and table, whatever the study's shape."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from synthetic_study import FINALS

from sgim_nodes.analysis.cli import main

FILES = ("error_curves.png", "landings.png", "landings_frames.png", "region_tree.png",
         "results.md", "results.json")


def _png(path: Path) -> bool:
    return path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_cli_writes_every_file(study: Path, tmp_path: Path, capsys: pytest.CaptureFixture
                               ) -> None:
    out = tmp_path / "out"
    assert main([str(study), "--out", str(out), "--times", "5", "10", "20"]) == 0
    for name in FILES:
        assert (out / name).stat().st_size > 0, name
    assert all(_png(out / n) for n in FILES if n.endswith(".png"))
    assert str(out) in capsys.readouterr().out  # tells the user where the files are
    results = json.loads((out / "results.json").read_text())
    assert results["final_errors"]["sgim-d"]["values"] == pytest.approx(FINALS["sgim-d"])
    assert results["final_errors"]["sgim-d"]["mean"] == pytest.approx(0.25)
    assert results["tests"][0]["welch_p"] is not None
    assert results["isolated_coverage"]["sgim-d"]["runs_reached"] == 1
    [region_test] = results["isolated_coverage_tests"]
    assert (region_test["reached_a"], region_test["reached_b"]) == (1, 0)
    assert region_test["fisher_p"] == pytest.approx(1.0)  # 1/3 against 0/3: no evidence
    assert results["runs"]["sgim-d"]["total_duration_s"] == pytest.approx(33.0)
    assert results["curves"]["random"]["movements"] == [0, 10, 20]
    md = (out / "results.md").read_text()
    for heading in ("## Runs", "## Final error", "## Pairwise tests", "## Isolated region"):
        assert heading in md
    assert "| sgim-d | 3 | 0 | **0.250** | [0.126, 0.374] |" in md  # no demonstrations
    assert "mean final error (movement 20)" in md
    # The isolated region's tests: runs reaching it, their difference, Fisher p (raw, Holm).
    assert "| sgim-d | random | 1/3, 0/3 | +0.33 [-0.29, +0.79] | 1 | 1 | 0.1 |" in md


@pytest.mark.slow
def test_default_output_folder_and_times(study: Path) -> None:
    assert main([str(study)]) == 0
    assert all((study / "analysis" / name).exists() for name in FILES)
    assert json.loads((study / "analysis" / "results.json").read_text())["skipped"] == {}


def test_one_seed_study_reports_tests_as_not_applicable(make_study, tmp_path: Path) -> None:
    study = make_study("one", seeds=1)
    out = tmp_path / "out1"
    assert main([str(study), "--out", str(out)]) == 0
    results = json.loads((out / "results.json").read_text())
    [test] = results["tests"]
    assert test["applicable"] is False and test["welch_p"] is None
    assert results["final_errors"]["random"]["low"] is None
    assert results["final_errors"]["random"]["mean"] == pytest.approx(FINALS["random"][0])
    assert "| n/a |" in (out / "results.md").read_text()
    assert all((out / name).exists() for name in FILES)


def test_a_single_learner_without_tree(make_study, tmp_path: Path) -> None:
    study = make_study("random_only", seeds=2, learners=("random",))
    out = tmp_path / "out2"
    assert main([str(study), "--out", str(out)]) == 0
    results = json.loads((out / "results.json").read_text())
    assert results["tests"] == [] and list(results["final_errors"]) == ["random"]
    assert not (out / "region_tree.png").exists()  # random builds no interest tree
    assert "region_tree" not in results["figures"]


def test_a_corrupted_bag_is_reported_and_skipped(study: Path, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture) -> None:
    for part in (study / "random-seed1" / "bag").glob("*.mcap"):
        part.write_bytes(b"\0" * 64)
    out = tmp_path / "out3"
    assert main([str(study), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "random-seed1" in captured.err and "warning" in captured.err
    assert "Skipped 1 run(s): random-seed1" in captured.out
    results = json.loads((out / "results.json").read_text())
    assert "random-seed1" in results["skipped"]
    assert results["final_errors"]["random"]["seeds"] == [0, 2]
    assert "random-seed1" in (out / "results.md").read_text()


def test_empty_or_missing_folder_fails_cleanly(tmp_path: Path) -> None:
    assert main([str(tmp_path)]) == 2
    assert main([str(tmp_path / "missing")]) == 2


def test_help_describes_the_outputs(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as done:
        main(["--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert all(name in text for name in FILES)


def test_reports_name_a_study_inside_the_working_directory_relatively(
        study: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A report committed to a repository names the study folder as the repository sees it;
    one outside the working directory keeps its absolute path."""
    out = tmp_path / "rel"
    monkeypatch.chdir(study.parent)
    assert main([study.name, "--out", str(out), "--times", "10"]) == 0
    assert (out / "results.md").read_text().startswith(f"# Study results: {study.name}\n")
    assert json.loads((out / "results.json").read_text())["study"] == study.name
    monkeypatch.chdir(tmp_path / "rel")
    assert main([str(study), "--out", str(out), "--times", "10"]) == 0
    assert json.loads((out / "results.json").read_text())["study"] == str(study.resolve())


def test_a_signed_run_without_its_key_is_skipped_or_read_as_told(
        make_study, tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch) -> None:
    """A run whose movements are signed but whose record.key was not copied is skipped with
    the reason; with --trust-unkeyed it counts, and results.md says so at its top."""
    from synthetic_study import movement, run_messages, write_run

    from sgim_ros import record_key

    monkeypatch.delenv(record_key.TRUST_ENV, raising=False)
    study = make_study("keyless", seeds=2, learners=("random",))
    key = record_key.new_key()
    messages = run_messages("random", 7, {0: 0.5, 20: 0.3})
    for topic, msg in messages:
        if topic == "movements":
            msg.signature = np.frombuffer(record_key.movement_signature(key, msg), np.uint8)
    write_run(study, "random", 7, messages)  # copied without its key
    assert movement(1, None).signature.size == 0  # the study's other runs sign nothing
    assert main([str(study), "--out", str(tmp_path / "strict")]) == 0
    err = capsys.readouterr().err
    assert "random-seed7" in err and f"key ({record_key.KEY_FILE}) is not in its folder" in err
    assert "random-seed7" not in (tmp_path / "strict" / "results.md").read_text().split(
        "## Runs")[0]
    assert main([str(study), "--out", str(tmp_path / "trusted"), "--trust-unkeyed",
                 "--no-cache"]) == 0
    top = (tmp_path / "trusted" / "results.md").read_text().split("## Runs")[0]
    assert f"Runs {record_key.UNKEYED} (--trust-unkeyed): random-seed7." in top
