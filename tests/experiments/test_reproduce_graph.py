"""ros_ws/reproduce.sh on a tiny graph experiment: runs made through the sweep driver, the
study report written into its two pages with their provenance, a run another experiment made
with the same learner taken rather than made again, and the same pages made again, byte for
byte, from the run tables it shipped once its runs are gone."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.analysis import run_table
from sgim_nodes.experiments import cli, pages, pinned, shipped
from sgim_nodes.experiments.reports.study import own_runs  # noqa: F401  (imported: it loads)
from sgim_nodes.provenance.record import machine

pytestmark = [pytest.mark.ros, pytest.mark.slow]

STUDY_BLOCKS = ("provenance", "final-errors", "error-curve", "pairwise", "isolated-coverage",
                "isolated-tests", "goal-groups", "findings", "second-finding", "cost")


def page(title: str, names) -> str:
    return f"# {title}\n\nProse.\n\n" + "\n".join(
        f"<!-- begin generated {n} -->\n<!-- end generated {n} -->\n" for n in names)


def experiment(name: str, pages_: list[str], learners: list[str], seeds: list[int]) -> str:
    return f"""\
        name: {name}
        maker: graph
        report: study
        pages: {pages_}
        runs:
          movements: 40
          eval_every: 20
          demonstration_period: 20
          seeds: {seeds}
          learner: {learners}
        """


def test_a_graph_experiment_is_made_reported_and_shares_its_runs(scratch_repo, monkeypatch,
                                                                  capsys):
    tmp_path = scratch_repo.root
    # A reference run (seed 0, the budget and evaluations of these tiny runs) is the very run
    # the experiment made for seed 0: its bag is digested rather than made a second time.
    from sgim_nodes.experiments import references

    digested = []

    def own_run(spec, work, name):
        made = tmp_path / "runs" / "tiny" / spec.name
        assert (spec.seed, spec.movements, spec.eval_every) == (0, 40, 20), spec
        assert f"-seed{spec.seed}" in spec.name, spec.name
        digested.append(spec.learner)
        return references.bag_digest(made / "bag")

    monkeypatch.setattr(references, "graph_reference", own_run)
    scratch_repo.page("docs/results.md", page("Results", STUDY_BLOCKS))
    scratch_repo.page("README.md", page("Readme", ("provenance", "summary")))
    scratch_repo.page("docs/other.md", page("Other", STUDY_BLOCKS))
    scratch_repo.page("docs/other_readme.md", page("Other", ("provenance", "summary")))
    scratch_repo.experiment("tiny", experiment(
        "tiny", ["docs/results.md", "README.md"], ["sgim-d", "random"], [0, 1]))
    scratch_repo.experiment("other", experiment(
        "other", ["docs/other.md", "docs/other_readme.md"], ["sgim-d"], [1]))

    assert cli.main(["tiny", "--parallel", "2"]) == 0, capsys.readouterr().err[-3000:]
    results = (tmp_path / "docs" / "results.md").read_text()
    blocks = pages.blocks_of(results)
    assert "| sgim-d | 2 |" in blocks["final-errors"]
    assert "SAGG-RIAC is missing" in blocks["findings"]
    assert pages.provenance_of(results, "tiny").fingerprint == pinned.find("tiny").fingerprint()
    assert f"made on {machine()}" in blocks["provenance"]  # where the runs were made
    assert sorted(digested) == ["random", "sgim-d"]
    readme = (tmp_path / "README.md").read_text()
    assert "| SGIM-D |" in pages.blocks_of(readme)["summary"]
    for figure in ("study_error_curves.png", "study_landings_frames.png"):
        assert (tmp_path / "docs" / "figures" / figure).stat().st_size > 10_000
    assert cli.main(["--check"]) == 1  # 'other' was never made
    capsys.readouterr()

    # 'other' needs sgim-d seed 1 with the same settings: 'tiny' shipped it
    assert cli.main(["other", "--runs-only"]) == 0
    assert "1 run(s) shipped in experiments/shipped/" in capsys.readouterr().err
    # without the shipped tables, it is taken from 'tiny''s folder, not made again
    assert cli.main(["other", "--ignore-shipped"]) == 0
    err = capsys.readouterr().err
    assert "1 run(s) taken from other experiments" in err, err
    assert "sgim-d-P20-seed1 (tiny)" in err and "1 already finished, 0 to do" in err, err
    mine = tmp_path / "runs" / "other" / "sgim-d-P20-seed1" / "metadata.yaml"
    theirs = tmp_path / "runs" / "tiny" / "sgim-d-P20-seed1" / "metadata.yaml"
    assert mine.stat().st_ino == theirs.stat().st_ino  # linked, not copied
    assert cli.main(["--check"]) == 0

    # A --runs-dir chosen elsewhere takes its runs from the experiments beside it too
    monkeypatch.setenv("SGIM_EXPERIMENT_RUNS", str(tmp_path / "nowhere"))
    assert cli.main(["other", "--runs-only", "--ignore-shipped", "--runs-dir",
                     str(tmp_path / "runs" / "o2")]) == 0
    err = capsys.readouterr().err
    assert "sgim-d-P20-seed1 (" in err and "1 already finished, 0 to do" in err, err

    # The runs are gone (a fresh clone): the pages are made from the shipped run tables alone,
    # byte for byte but for where their data came from
    tables = sorted(p.name for p in shipped.SHIPPED.iterdir())
    assert tables == [f"{learner}-seed{seed}.npz" for learner in ("random", "sgim-d-P20")
                      for seed in (0, 1)], tables
    assert cli.main(["tiny", "--report-only"]) == 0  # the figures are 'other''s until now
    made = {name: (tmp_path / name).read_text() for name in ("docs/results.md", "README.md")}
    figures = {p.name: p.read_bytes() for p in (tmp_path / "docs" / "figures").iterdir()}
    (tmp_path / "runs").rename(tmp_path / "runs.gone")
    assert cli.main(["tiny", "--report-only"]) == 0, capsys.readouterr().err[-3000:]
    for name, before in made.items():
        after = (tmp_path / name).read_text()
        assert without_provenance(after) == without_provenance(before), name
        assert "4 read from the run tables of experiments/shipped/" in after, name
    assert {p.name: p.read_bytes() for p in (tmp_path / "docs" / "figures").iterdir()} \
        == figures

    assert cli.main(["tiny", "--runs-only"]) == 0  # shipped: no run is made again
    assert "4 run(s) shipped in experiments/shipped/ with today's behaviour: not made again" \
        in capsys.readouterr().err
    assert not (tmp_path / "runs" / "tiny").exists() or not any(
        (tmp_path / "runs" / "tiny").glob("*-seed*"))

    # --verify makes shipped runs again, by the runner and through the graph: the same runs;
    # a table changed by one bit in one landing is found, its movement named
    assert cli.main(["tiny", "--verify", "4", "--verify-seed", "5"]) == 0
    err = capsys.readouterr().err
    assert "verifying 4 of its 4 shipped runs (seed 5, by the runner)" in err, err
    assert "4 of 4 runs made again the same" in err, err
    assert cli.main(["tiny", "--verify", "1", "--graph"]) == 0
    err = capsys.readouterr().err
    assert "through the graph" in err and "1 of 1 runs made again the same" in err, err
    path = shipped.SHIPPED / "sgim-d-P20-seed1.npz"
    changed = run_table.load_run(path)
    k = 11 + int(np.flatnonzero(np.isfinite(changed.outcome[11:, 1]))[0])
    changed.outcome[k, 1] = np.nextafter(changed.outcome[k, 1], 2.0)
    run_table.save_run(changed, path, run_table.read_stamp(path))
    assert cli.main(["tiny", "--verify", "4"]) == 1
    err = capsys.readouterr().err
    assert f"sgim-d-P20-seed1: outcome differs first at movement {k + 1}" in err, err
    assert "3 of 4 runs made again the same; differ: sgim-d-P20-seed1" in err, err


def without_provenance(text: str) -> dict[str, str]:
    blocks = pages.blocks_of(text)
    blocks.pop("provenance", None)
    return blocks
