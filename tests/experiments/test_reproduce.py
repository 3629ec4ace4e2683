"""ros_ws/reproduce.sh end to end on a tiny experiment: runs made once and resumed, the page's
blocks written with their provenance, stale pages found and marked, data pins enforced."""

from __future__ import annotations

from pathlib import Path

import pytest

from sgim_nodes.experiments import cli, pages, pinned, shipped, world_jobs
from sgim_nodes.experiments.pinned import pin_of
from sgim_nodes.provenance.fingerprint import data_files

PAGE = """# The pond

<!-- begin generated provenance -->
<!-- end generated provenance -->

Prose about the pond.

<!-- begin generated pond-share -->
<!-- end generated pond-share -->

<!-- begin generated pond-data -->
<!-- end generated pond-data -->
"""


@pytest.fixture
def repo(scratch_repo) -> Path:
    """A repository of one experiment (20 random casts in two chunks) and its page."""
    scratch_repo.page("docs/pond.md", PAGE)
    scratch_repo.experiment("pond", """\
        # twenty casts
        name: pond
        maker: world
        report: isolated_region
        pages: [docs/pond.md]
        runs:
          casts: 20
          chunk: 10
          seed: 3
        """)
    assert cli.main(["--references"]) == 0  # a world experiment's: its world's key alone
    return scratch_repo.root


@pytest.mark.slow
def test_reproduce_makes_the_runs_once_and_writes_the_page(repo, capsys):
    assert cli.main(["pond", "--parallel", "2"]) == 0
    err = capsys.readouterr().err
    assert "2 runs, 0 already made, 2 to do" in err
    runs = sorted((repo / "runs" / "pond").glob("*.npz"))
    assert [p.name for p in runs] == ["casts-seed3-chunk0.npz", "casts-seed3-chunk1.npz"]
    text = (repo / "docs" / "pond.md").read_text()
    assert "Prose about the pond." in text and "| random casts | 20 (" in text
    assert "| benchmark goals in it (`benchmark_goals.npz`) |" in text
    made = pages.provenance_of(text, "pond")
    experiment = pinned.find("pond")
    assert made.fingerprint == experiment.fingerprint()
    assert made.command == "ros_ws/reproduce.sh pond --parallel 2"
    # made again: nothing to cast, the same page
    before = {p: p.stat().st_mtime_ns for p in runs}
    assert cli.main(["pond"]) == 0
    assert "2 run(s) shipped in experiments/shipped/ with today's behaviour: not made again" \
        in capsys.readouterr().err
    assert {p: p.stat().st_mtime_ns for p in runs} == before
    assert cli.main(["--check"]) == 0
    # shipped: without its runs, the same page from the shipped result files
    folder = shipped.SHIPPED / "pond"
    assert sorted(p.name for p in folder.iterdir()) == [
        "casts-seed3-chunk0.npz", "casts-seed3-chunk1.npz", "stamps.yaml"]
    (repo / "runs" / "pond").rename(repo / "runs" / "gone")
    assert cli.main(["pond", "--report-only"]) == 0
    after = (repo / "docs" / "pond.md").read_text()
    assert "2 of 2 results read from `experiments/shipped/pond/`" in after  # its provenance
    assert {n: b for n, b in pages.blocks_of(after).items() if n != "provenance"} == \
        {n: b for n, b in pages.blocks_of(text).items() if n != "provenance"}
    assert cli.main(["pond", "--runs-only"]) == 0  # shipped: nothing to cast again
    assert not list((repo / "runs" / "pond").glob("*.npz"))
    assert cli.main(["pond", "--runs-only", "--ignore-shipped"]) == 0
    assert "2 runs, 0 already made, 2 to do" in capsys.readouterr().err
    (repo / "runs" / "pond").rename(repo / "runs" / "gone again")
    # --verify casts shipped chunks again (whole, or their first casts) and compares
    assert cli.main(["pond", "--verify", "2", "--verify-seed", "4"]) == 0
    err = capsys.readouterr().err
    assert "pond: verifying 2 of its shipped results (seed 4)" in err
    assert "casts-seed3-chunk1: the same result" in err
    assert cli.main(["pond", "--verify", "1", "--verify-movements", "3"]) == 0
    assert "first 3 movements or casts" in capsys.readouterr().err
    chunk = folder / "casts-seed3-chunk0.npz"
    kept = chunk.read_bytes()
    wrong = world_jobs.read_result(chunk)
    wrong["points"][1, 0] += 1e-9
    world_jobs.write_result(chunk, wrong)
    assert cli.main(["pond", "--verify", "2", "--verify-movements", "5"]) == 1
    assert "casts-seed3-chunk0: points differs first at entry 1" in capsys.readouterr().err
    assert cli.main(["pond", "--verify", "1", "--graph"]) == 2
    chunk.write_bytes(kept)
    # a result file of behaviour other than today's is not used
    stamps = folder / "stamps.yaml"
    stamps.write_text(stamps.read_text().replace(": ", ": 0", 1))
    assert cli.main(["pond", "--report-only"]) == 2


def test_check_finds_a_stale_page_and_mark_stale_bannering_it(repo, capsys):
    page = repo / "docs" / "pond.md"
    assert cli.main(["--check"]) == 1  # never made: no provenance
    assert "docs/pond.md: stale and not marked: pond's" in capsys.readouterr().out
    assert cli.main(["--mark-stale"]) == 0
    assert pages.has_banner(page.read_text(), "pond")
    assert cli.main(["--check"]) == 0
    # The banner says today's fingerprint: once that changes, --mark-stale says the new one,
    # in place, and marking again changes nothing.
    today = pinned.find("pond").fingerprint()
    page.write_text(page.read_text().replace(today, "0123456789abcdef"))
    capsys.readouterr()
    assert cli.main(["--mark-stale"]) == 0
    assert "docs/pond.md: marked stale" in capsys.readouterr().out
    marked = page.read_text()
    assert f"`{today}`" in marked and "0123456789abcdef" not in marked
    assert marked.count("<!-- stale pond: begin -->") == 1
    assert cli.main(["--mark-stale"]) == 0 and page.read_text() == marked
    assert "marked stale" not in capsys.readouterr().out


def test_a_change_of_the_runs_makes_the_page_stale(repo, capsys):
    experiment = pinned.find("pond")
    page = repo / "docs" / "pond.md"
    from sgim_nodes.provenance.fingerprint import environment
    from sgim_nodes.provenance.record import Provenance

    made = Provenance.now("x", "pond", experiment.fingerprint(), environment(), 1.0)
    pages.write_page(page, {"provenance": made.markdown()}, "pond")
    assert cli.main(["--check"]) == 0
    path = repo / "experiments" / "pond.yaml"
    path.write_text(path.read_text().replace("seed: 3", "seed: 4"))
    assert cli.main(["--check"]) == 1
    assert "stale and not marked" in capsys.readouterr().out


def test_a_page_stamped_by_the_sources_of_today_s_code_stays_fresh(repo, capsys):
    """A page stamped before reference runs existed (by its runs' sources) is fresh while
    today's code is the code that stamped it, through an alias the references record; the
    alias names what that code's runs did, so a change of the runs still stales the page."""
    from sgim_nodes.provenance.fingerprint import environment
    from sgim_nodes.provenance.record import Provenance

    experiment = pinned.find("pond")
    page = repo / "docs" / "pond.md"
    made = Provenance.now("x", "pond", experiment.source_fingerprint(), environment(), 1.0)
    pages.write_page(page, {"provenance": made.markdown()}, "pond")
    assert cli.main(["--check"]) == 1
    assert cli.main(["--references"]) == 0
    assert "pond: its runs do what they did" in capsys.readouterr().err
    assert cli.main(["--check"]) == 0
    path = repo / "experiments" / "pond.yaml"
    path.write_text(path.read_text().replace("seed: 3", "seed: 4"))
    assert cli.main(["--check"]) == 1


def test_check_says_when_the_references_are_another_code_s(repo, capsys, monkeypatch):
    from sgim_nodes.experiments import references

    monkeypatch.setattr(references, "maker_key", lambda maker: "0123456789abcdef")
    assert cli.main(["--check"]) == 1
    out = capsys.readouterr().out
    assert "pond: the world experiments' reference runs were made by other code" in out
    assert "ros_ws/reproduce.sh --references" in out


def test_data_other_than_pinned_is_refused_and_pin_takes_todays(repo, capsys):
    path = repo / "experiments" / "pond.yaml"
    text = path.read_text()
    first = next(iter(data_files()))
    path.write_text(text.replace(pin_of(data_files()[first]), "sha256:" + "0" * 16))
    assert cli.main(["pond"]) == 2
    assert f"{first} is " in capsys.readouterr().err
    assert cli.main(["--check"]) == 1
    assert cli.main(["pond", "--pin"]) == 0
    assert pinned.find("pond").data_problems() == []
    assert "# twenty casts" in path.read_text()


@pytest.mark.parametrize(("change", "message"), [
    ("name: pond", "name 'other' must be the file's name"),
    ("maker: world", "maker must be one of graph, runner, world"),
    ("pages: [docs/pond.md]", "pages must list existing pages"),
    ("  casts: 20", "runs takes casts, chunk"),
])
def test_a_bad_experiment_file_is_refused_with_its_reason(repo, capsys, change, message):
    path = repo / "experiments" / "pond.yaml"
    bad = {"name: pond": "name: other", "maker: world": "maker: robot",
           "pages: [docs/pond.md]": "pages: [docs/absent.md]",
           "  casts: 20": "  casts: twenty"}[change]
    path.write_text(path.read_text().replace(change, bad))
    assert cli.main(["pond", "--report-only"]) == 2
    assert message in capsys.readouterr().err


def test_a_key_given_twice_is_refused(repo, capsys):
    path = repo / "experiments" / "pond.yaml"
    path.write_text(path.read_text() + "maker: graph\n")
    assert cli.main(["--list"]) == 2
    assert "the key 'maker' is given twice" in capsys.readouterr().err


def test_a_chunk_of_another_learner_is_made_again(repo, capsys, monkeypatch):
    experiment = pinned.find("pond")
    runs = repo / "runs" / "pond"
    runs.mkdir(parents=True)
    calls = []

    def fake_run(job):
        calls.append(job.name)
        return {"name": job.name, "points": world_jobs.touch_downs.__doc__ and
                __import__("numpy").zeros((job.casts, 2)),
                "fingerprint": job.fingerprint().value, "seconds": 0.0}

    jobs = experiment.world_jobs
    world_jobs.write_result(world_jobs.result_path(runs, jobs[0]), fake_run(jobs[0]))
    stale = fake_run(jobs[1]) | {"fingerprint": "0" * 16}
    world_jobs.write_result(world_jobs.result_path(runs, jobs[1]), stale)
    calls.clear()
    from sgim_nodes.experiments import makers

    monkeypatch.setattr(world_jobs, "run_job", fake_run)
    assert makers.make_file_jobs(jobs, world_jobs, runs, 1, None, False) == 0
    assert calls == [jobs[1].name]
    assert "casts-seed3-chunk1: its learner differs" in capsys.readouterr().err
    assert len(list((runs / makers.UNLIKE_DIR).iterdir())) == 1


def test_report_only_without_runs_says_what_to_make_in_one_line(repo, capsys):
    """On a fresh clone no run is made: --report-only says so in one line, with the command
    that makes them, exit code 2, and leaves the page as it is."""
    before = (repo / "docs/pond.md").read_text()
    assert cli.main(["pond", "--report-only", "--runs-dir", str(repo / "nothing")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    (line,) = [x for x in err.splitlines() if "nothing to report from" in x]
    assert "`ros_ws/reproduce.sh pond` makes its" in line
    assert (repo / "docs/pond.md").read_text() == before
