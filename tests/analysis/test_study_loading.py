"""Loading a study from its bags: arrays, cache, damaged bags."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from synthetic_study import INSIDE, N_MOVES, OUTSIDE, run_messages, write_run

from sgim_nodes.analysis import study as study_module
from sgim_nodes.analysis.study import CACHE_NAME, AnalysisWarning, load_study


def test_runs_are_found_and_loaded_into_arrays(study: Path) -> None:
    s = load_study(study)
    assert s.learners == ["sgim-d", "random"]
    assert [r.seed for r in s.runs_of("sgim-d")] == [0, 1, 2]
    run = s.runs_of("sgim-d")[0]
    assert run.movement_index.tolist() == list(range(1, N_MOVES + 1))
    assert np.isnan(run.outcome[6]).all() and run.status[6] == 1  # movement 7 failed
    assert run.outcome[4].tolist() == list(INSIDE) and run.outcome[0].tolist() == list(OUTSIDE)
    assert run.process[8] == 2
    assert run.eval_index.tolist() == [0, 10, 20]
    assert run.eval_mean.tolist() == pytest.approx([0.9, 0.40, 0.20])
    assert run.total_movements == N_MOVES and run.finished and run.duration_s == 10.0
    assert not s.warnings and not s.skipped


def test_region_map_closest_to_a_time(study: Path) -> None:
    run = load_study(study).runs_of("sgim-d")[0]
    at, lower, upper, interest = run.region_map_at(12)
    assert at == 10 and lower.tolist() == [[-1, -1]] and upper.tolist() == [[1, 1]]
    at, lower, upper, interest = run.region_map_at(17)
    assert at == 20 and len(lower) == 2  # the two leaves, not the split root
    assert interest.tolist() == pytest.approx([0.01, 0.02])
    assert load_study(study).runs_of("random")[0].region_map_at(10)[0] == -1


def test_second_load_uses_the_cache(study: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    first = load_study(study)
    assert (study / "sgim-d-seed0" / CACHE_NAME).exists()

    def no_bag_reading(bag):
        raise AssertionError(f"{bag} read again although cached")

    monkeypatch.setattr(study_module, "_read_run", no_bag_reading)
    second = load_study(study)
    for a, b in zip(first.runs, second.runs, strict=True):
        np.testing.assert_array_equal(a.outcome, b.outcome)
        np.testing.assert_array_equal(a.eval_mean, b.eval_mean)
        np.testing.assert_array_equal(a.leaf_lower, b.leaf_lower)


def test_a_changed_bag_invalidates_the_cache(study: Path) -> None:
    load_study(study)
    run_dir = study / "random-seed1"
    shutil.rmtree(run_dir)
    write_run(study, "random", 1, run_messages("random", 1, {0: 0.9, 20: 0.1}))
    run = next(r for r in load_study(study).runs if r.name == "random-seed1")
    assert run.eval_index.tolist() == [0, 20] and run.eval_mean[-1] == pytest.approx(0.1)


def test_a_truncated_part_is_reported_and_the_rest_used(study: Path) -> None:
    run_dir = write_run(study, "sgim-d", 7, run_messages("sgim-d", 7, {0: 0.9, 10: 0.5, 20: 0.3}),
                        chunk_messages=10)
    (victim,) = sorted((run_dir / "bag").glob("*.mcap"))  # one file, cut by a full disk
    victim.write_bytes(victim.read_bytes()[: victim.stat().st_size // 2])
    with pytest.warns(AnalysisWarning, match=victim.name):
        s = load_study(study)
    run = next(r for r in s.runs if r.name == "sgim-d-seed7")
    assert 0 < len(run.movement_index) < N_MOVES  # partially used, not skipped
    assert "sgim-d-seed7" not in s.skipped


def test_an_unreadable_bag_is_skipped_with_a_warning(study: Path) -> None:
    run_dir = study / "random-seed2"
    for part in (run_dir / "bag").glob("*.mcap"):
        part.write_bytes(b"not an mcap file at all")
    with pytest.warns(AnalysisWarning, match="random-seed2"):
        s = load_study(study)
    assert "random-seed2" in s.skipped
    assert [r.seed for r in s.runs_of("random")] == [0, 1]


def test_folders_without_bag_or_name_are_reported(tmp_path: Path) -> None:
    (tmp_path / "random-seed0").mkdir()
    (tmp_path / "random-seed0" / "metadata.yaml").write_text("learner: random\nseed: 0\n")
    (tmp_path / "notes").mkdir()  # not a run: ignored silently
    with pytest.warns(AnalysisWarning, match="no bag"):
        s = load_study(tmp_path)
    assert not s.runs and "random-seed0" in s.skipped
