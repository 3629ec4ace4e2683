"""A run table (analysis/run_table.py) holds every column the analysis reads from a run's bag,
the same run always gives the same bytes, and a table of another layout is refused."""

from __future__ import annotations

import dataclasses
import zipfile

import numpy as np
import pytest
from synthetic_study import ACTS_EPISODES, acts_records, run_messages, write_run

from sgim_nodes.analysis import run_table
from sgim_nodes.analysis.study import load_run_data, load_study

MAPS = ("map_index", "map_offsets", "leaf_lower", "leaf_upper", "leaf_interest")


def same_run(a, b) -> None:
    """Equal in every column; the region maps equal where the analysis reads them."""
    for t in [*a.eval_index, 10**9]:
        for left, right in zip(a.region_map_at(t), b.region_map_at(t), strict=True):
            assert np.array_equal(left, right), t
    for f in dataclasses.fields(a):
        if f.name == "path" or f.name in MAPS:
            continue
        left, right = getattr(a, f.name), getattr(b, f.name)
        if isinstance(left, np.ndarray):
            assert left.dtype == right.dtype and left.shape == right.shape, f.name
            assert np.array_equal(left, right, equal_nan=left.dtype.kind == "f"), f.name
        else:
            assert left == right, f.name


def test_every_column_of_a_study_survives_the_table(study, tmp_path):
    for run in load_study(study, warn=lambda m: None).runs:
        path = run_table.save_run(run, tmp_path / "tables" / f"{run.name}.npz",
                                  {"behaviour": "b" * 16})
        back = run_table.load_run(path)
        same_run(run, back)
        assert back.path == path
        assert run_table.read_stamp(path) == {"behaviour": "b" * 16}
    sgim = load_run_data(study / "sgim-d-seed0", warn=lambda m: None)
    assert sgim.eval_distances.shape == (3, 2)  # three evaluations of two goals
    assert np.allclose(sgim.eval_distances[-1], [0.1, 0.3])  # FINALS 0.20 -/+ 0.1
    assert sgim.map_index.size and sgim.leaf_interest.size  # the region maps are kept too


def test_an_acts_run_keeps_its_requests_and_choices(tmp_path):
    extra = acts_records(ACTS_EPISODES)
    folder = write_run(tmp_path / "s", "sgim-acts", 0,
                       run_messages("sgim-acts", 0, {0: 0.9, 20: 0.3}, extra=extra))
    run = load_run_data(folder, warn=lambda m: None)
    assert list(run.ask_teacher) == ["centre", "rough", "centre", "west", "rough", "centre", "west"]
    back = run_table.load_run(run_table.save_run(run, tmp_path / "t.npz", {}))
    same_run(run, back)


def test_the_same_run_gives_the_same_bytes(study, tmp_path):
    run = load_run_data(study / "sgim-d-seed1", warn=lambda m: None)
    first = run_table.save_run(run, tmp_path / "a.npz", {"behaviour": "x"}).read_bytes()
    second = run_table.save_run(run, tmp_path / "b.npz", {"behaviour": "x"}).read_bytes()
    assert first == second
    third = run_table.save_run(run, tmp_path / "c.npz", {"behaviour": "y"}).read_bytes()
    assert third != first


def test_a_table_of_another_format_or_without_a_column_is_refused(study, tmp_path):
    run = load_run_data(study / "random-seed0", warn=lambda m: None)
    path = run_table.save_run(run, tmp_path / "r.npz", {})
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    for dropped, message in (("format.npy", "format None"), ("eval_mean.npy", "eval_mean")):
        with zipfile.ZipFile(tmp_path / "bad.npz", "w") as archive:
            for name, data in members.items():
                if name != dropped:
                    archive.writestr(name, data)
        with pytest.raises(run_table.RunTableError, match=message):
            run_table.load_run(tmp_path / "bad.npz")


def test_a_table_keeps_the_tree_at_each_evaluation_and_the_last(study, tmp_path):
    run = load_run_data(study / "sgim-d-seed0", warn=lambda m: None)
    maps = 100  # a tree that changed at every count 1..100, with k + 1 leaves at count k
    sizes = np.arange(2, maps + 2)
    leaves = int(sizes.sum())
    busy = dataclasses.replace(
        run, eval_index=np.array([0, 40, 100]), eval_mean=np.array([0.5, 0.4, 0.3]),
        eval_distances=np.zeros((3, 2)), map_index=np.arange(1, maps + 1),
        map_offsets=np.concatenate([[0], np.cumsum(sizes)]),
        leaf_lower=np.random.default_rng(0).uniform(-1, 0, (leaves, 2)),
        leaf_upper=np.random.default_rng(1).uniform(0, 1, (leaves, 2)),
        leaf_interest=np.arange(leaves, dtype=float))
    back = run_table.load_run(run_table.save_run(busy, tmp_path / "busy.npz", {}))
    assert list(back.map_index) == [1, 40, 100]
    same_run(busy, back)
    assert back.region_map_at(40)[3].size == 41
