"""`analyze` pools runs that differ only in settings that cannot change a movement (how long
the web page stays, how long a node waits, where and how the bag is written, the web page's
address), and the list of those settings is the nodes' own."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
import yaml

from sgim_nodes.analysis.study import NOT_THE_RUN, RUN_TIME, SILENT, AnalysisWarning, load_study

# Two runs' settings, apart in everything that is not the run: each pair of values differs.
APART = {"linger": (600.0, 0.0), "teacher_timeout": (60.0, 3600.0), "call_timeout": (600.0, 30.0),
         "service_timeout": (30.0, 5.0), "chunk_seconds": (0.5, 2.0), "port": (8765, 9000),
         "host": ("127.0.0.1", "0.0.0.0"), "token": ("***", ""), "storage": ("mcap", "sqlite3"),
         "address_file": ("/a/web_teacher.url", "/b/web_teacher.url")}


def _set_parameters(run_dir: Path, parameters: dict) -> None:
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    meta["parameters"] = parameters
    (run_dir / "metadata.yaml").write_text(yaml.safe_dump(meta))


def test_runs_apart_only_in_settings_outside_the_run_are_pooled(make_study) -> None:
    study = make_study(seeds=2, learners=("sgim-d",))
    for seed in (0, 1):
        _set_parameters(study / f"sgim-d-seed{seed}",
                        {"seed": seed, "demonstration_period": 150,
                         **{name: values[seed] for name, values in APART.items()}})
    with warnings.catch_warnings():
        warnings.simplefilter("error", AnalysisWarning)  # no "runs differ in ..."
        loaded = load_study(study)
    assert loaded.learners == ["sgim-d"]
    assert [r.seed for r in loaded.runs_of("sgim-d")] == [0, 1]


def test_a_setting_of_the_run_still_splits_them(make_study) -> None:
    study = make_study(seeds=2, learners=("sgim-d",))
    for seed, period in ((0, 150), (1, 50)):
        _set_parameters(study / f"sgim-d-seed{seed}",
                        {"seed": seed, "demonstration_period": period, "linger": 600.0 * seed})
    with pytest.warns(AnalysisWarning, match=r"runs differ in demonstration_period;"):
        loaded = load_study(study)
    assert sorted(loaded.learners) == ["sgim-d [demonstration_period=150]",
                                       "sgim-d [demonstration_period=50]"]


@pytest.mark.ros  # the nodes' declarations import rclpy
def test_the_settings_outside_the_run_are_the_ones_the_nodes_declare_so() -> None:
    """RUN_TIME: every parameter a node of the graph may change while it runs; SILENT: the
    recorder's and markers' own. Each leaves the fingerprint too (it names what shapes the
    movements), and nothing any other node reads as fixed is among them."""
    from sgim_nodes.graph.description import NODES
    from sgim_nodes.provenance.fingerprint import SILENT_NODES

    params = [(spec.name, p) for spec in NODES.values() for p in spec.params]
    shaping = {p.name for node, p in params if p.read_only and node not in SILENT_NODES}
    silent = {p.name for node, p in params if node in SILENT_NODES} - shaping
    assert {p.name for _, p in params if not p.read_only} == RUN_TIME
    assert silent - {"output", "storage"} == SILENT  # those two are per run (PER_RUN)
    assert not (RUN_TIME | SILENT) & shaping
    assert set(APART) <= NOT_THE_RUN
