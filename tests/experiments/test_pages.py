"""Generated blocks of a page, and the stale banner."""

from __future__ import annotations

import pytest

from sgim_nodes.experiments import pages
from sgim_nodes.provenance.fingerprint import environment
from sgim_nodes.provenance.record import Provenance

PAGE = """# A page

Some prose.

<!-- begin generated provenance -->
old
<!-- end generated provenance -->

More prose stays.

<!-- begin generated table -->
| a |
<!-- end generated table -->
"""


def made(fingerprint: str = "a" * 16) -> str:
    return Provenance.now("ros_ws/reproduce.sh x", "x", fingerprint, environment(), 1.0
                          ).markdown()


def test_fill_replaces_only_the_named_blocks_and_keeps_the_prose():
    out = pages.fill(PAGE, {"table": "| b |\n| c |", "provenance": made()}, "page.md")
    assert "Some prose." in out and "More prose stays." in out
    assert pages.blocks_of(out)["table"] == "| b |\n| c |\n"
    assert pages.provenance_of(out, "x").fingerprint == "a" * 16
    assert pages.provenance_of(out, "y") is None
    assert pages.fill(out, {"table": "| b |\n| c |"}, "p") == out  # idempotent


def test_a_block_the_page_lacks_is_named():
    with pytest.raises(pages.PageError, match=r"page\.md has no block for curves, figures"):
        pages.fill(PAGE, {"curves": "x", "figures": "y", "table": "z"}, "page.md")


def test_banner_goes_under_the_title_and_comes_off_when_fresh(tmp_path):
    text = pages.fill(PAGE, {"provenance": made()}, "p")
    marked = pages.with_banner(text, pages.banner("x", pages.provenance_of(text, "x"),
                                                  "b" * 16))
    assert marked.startswith("# A page\n\n<!-- stale x: begin -->\n> **Stale.**")
    assert f"come from commit {pages.provenance_of(text, 'x').commit} " in marked
    assert "`ros_ws/reproduce.sh x`" in marked and pages.has_banner(marked, "x")
    assert not pages.has_banner(marked, "other")
    assert pages.remove_banner(marked, "x") == text  # as before, no blank line left over
    path = tmp_path / "page.md"
    path.write_text(marked)
    pages.write_page(path, {"provenance": made("b" * 16)}, "x")
    fresh = path.read_text()
    assert not pages.has_banner(fresh, "x")
    assert pages.freshness(path, "x", "b" * 16).fresh
    assert not pages.freshness(path, "x", "c" * 16).fresh


def test_a_page_never_made_says_so_not_that_it_is_stale():
    never = pages.with_banner(PAGE, pages.banner("x", None, "b" * 16))
    assert "**Not made yet.**" in never and "**Stale.**" not in never
    assert "`ros_ws/reproduce.sh x`" in never and pages.has_banner(never, "x")


def test_a_studys_wall_time_is_its_runs_span_not_the_reports():
    """Made again from finished runs, a report takes seconds: the study's wall time is the
    span of its runs' metadata, from the first start to the last end."""
    from types import SimpleNamespace

    from sgim_nodes.experiments.reports.graph_study import wall_span

    def run(started: str, ended: str):
        return SimpleNamespace(metadata={"started": started, "ended": ended})

    study = SimpleNamespace(runs=[run("2026-12-04T17:00:00+00:00", "2026-12-04T17:03:00+00:00"),
                                  run("2026-12-04T17:01:00+00:00", "2026-12-04T18:10:00+00:00")])
    assert wall_span(study) == 70 * 60
    study.runs.append(SimpleNamespace(metadata={"started": "2026-12-04T17:00:00+00:00"}))
    assert wall_span(study) is None  # a run that does not say: no span rather than a wrong one
