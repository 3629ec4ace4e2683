"""`analyze` reads resumed runs whole, never pools unlike runs, refuses repeated seeds, and
leaves quarantined records out (issue 12, "Tools")."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from synthetic_study import N_MOVES, T, movement, run_messages, write_run

from sgim_nodes.analysis.cli import main
from sgim_nodes.analysis.study import AnalysisWarning, load_study
from tests.bag.samples import write_bag


def _set_metadata(run_dir: Path, **values) -> None:
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    meta.update(values)
    (run_dir / "metadata.yaml").write_text(yaml.safe_dump(meta))


def test_a_resumed_run_is_read_across_its_segments(tmp_path: Path) -> None:
    study = tmp_path / "study"
    messages = run_messages("sgim-d", 0, {0: 0.9, 10: 0.5, 20: 0.3})
    cut = next(i for i, (t, m) in enumerate(messages) if t == "movements" and m.index == 11)
    run_dir = write_run(study, "sgim-d", 0, messages[:cut])
    write_bag(run_dir / "bag.resume1", messages[cut:])
    run = load_study(study).runs[0]
    assert run.movement_index.tolist() == list(range(1, N_MOVES + 1))
    assert run.eval_index.tolist() == [0, 10, 20] and run.eval_mean[-1] == pytest.approx(0.3)
    assert run.finished and run.movements_done == N_MOVES


def test_runs_of_a_learner_with_different_teachers_or_budgets_are_not_pooled(
        make_study, tmp_path: Path) -> None:
    study = make_study(seeds=3, learners=("sgim-d",))
    for seed, teacher in ((0, "automatic"), (1, "automatic"), (2, "human")):
        _set_metadata(study / f"sgim-d-seed{seed}", teacher=teacher)
    with pytest.warns(AnalysisWarning, match="sgim-d: runs differ in teacher"):
        loaded = load_study(study)
    # The usual runs keep the learner's name; the others are named by what sets them apart.
    assert loaded.learners == ["sgim-d", "sgim-d [teacher=human]"]
    assert [r.seed for r in loaded.runs_of("sgim-d")] == [0, 1]
    out = tmp_path / "out"
    assert main([str(study), "--out", str(out)]) == 0
    results = json.loads((out / "results.json").read_text())
    assert results["final_errors"]["sgim-d"]["n"] == 2
    assert results["final_errors"]["sgim-d [teacher=human]"]["n"] == 1


def test_runs_of_a_learner_with_different_budgets_are_not_pooled(make_study) -> None:
    study = make_study(seeds=3, learners=("random",))
    _set_metadata(study / "random-seed2", movements=40)  # same recordings, another budget
    with pytest.warns(AnalysisWarning, match=r"random: runs differ in movements.*'random' "
                      r"\(movements=20; seeds 0, 1\)"):
        loaded = load_study(study)
    assert loaded.learners == ["random", "random [movements=40]"]
    assert [r.seed for r in loaded.runs_of("random")] == [0, 1]
    assert [r.seed for r in loaded.runs_of("random [movements=40]")] == [2]


def test_runs_differing_in_a_parameter_are_labelled_by_it(make_study) -> None:
    study = make_study(seeds=2, learners=("random",))
    for seed, period in ((0, 150), (1, 50)):
        _set_metadata(study / f"random-seed{seed}",
                      parameters={"seed": seed, "demonstration_period": period,
                                  "output": f"/x/{seed}"})
    with pytest.warns(AnalysisWarning, match="demonstration_period"):
        groups = load_study(study).learners
    assert groups == ["random [demonstration_period=150]", "random [demonstration_period=50]"]


def test_two_runs_with_the_same_seed_are_refused_unless_allowed(
        make_study, tmp_path: Path, capsys) -> None:
    study = make_study(seeds=2, learners=("random",))
    twin = study / "random-again"
    twin.mkdir()
    for item in (study / "random-seed0").iterdir():
        if item.name != "analysis_cache.npz":
            target = twin / item.name
            target.write_bytes(item.read_bytes()) if item.is_file() else \
                __import__("shutil").copytree(item, target)
    with pytest.warns(AnalysisWarning, match="share a seed"):
        assert load_study(study).repeated_seeds == {"random": ["random-again", "random-seed0"]}
    assert main([str(study), "--out", str(tmp_path / "out")]) == 2
    assert "same seed" in capsys.readouterr().err
    assert main([str(study), "--out", str(tmp_path / "out"), "--allow-repeated-seeds"]) == 0


@pytest.mark.parametrize("outcome", ["failed: the recorder could not write the bag (exit 3)",
                                     "finished"])
def test_a_run_whose_recordings_end_early_is_not_finished(tmp_path: Path, outcome) -> None:
    """A full disk: the bag ends at movement 14 with its last evaluation at 10. Its final
    error is not the run's, even if an older launcher wrote `finished`."""
    study = tmp_path / "study"
    messages = run_messages("random", 0, {0: 0.9, 10: 0.5, 20: 0.3})
    cut = next(i for i, (t, m) in enumerate(messages) if t == "movements" and m.index == 14)
    run_dir = write_run(study, "random", 0, messages[:cut + 1])
    _set_metadata(run_dir, outcome=outcome)
    with pytest.warns(AnalysisWarning, match=r"run not finished .*14/20 movements"):
        run = load_study(study).runs[0]
    assert not run.finished and run.movements_done == 14 and run.eval_index.tolist() == [0, 10]


def test_quarantined_records_are_reported_and_left_out(tmp_path: Path) -> None:
    study = tmp_path / "study"
    messages = run_messages("random", 0, {0: 0.9, 20: 0.3})
    forged = movement(3, (0.9, 0.9))  # a duplicate of movement 3
    far = movement(2_000_000, (0.1, 0.1))
    bad_eval = T["sgim_msgs/msg/Evaluation"](
        stamp=forged.stamp, movement_index=20, mean_distance=float("nan"), outcome_size=2,
        goals=np.zeros(4), reached=np.zeros(4), distances=np.array([np.nan, 0.1]))
    at = next(i for i, (t, m) in enumerate(messages) if t == "movements" and m.index == 15)
    messages[at + 1: at + 1] = [("movements", forged), ("movements", far),
                                ("evaluations", bad_eval)]
    write_run(study, "random", 0, messages)
    with pytest.warns(AnalysisWarning, match="3 record"):
        run = load_study(study).runs[0]
    assert run.movement_index.tolist() == list(range(1, N_MOVES + 1))
    assert run.eval_mean.tolist() == pytest.approx([0.9, 0.3])


def test_a_sweep_s_groups_are_named_by_what_they_change_from_the_usual_runs(make_study) -> None:
    """A sweep varies one setting per block around the paper's default, which every block
    shares: each group is named by its own change only, so labels (and legends) stay short."""
    study = make_study(seeds=3, learners=("sgim-d",))
    settings = [(150, "random-unreached"), (50, "random-unreached"), (150, "nearest-unreached")]
    for seed, (period, choice) in enumerate(settings):
        _set_metadata(study / f"sgim-d-seed{seed}",
                      parameters={"seed": seed, "demonstration_period": period,
                                  "teacher_choice": choice, "output": f"/x/{seed}"})
    with pytest.warns(AnalysisWarning, match="demonstration_period, teacher_choice"):
        loaded = load_study(study)
    assert sorted(loaded.learners) == ["sgim-d", "sgim-d [demonstration_period=50]",
                                       "sgim-d [teacher_choice=nearest-unreached]"]
    assert [r.seed for r in loaded.runs_of("sgim-d")] == [0]
    assert [r.seed for r in loaded.runs_of("sgim-d [demonstration_period=50]")] == [1]
