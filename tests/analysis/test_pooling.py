"""`analyze` refuses runs of two commits or two numpy versions (issue 30, item 3): runs are
pooled only when their learner fingerprints agree, unless --allow-mixed says otherwise."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from synthetic_study import fingerprint

from sgim_nodes.analysis.cli import main
from sgim_nodes.analysis.pooling import unlike_runs
from sgim_nodes.analysis.study import load_study

RANDOM = ("random-seed0", "random-seed1", "random-seed2")


def _refused(study: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> str:
    out = tmp_path / "out"
    assert main([str(study), "--out", str(out)]) == 2
    assert not out.exists()  # refused before any figure or table
    return capsys.readouterr().err


def test_runs_of_two_commits_are_refused(make_study, tmp_path: Path,
                                         capsys: pytest.CaptureFixture) -> None:
    study = make_study(fingerprints={"sgim-d-seed1": fingerprint(code="0ther0c0de")})
    err = _refused(study, tmp_path, capsys)
    assert "code: c0de0000c0de0000 in 5 runs (random-seed0, random-seed1, random-seed2, ...), " \
           "0ther0c0de in 1 run (sgim-d-seed1)" in err
    assert "--allow-mixed" in err


def test_runs_of_two_numpy_versions_are_refused(make_study, tmp_path: Path,
                                                capsys: pytest.CaptureFixture) -> None:
    study = make_study(fingerprints={name: fingerprint(numpy="1.26.4") for name in RANDOM})
    err = _refused(study, tmp_path, capsys)
    assert "numpy: 1.26.4 in 3 runs (random-seed0, random-seed1, random-seed2), 2.4.6 in 3 " \
           "runs (sgim-d-seed0, sgim-d-seed1, sgim-d-seed2)" in err
    assert "code:" not in err and "python:" not in err  # only what differs is named


@pytest.mark.parametrize(("recorded", "alike"), [("3.11", True), ("3.12", False)])
def test_python_counts_by_its_minor_release(make_study, recorded: str, alike: bool) -> None:
    # Fingerprints record Python's major and minor release; older runs (3.11.7 here) recorded
    # the patch release too.
    study = load_study(make_study(fingerprints={name: fingerprint(python=recorded)
                                                for name in RANDOM}))
    unlike = unlike_runs(study)
    if alike:
        assert unlike == []
    else:
        assert [(u.what, set(u.holders)) for u in unlike] == [("python", {"3.11", "3.12"})]


@pytest.mark.slow
def test_allow_mixed_pools_them_and_says_so_at_the_top(make_study, tmp_path: Path) -> None:
    study = make_study(fingerprints={"random-seed2": fingerprint(numpy="1.26.4")})
    out = tmp_path / "out"
    assert main([str(study), "--out", str(out), "--allow-mixed"]) == 0
    first = (out / "results.md").read_text().splitlines()[0]
    assert first.startswith("**Mixed runs pooled (--allow-mixed)**: numpy: 2.4.6 in 5 runs")
    assert "1.26.4 in 1 run (random-seed2)" in first
    mixed = json.loads((out / "results.json").read_text())["mixed"]
    assert [m["what"] for m in mixed] == ["numpy"]
    assert mixed[0]["holders"]["1.26.4"] == ["random-seed2"]


@pytest.mark.slow
def test_a_study_without_fingerprints_is_refused(make_study, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture) -> None:
    names = [f"{lr}-seed{s}" for lr in ("sgim-d", "random") for s in range(3)]
    study = make_study(fingerprints=dict.fromkeys(names))
    err = _refused(study, tmp_path, capsys)
    assert "the 6 runs predate learner fingerprints" in err and "--allow-mixed" in err
    assert main([str(study), "--out", str(tmp_path / "out"), "--allow-mixed"]) == 0
    assert "made before learner fingerprints" in \
        (tmp_path / "out" / "results.md").read_text().splitlines()[0]


def test_runs_without_a_fingerprint_among_runs_with_one_are_refused(
        make_study, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    study = make_study(fingerprints={"sgim-d-seed0": None})
    err = _refused(study, tmp_path, capsys)
    assert "fingerprint: recorded in 5 runs" in err
    assert "none (made before learner fingerprints) in 1 run (sgim-d-seed0)" in err


def test_a_run_resumed_by_another_learner_is_refused(make_study, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture) -> None:
    study = make_study()
    meta_file = study / "random-seed1" / "metadata.yaml"
    meta = yaml.safe_load(meta_file.read_text())
    meta["resumed"] = [{"segment": "bag.resume1", "fingerprint": "f00",
                        "fingerprint_changed": ["code", "numpy"]}]
    meta_file.write_text(yaml.safe_dump(meta))
    err = _refused(study, tmp_path, capsys)
    assert "resumed by another learner: bag.resume1 changed code, numpy in 1 run " \
           "(random-seed1)" in err


def test_parameters_that_differ_within_a_group_are_refused_by_name(
        make_study, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Parameters the metadata does not list (a node's) leave the runs in one group: the
    fingerprint tells them apart, and names the parameter."""
    other = fingerprint(parameters={"learner": {"demonstration_period": 150, "imitations": 9}})
    study = make_study(fingerprints={"sgim-d-seed2": other})
    err = _refused(study, tmp_path, capsys)
    assert "parameters of 'sgim-d' (imitations): imitations=5 in 2 runs (sgim-d-seed0, " \
           "sgim-d-seed1), imitations=9 in 1 run (sgim-d-seed2)" in err
    assert "numpy" not in err


def test_groups_that_differ_in_their_settings_are_still_analysed_apart(make_study) -> None:
    """Runs whose settings differ are separate groups (as before), so their fingerprints'
    parameters may differ: nothing is pooled across them."""
    study = make_study(seeds=2, learners=("random",))
    for seed, period in ((0, 150), (1, 50)):
        meta_file = study / f"random-seed{seed}" / "metadata.yaml"
        meta = yaml.safe_load(meta_file.read_text())
        meta["parameters"] = {"seed": seed, "demonstration_period": period}
        meta["fingerprint"] = fingerprint(parameters={"learner": {"demonstration_period":
                                                                  period}})
        meta_file.write_text(yaml.safe_dump(meta))
    with pytest.warns(UserWarning, match="demonstration_period"):
        loaded = load_study(study)
    assert len(loaded.learners) == 2 and unlike_runs(loaded) == []



def test_a_learners_own_code_must_agree_within_its_group_only(make_study, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture) -> None:
    """SGIM-ACTS's own modules count in its runs' learner_code alone: other learners' runs
    have none, and may be compared with it; two versions of it in one group may not."""
    own = {f"sgim-d-seed{s}": fingerprint(learner_code="ac750000") for s in range(3)}
    own["sgim-d-seed1"] = fingerprint(learner_code="0ther")
    study = make_study(fingerprints=own)
    err = _refused(study, tmp_path, capsys)
    assert "learner_code of 'sgim-d': ac750000 in 2 runs (sgim-d-seed0, sgim-d-seed2), " \
           "0ther in 1 run (sgim-d-seed1)" in err
    meta_file = study / "sgim-d-seed1" / "metadata.yaml"
    meta = yaml.safe_load(meta_file.read_text())
    meta["fingerprint"] = fingerprint(learner_code="ac750000")
    meta_file.write_text(yaml.safe_dump(meta))
    assert unlike_runs(load_study(study)) == []  # the random runs have none: still alike
