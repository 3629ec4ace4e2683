"""bench_suite.py reads pytest's own report: its summary line and its --durations table."""

from __future__ import annotations

from tests.benchmarks.scripts import load_benchmark

OUTPUT = """\
[bootstrap] ready: source ros_ws/env.sh to use the workspace in a shell
All checks passed!
........................................................................ [ 98%]
.F.                                                                      [100%]
=================================== FAILURES ===================================
__________________________________ test_turns __________________________________
>       assert turns == 3
E       AssertionError: assert 2 == 3
---------------------------------- node logs -----------------------------------
== logs/sim.log (last 1 lines)
[INFO] fishing world ready
=============================== warnings summary ===============================
tests/x.py::test_y
  a warning
============================= slowest 40 durations =============================
61.20s call     tests/ros/test_graph_runs.py::test_learner_through_the_graph[sgim-d]
4.50s setup    tests/browser/test_web_teacher_page.py::test_the_page_shows_the_run
40.00s call     tests/browser/test_web_teacher_page.py::test_the_page_shows_the_run
0.30s teardown tests/ros/test_graph_runs.py::test_learner_through_the_graph[sgim-d]
(10 durations < 0.005s hidden.  Use -vv to show these durations.)
=========================== short test summary info ============================
FAILED tests/ros/test_pace.py::test_turns - AssertionError
1 failed, 1103 passed, 2 warnings in 798.23s (0:13:18)
"""


def load():
    return load_benchmark("bench_suite")


def test_the_summary_line_is_read_whole():
    assert load().summary(OUTPUT) == ("1 failed, 1103 passed, 2 warnings", 798.23)
    assert load().summary("no tests ran\n") is None


def test_the_longest_tests_add_their_setup_call_and_teardown():
    longest = load().longest(OUTPUT, count=2)
    assert longest == [(61.5, "tests/ros/test_graph_runs.py::test_learner_through_the_graph"
                              "[sgim-d]"),
                       (44.5, "tests/browser/test_web_teacher_page.py::test_the_page_shows_"
                              "the_run")]


def test_a_failed_run_shows_each_failure_with_its_node_logs():
    shown = load().failures(OUTPUT)
    assert shown.startswith("=" * 35 + " FAILURES ")
    assert "E       AssertionError: assert 2 == 3" in shown and "fishing world ready" in shown
    assert "warnings summary" not in shown and "slowest" not in shown
    assert load().failures(OUTPUT, limit=100).endswith("[... cut]\n")
    assert load().failures("1 passed in 2.0s\n") == ""
