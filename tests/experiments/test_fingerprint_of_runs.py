"""An experiment's fingerprint is what its runs do (experiments/references.py): each run's
reference digest and the data files. The id of a configuration only groups the runs that share
a reference run, so renaming it changes nothing; a run's changed digest changes it."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from sgim_nodes.experiments import references

RUNS = ("sgim-d-seed0", "sgim-d-seed1", "demo-only-seed0")


def _fingerprint(monkeypatch, ids: dict[str, str], digests: dict[str, str]) -> str:
    monkeypatch.setattr(references, "configurations", lambda experiment: ids)
    experiment = SimpleNamespace(name="toy", maker="graph", data={"goals": "abc"})
    table = {"graph": {"key": "k", "runs": digests}}
    return references.experiment_fingerprint(experiment, table, todays=False)


def test_renaming_a_configuration_leaves_the_fingerprint(monkeypatch):
    before = _fingerprint(monkeypatch, dict(zip(RUNS, ("a", "a", "b"), strict=True)),
                          {"a": "d1", "b": "d2"})
    renamed = _fingerprint(monkeypatch, dict(zip(RUNS, ("a", "a", "c"), strict=True)),
                           {"a": "d1", "c": "d2"})
    assert renamed == before


def test_a_run_that_does_something_else_changes_it(monkeypatch):
    ids = dict(zip(RUNS, ("a", "a", "b"), strict=True))
    before = _fingerprint(monkeypatch, ids, {"a": "d1", "b": "d2"})
    assert _fingerprint(monkeypatch, ids, {"a": "d1", "b": "d3"}) != before
    # Two runs that swap what they do are two runs that changed.
    swapped = dict(zip(RUNS, ("b", "b", "a"), strict=True))
    assert _fingerprint(monkeypatch, swapped, {"a": "d1", "b": "d2"}) != before


def test_a_configuration_without_its_reference_run_is_refused(monkeypatch):
    with pytest.raises(references.ReferencesOutdated, match="no reference run"):
        _fingerprint(monkeypatch, dict(zip(RUNS, ("a", "a", "b"), strict=True)), {"a": "d1"})
