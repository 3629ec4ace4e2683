"""Fuzz run_experiment's command line up to the moment the first node would start.

`parse_args` then `plan_new` (or `plan_resume`) and `processes_of` (the processes and their
prefixes) are everything the launcher does before it starts a node; `run()` turns a refusal
(ParameterError, RunFolderError) into exit code 2 with one line per problem, and argparse
refuses its own options with exit code 2 and one "error:" line. Whatever the argument list, it
is refused that way or accepted: never a traceback. Nothing is written outside the test's own
folder: the run folder options (--runs-dir, --name, --resume) draw from paths inside it, and
garbage tokens never start with "--", which argparse would read as an abbreviation of one of
them.
"""

from __future__ import annotations

import contextlib
import io
import shutil
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.tally import fuzz, tally

pytestmark = pytest.mark.ros  # the graph's description imports the nodes' PARAMS

LEARNERS = ["sgim-d", "saggriac", "random-goals", "demo-only", "random"]
good_numbers = st.integers(min_value=0, max_value=2000).map(str)
numbers = st.one_of(good_numbers, good_numbers, good_numbers,
                    st.integers(min_value=-5, max_value=10_000).map(str),
                    st.sampled_from(["0", "-1", "4294967295", "4294967296",
                                     "99999999999999999999", "1e3", "nan", "inf", "-inf",
                                     "0x10", "", " ", "1_000", "forever", "٣"]))
garbage = st.text(max_size=12).filter(lambda t: not t.startswith("--"))
param_names = st.sampled_from(["goal_budget", "imitation_epsilon", "noise", "seed",
                               "teaching_set", "p_mode1", "zeta", "timing", "nosuch",
                               "a.b", "", "x y", "1abc"])
param_values = st.one_of(numbers, garbage, st.sampled_from(
    [".inf", ".nan", "[1,", "{a: 1}", "/etc/passwd", "2020-13-45", "&a 1", "*a", "~",
     "on-request", "[1, 2]", "'quoted'", "!!python/object:os.system ls"]))


@st.composite
def argument_lists(draw, root: Path) -> list[str]:
    """A run_experiment command line: options with values of their kind or not, in any
    order, some of them twice, some garbage."""
    paths = st.sampled_from([str(root / "params.yaml"), str(root / "binary.yaml"),
                             str(root / "twice.yaml"), str(root / "absent.yaml"), str(root),
                             "relative.yaml", str(root / "a\0b")])
    run_dirs = st.sampled_from([str(root / "runs"), str(root / "a-file"), "relative-runs",
                                str(root / "runs" / "deep" / "er")])
    resumes = st.sampled_from([str(root / "old-run"), str(root / "runs"), str(root / "none"),
                               str(root / "a-file")])
    options = {
        "--seed": numbers, "--movements": numbers, "--eval-every": numbers,
        "--demonstration-period": numbers,
        "--teacher": st.sampled_from(["automatic", "human", "web", "external", "robot"]),
        "--wait-for-teacher": numbers, "--web-port": numbers, "--web-host": st.sampled_from(
            ["127.0.0.1", "0.0.0.0", "::1", "localhost", "example.org", "", "a\nb"]),
        "--web-token": st.sampled_from(["", "short", "x" * 16, "t" * 40]),
        "--web-linger": numbers, "--runs-dir": run_dirs,
        "--name": st.one_of(garbage, st.sampled_from(["../../etc", "..", ".", "a/b", "",
                                                      "ok-name", "x" * 300, "n\0ul"])),
        "--storage": st.sampled_from(["mcap", "sqlite3", "zip"]),
        "--param": st.tuples(param_names, param_values).map(lambda t: f"{t[0]}={t[1]}")
        | garbage,
        "--params-file": paths, "--prefix": st.sampled_from(
            ["sim_bridge=nice", "nobody=nice", "sim_bridge=", "sim_bridge='unclosed",
             "light=nice", "garbage"]),
        "--compose": st.sampled_from(
            ["a=recorder,markers", "light=recorder", "x=nobody,markers", "recorder=markers,"
             "imitation", "=a", "b=", "c/d=recorder,markers", "garbage"]),
        "--domain": numbers, "--timeout": numbers, "--resume": resumes,
    }
    flags = ["--no-markers", "--quiet", "--separate"]
    argv: list[str] = []
    if draw(st.integers(0, 9)):  # usually a learner, first or anywhere
        argv.append(draw(st.sampled_from(LEARNERS) if draw(st.integers(0, 5)) else garbage))
    for _ in range(draw(st.integers(0, 5))):
        choice = draw(st.sampled_from([*options, *flags, "garbage"]))
        if choice in flags:
            argv.append(choice)
        elif choice == "garbage":
            argv.append(draw(garbage))
        else:
            argv += [choice, draw(options[choice])]
    if draw(st.booleans()):
        argv = draw(st.permutations(argv))
    return [*argv, *(["--runs-dir", str(root / "runs")] if draw(st.booleans()) else [])]


def _files(root: Path) -> None:
    """The files the command lines name: a good parameter file, bad ones, a run folder to
    resume with a damaged metadata.yaml."""
    root.mkdir(parents=True, exist_ok=True)
    (root / "params.yaml").write_text("/**:\n  ros__parameters:\n    goal_budget: 20\n")
    (root / "binary.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\xff\x00")
    (root / "twice.yaml").write_text("/**:\n  ros__parameters:\n    zeta: 2\n    zeta: 4\n")
    (root / "a-file").write_text("not a folder\n")
    (root / "old-run").mkdir(exist_ok=True)
    (root / "old-run" / "metadata.yaml").write_bytes(b"learner: sgim-d\nseed: \xff\n")


@fuzz(200)
@given(data=st.data())
def test_the_command_line_is_refused_in_one_line_or_planned(tmp_path_factory, monkeypatch,
                                                             data):
    from sgim_nodes.graph.experiment import processes_of
    from sgim_nodes.graph.experiment_options import parse_args
    from sgim_nodes.graph.plan import plan_new, plan_resume
    from sgim_nodes.graph.run_folder import RunFolderError
    from sgim_ros.params import ParameterError

    root = tmp_path_factory.getbasetemp() / "fuzz-command-line"
    _files(root)
    monkeypatch.chdir(root)  # a relative path stays inside the test's folder
    argv = data.draw(argument_lists(root))
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            args = parse_args(argv)
        except SystemExit as stop:
            lines = err.getvalue().strip().splitlines()
            assert stop.code == 2, (argv, err.getvalue())
            assert lines and lines[-1].startswith("ros_ws/run_experiment.sh: error: "), lines
            assert "Traceback" not in err.getvalue()
            tally("run_experiment command line", "refused by its options (exit 2)")
            return
        plan = None
        try:
            plan = plan_resume(args) if args.resume is not None else plan_new(args)
            if plan is not None:
                processes_of(args, plan.nodes)
        except (ParameterError, RunFolderError) as error:
            lines = str(error).split("\n")
            assert all(line.strip() for line in lines), (argv, str(error))
            tally("run_experiment command line", "refused before any node (exit 2)")
            return
        finally:
            if plan is not None:
                plan.lock.release()
                if args.resume is None:
                    shutil.rmtree(plan.run_dir)
    assert plan is not None and plan.run_dir.resolve().is_relative_to(
        Path(args.runs_dir).resolve()), (argv, plan.run_dir)
    tally("run_experiment command line", "accepted (planned)")
