"""The `world` experiment (sim_bridge/README_world.md): probes of the physics as jobs, their
settings checked, and a tiny experiment made into a page with every block and the figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sgim_nodes.experiments import cli, pages, world_jobs, world_probes

BLOCKS = ("provenance", "random-casts", "learnability", "noise")
PAGE = "# The world\n\n" + "".join(
    f"<!-- begin generated {name} -->\n<!-- end generated {name} -->\n\n" for name in BLOCKS)


def test_probes_are_jobs_one_per_seed_beside_the_chunks():
    jobs = world_jobs.expand_jobs({
        "casts": 30, "chunk": 20, "seed": 2, "sensitivity": {"seeds": 1, "actions": 20},
        "time_step": {"seeds": [4, 5], "actions": 3},
        "noise": {"seeds": 3, "actions": 20, "attempts": 10}}, "here")
    assert [job.name for job in jobs] == [
        "casts-seed2-chunk0", "casts-seed2-chunk1", "sensitivity-seed0", "time_step-seed4",
        "time_step-seed5", "noise-seed0", "noise-seed1", "noise-seed2"]
    assert jobs[-1].attempts == 10 and jobs[3].actions == 3
    # A probe's settings are part of its fingerprint: another count is another job.
    other = world_jobs.expand_jobs({"noise": {"seeds": 1, "actions": 20, "attempts": 9}}, "x")
    assert other[0].fingerprint().value != jobs[5].fingerprint().value


def test_a_change_of_the_probes_code_changes_their_fingerprint(monkeypatch, tmp_path):
    job = world_jobs.expand_jobs({"sensitivity": {"seeds": 1, "actions": 20}}, "x")[0]
    before = job.fingerprint().value
    changed = tmp_path / "world_probes.py"
    changed.write_text(Path(world_probes.__file__).read_text().replace("DELTA = 1e-3",
                                                                        "DELTA = 1e-2"))
    monkeypatch.setattr(world_probes, "__file__", str(changed))
    assert job.fingerprint().value != before


@pytest.mark.parametrize(("runs", "message"), [
    ({}, "runs names no casts and no probe"),
    ({"noise": {"seeds": 2, "actions": 20}}, "noise takes seeds, actions, attempts"),
    ({"time_step": {"seeds": 0, "actions": 3}}, "time_step takes seeds, actions"),
    ({"sensitivity": {"seeds": 1, "actions": -1}}, "sensitivity takes seeds, actions"),
    ({"sensitivity": {"seeds": ["a"], "actions": 2}}, "sensitivity takes seeds, actions"),
    ({"wind": 3}, "runs has no wind"),
])
def test_bad_probe_settings_are_refused_with_their_reason(runs, message):
    with pytest.raises(ValueError, match=message):
        world_jobs.expand_jobs(runs, "here")


def test_the_probes_measure_the_physics():
    """Noise off, a cast comes down where its twin does: a nudged number moves it a little
    (the world is smooth), while the world's noise spreads repeated casts apart."""
    shifts = world_probes.sensitivity(seed=0, actions=1)
    assert 20 <= len(shifts) <= 24 and np.all(shifts >= 0)
    assert np.median(shifts) < 0.05
    spreads = world_probes.paper_noise(seed=0, actions=2, attempts=3)
    assert len(spreads) == 2 and np.all(spreads > 0)
    assert len(world_probes.time_step(seed=0, actions=1)) == 1


def test_a_tiny_world_experiment_fills_every_block_and_draws_the_histogram(scratch_repo,
                                                                           capsys):
    scratch_repo.page("docs/world.md", PAGE)
    scratch_repo.experiment("tinyworld", """\
        name: tinyworld
        maker: world
        report: world
        pages: [docs/world.md]
        runs:
          casts: 20
          chunk: 10
          seed: 3
          sensitivity: {seeds: 1, actions: 1}
          time_step: {seeds: 1, actions: 2}
          noise: {seeds: 2, actions: 2, attempts: 3}
        """)
    assert cli.main(["tinyworld", "--parallel", "1"]) == 0, capsys.readouterr().err[-3000:]
    blocks = pages.blocks_of((scratch_repo.root / "docs" / "world.md").read_text())
    assert "| random casts | 20: **" in blocks["random-casts"]
    assert "the time step halved" in blocks["learnability"]
    assert "one action number moved by 0.001" in blocks["learnability"]
    seeds = next(line for line in blocks["noise"].splitlines() if "seed by seed" in line)
    assert len(seeds.split("|")[2].split(",")) == 2
    figure = scratch_repo.root / "docs" / "figures" / "sim_random_casts.png"
    assert figure.stat().st_size > 5_000
