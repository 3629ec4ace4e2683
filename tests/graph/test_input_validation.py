"""One validation of every input, before any node starts (issue 31, item 4).

Each case below was accepted on main before this check: the launcher planned the run, and a
node refused it (exit code 2) at movement 0, or the simulator restarted until the run
aborted, or a traceback, or a silent last-wins, or a run folder outside --runs-dir. Now each is
refused up front, exit code 2, with one line naming the option, the file, the line or the
parameter.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.ros  # the graph's description imports the nodes' PARAMS


def _args(*argv):
    from sgim_nodes.graph.experiment_options import parse_args

    return parse_args(list(argv))


def _refused(capsys, tmp_path: Path, *argv: str) -> str:
    """Run the launcher up to its refusal: exit code 2, no traceback, no run folder; the
    refusal's lines."""
    from sgim_nodes.graph.experiment import run

    runs = tmp_path / "runs"
    code = run(_args(*argv, "--runs-dir", str(runs)))
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err and not runs.exists(), err
    return err


def _params_file(tmp_path: Path, body: str, name: str = "mine.yaml") -> Path:
    path = tmp_path / name
    path.write_text(body)
    return path


# --- finite numbers ---------------------------------------------------------------------------
@pytest.mark.parametrize("value", [".inf", "-.inf", ".nan", ".NaN", "1.0e+999"])
def test_an_infinite_or_nan_float_is_refused_before_any_node_starts(capsys, tmp_path, value):
    err = _refused(capsys, tmp_path, "sgim-d", "--param", f"imitation_epsilon={value}")
    assert "parameter 'imitation_epsilon'" in err and "must be a finite number" in err
    assert f"(--param imitation_epsilon={value})" in err and len(err.splitlines()) == 1


def test_every_float_parameter_refuses_nan_and_infinities():
    import math

    from sgim_nodes.graph.description import NODES
    from sgim_ros.params import ParameterError

    floats = [(spec.name, p) for spec in NODES.values() for p in spec.params
              if type(p.default) is float]
    assert len(floats) > 40
    for node, param in floats:
        for bad in (math.nan, math.inf, -math.inf):
            with pytest.raises(ParameterError, match="finite"):
                param.validate(bad)
        assert param.validate(param.default) == param.default, node  # its default still


def test_an_integer_ros_cannot_carry_is_refused_by_name():
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError, match=r"'goal_budget'.*64 bits"):
        parameters(RunOptions("sgim-d", overrides={"goal_budget": 2**63}))


# --- files only where files belong ------------------------------------------------------------
def test_a_teaching_set_that_is_not_one_is_refused_before_any_node_starts(capsys, tmp_path):
    wildcard = _params_file(tmp_path, "/**:\n  ros__parameters:\n    teaching_set: /etc/passwd\n")
    err = _refused(capsys, tmp_path, "sgim-d", "--params-file", str(wildcard))
    assert "parameter 'teaching_set' = '/etc/passwd' is invalid: not a teaching set" in err
    assert f"(in {wildcard})" in err and len(err.splitlines()) == 1
    # A section of the teacher alone is checked against the teacher's own declaration.
    section = _params_file(
        tmp_path, "teacher:\n  ros__parameters:\n    teaching_set: /etc/passwd\n", "teacher.yaml")
    err = _refused(capsys, tmp_path, "sgim-d", "--params-file", str(section))
    assert "'teaching_set'" in err and "node 'teacher'" in err


def _npz(path: Path, **arrays) -> str:
    np.savez(path, **arrays)
    return str(path)


@pytest.mark.parametrize(("make", "message"), [
    (lambda d: str(d / "absent.npz"), "no such file"),
    (lambda d: str(d), "not a regular file"),
    (lambda d: "/dev/null", "not a regular file"),
    (lambda d: _npz(d / "goals.npz", goals=np.zeros((3, 2))), "no actions, outcomes, spread"),
    (lambda d: _npz(d / "small.npz", actions=np.zeros((3, 12)), outcomes=np.zeros((3, 2)),
                    spread=np.zeros(3)), "actions has shape (3, 12), expected (M >= 1, 24)"),
    (lambda d: _npz(d / "nan.npz", actions=np.full((3, 24), np.nan),
                    outcomes=np.zeros((3, 2)), spread=np.zeros(3)), "NaN or infinite"),
    (lambda d: _npz(d / "wide.npz", actions=np.full((3, 24), 2.0), outcomes=np.zeros((3, 2)),
                    spread=np.zeros(3)), "outside [-1, 1]"),
    (lambda d: _npz(d / "empty.npz", actions=np.zeros((0, 24)), outcomes=np.zeros((0, 2)),
                    spread=np.zeros(0)), "expected (M >= 1, 24)"),
])
def test_a_teaching_set_must_be_an_npz_of_this_worlds_sizes(tmp_path, make, message):
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError) as refused:
        parameters(RunOptions("sgim-d", overrides={"teaching_set": make(tmp_path)}))
    assert message in str(refused.value) and "\n" not in str(refused.value)


def test_a_good_teaching_set_is_taken_and_named_absolutely(tmp_path, monkeypatch):
    """A path the user names is checked where they named it; the nodes (and a resume from
    another folder) read the same file."""
    from sgim_nodes.graph.description import NODES, RunOptions, parameters
    from sim_bridge.data_files import data_dir

    shutil.copy(data_dir() / "teaching_set.npz", tmp_path / "mine.npz")
    monkeypatch.chdir(tmp_path)
    values = parameters(RunOptions("sgim-d", overrides={"teaching_set": "mine.npz"}))
    assert values.shared["teaching_set"] == str(tmp_path / "mine.npz")
    assert values.for_node(NODES["teacher"])["teaching_set"] == str(tmp_path / "mine.npz")
    assert parameters(RunOptions("sgim-d")).shared.get("teaching_set", "") == ""


def test_every_node_that_takes_a_teaching_set_checks_it_the_same_way():
    from sgim_nodes.graph.description import NODES
    from sim_bridge.data_params import TEACHING_SET_FILE

    takers = {spec.name for spec in NODES.values() for p in spec.params
              if p.name == "teaching_set" and p.check == TEACHING_SET_FILE}
    declared = {spec.name for spec in NODES.values() for p in spec.params
                if p.name == "teaching_set"}
    assert takers == declared and {"teacher", "recorder", "social_interaction"} <= takers


def test_a_long_path_in_a_refusal_keeps_its_file_name():
    """A refused path deep in a folder tree is cut in its middle: the line stays short and
    still names the file the user must fix."""
    from sgim_nodes.graph.description import NODES
    from sgim_ros.params import ParameterError

    param = next(p for p in NODES["teacher"].params if p.name == "teaching_set")
    deep = "/tmp/" + "a-very-long-folder-name/" * 8 + "nope.npz"
    with pytest.raises(ParameterError) as refusal:
        param.validate(deep)
    message = str(refusal.value)
    assert "nope.npz'" in message and "/tmp/a-very" in message and "..." in message
    assert len(message) < len(deep)


# --- seeds ------------------------------------------------------------------------------------
def test_a_seed_beyond_the_graphs_range_is_refused_by_the_launcher(capsys):
    for seed in ("99999999999999999999", "4294967296", "-1"):
        with pytest.raises(SystemExit) as stop:
            _args("sgim-d", "--seed", seed)
        assert stop.value.code == 2
        assert "--seed must be in 0..4294967295" in capsys.readouterr().err
    assert _args("sgim-d", "--seed", "4294967295").seed == 2**32 - 1


def test_the_seed_range_is_the_graphs_and_numpys_everywhere(tmp_path):
    """RunStatus.seed is a uint32 (a larger seed is recorded wrapped, or stops the arbiter's
    status); numpy takes more, so that is the range of every entry: the nodes' seed
    parameters, `learn`, a sweep's seeds."""
    from rclpy.serialization import deserialize_message, serialize_message

    from sgim_msgs.msg import RunStatus
    from sgim_nodes.core import random_streams
    from sgim_nodes.core.runner import parse_args as learn_args
    from sgim_nodes.graph.description import NODES
    from sgim_nodes.sweep.sweep_file import SweepFileError, expand
    from sgim_ros.params import SEED_MAX, ParameterError

    assert SEED_MAX == random_streams.SEED_MAX == 2**32 - 1
    def recorded(seed: int) -> int:
        return deserialize_message(serialize_message(RunStatus(seed=seed)), RunStatus).seed

    assert recorded(SEED_MAX) == SEED_MAX and recorded(SEED_MAX + 1) == 0  # why: it wraps
    random_streams.component_rng(SEED_MAX, "goals")
    with pytest.raises(ValueError, match=r"seed must be in 0\.\.4294967295"):
        random_streams.component_rng(SEED_MAX + 1, "goals")
    seeds = [p for spec in NODES.values() for p in spec.params if p.name == "seed"]
    assert len(seeds) >= 6
    for param in seeds:
        assert param.validate(SEED_MAX) == SEED_MAX
        with pytest.raises(ParameterError, match="'seed'"):
            param.validate(SEED_MAX + 1)
    with pytest.raises(SystemExit):
        learn_args(["--seed", str(SEED_MAX + 1), "--output", str(tmp_path / "x.jsonl")])
    assert learn_args(["--seed", str(SEED_MAX), "--output", "x"]).seed == SEED_MAX
    for seeds_of_sweep in ([SEED_MAX + 1], {"first": SEED_MAX, "count": 2}, 10**12):
        with pytest.raises(SweepFileError, match="4294967295"):
            expand({"learner": "random", "seeds": seeds_of_sweep})


# --- parameter files: UTF-8 YAML, no key twice ------------------------------------------------
@pytest.mark.parametrize(("content", "message"), [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "not UTF-8 text (byte 0x89 at line 1)"),
    (b"/**:\n  ros__parameters:\n    noise: \xe9\n", "not UTF-8 text (byte 0xe9 at line 3)"),
    (b"\x00\x01\x02", "not valid YAML: unacceptable character"),
    (b"/**:\n  ros__parameters:\n    noise: &n 0.1\n    seed: *n\n",
     "line 4: an alias (*n): ROS does not read aliases"),
    (b"/**:\n  ros__parameters:\n    when: 2020-13-45\n", "not valid YAML: month must be in"),
    (b"[" * 2000, "not valid YAML: nested too deeply"),
])
def test_a_file_that_is_not_utf8_yaml_is_one_line(capsys, tmp_path, content, message):
    path = tmp_path / "params.yaml"
    path.write_bytes(content)
    err = _refused(capsys, tmp_path, "sgim-d", "--params-file", str(path))
    assert f"parameter file {path}: {message}" in err and len(err.splitlines()) == 1, err


@pytest.mark.parametrize(("text", "line", "key", "first"), [
    ("/**:\n  ros__parameters:\n    goal_budget: 1\n    goal_budget: 3\n", 4, "goal_budget", 3),
    ("/**:\n  ros__parameters:\n    a: {b: 1, b: 2}\n", 3, "b", 3),
    ("/**:\n  ros__parameters:\n    noise: 1\n/**:\n  ros__parameters:\n    noise: 2\n", 4,
     "/**", 1),
    ("sim_bridge:\n  ros__parameters: {}\n  ros__parameters:\n    noise: 0.1\n", 3,
     "ros__parameters", 2),
])
def test_a_key_given_twice_is_refused_naming_the_file_the_line_and_the_key(capsys, tmp_path,
                                                                          text, line, key,
                                                                          first):
    path = _params_file(tmp_path, text)
    err = _refused(capsys, tmp_path, "sgim-d", "--params-file", str(path))
    assert (f"parameter file {path}: line {line}: key '{key}' given twice (first at line "
            f"{first}); ROS would silently keep the last") in err
    assert len(err.splitlines()) == 1


def test_two_spellings_of_one_name_in_a_section_are_refused(tmp_path):
    from sgim_nodes.graph.overrides import read_parameter_files
    from sgim_ros.params import ParameterError

    path = _params_file(tmp_path, "/**:\n  ros__parameters:\n    a.b: 1\n    a:\n      b: 2\n")
    with pytest.raises(ParameterError, match=r"gives parameter 'a\.b' twice"):
        read_parameter_files([path])


def test_a_sweep_file_is_read_as_a_parameter_file_is(tmp_path):
    from sgim_nodes.sweep.sweep_file import SweepFileError, load

    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"learner: random\nseeds: \xff\n")
    with pytest.raises(SweepFileError, match=r"binary\.yaml: not UTF-8 text \(byte 0xff"):
        load(binary)
    twice = _params_file(tmp_path, "learner: random\nseeds: 2\nseeds: 3\n", "twice.yaml")
    with pytest.raises(SweepFileError, match=r"line 3: key 'seeds' given twice"):
        load(twice)


# --- run names stay inside --runs-dir ---------------------------------------------------------
@pytest.mark.parametrize("name", ["../../etc", "..", ".", "", "a/b", "/tmp/x", "n\0ul",
                                  "new\nline", "x" * 256])
def test_a_run_name_must_be_one_folder_inside_the_runs_dir(capsys, tmp_path, name):
    from sgim_nodes.graph.plan import plan_new
    from sgim_nodes.graph.run_folder import RunFolderError

    runs = tmp_path / "deep" / "runs"
    before = set(tmp_path.rglob("*"))
    with pytest.raises(SystemExit) as stop:
        _args("sgim-d", "--runs-dir", str(runs), "--name", name)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "--name" in err and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("ros_ws/run_experiment.sh: error: --name")
    # A caller that builds its own options meets the same check, before any folder is made
    # (an empty name there means the default one).
    if name:
        args = _args("sgim-d", "--runs-dir", str(runs))
        args.name = name
        with pytest.raises(RunFolderError, match="run name"):
            plan_new(args)
    assert set(tmp_path.rglob("*")) == before


def test_a_runs_dir_that_cannot_hold_a_run_is_one_line(capsys, tmp_path):
    from sgim_nodes.graph.experiment import run

    a_file = tmp_path / "a-file"
    a_file.write_text("")
    code = run(_args("random", "--runs-dir", str(a_file), "--name", "x"))
    err = capsys.readouterr().err
    assert code == 2 and "cannot make the run folder" in err and "Traceback" not in err


def test_a_good_name_makes_the_run_folder_inside_the_runs_dir(tmp_path):
    from sgim_nodes.graph.plan import plan_new

    plan = plan_new(_args("random", "--runs-dir", str(tmp_path), "--name", "seed-3 (retry)"))
    plan.lock.release()
    assert plan.run_dir.parent == tmp_path and plan.run_dir.is_dir()


def test_the_sweep_names_only_folders_the_file_system_takes(tmp_path):
    """A sweep names each run after its settings: a long one would be a folder name the file
    system refuses, at the run's start; it is refused with the sweep file instead."""
    from sgim_nodes.sweep.sweep_file import SweepFileError, expand
    from sim_bridge.data_files import data_dir

    long_file = tmp_path / ("t" * 200 + ".npz")
    shutil.copy(data_dir() / "teaching_set.npz", long_file)
    with pytest.raises(SweepFileError, match="at most 255 bytes"):
        expand({"learner": "sgim-d", "param": {"teaching_set": str(long_file)}})
    ok = expand({"learner": "random", "seeds": 2})
    assert [r.name for r in ok] == ["random-seed0", "random-seed1"]


def test_prefix_with_an_unclosed_quote_is_one_line():
    from sgim_nodes.graph.description import graph
    from sgim_nodes.graph.experiment import prefixes
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError, match="--prefix \"sim_bridge='x\": No closing quotation"):
        prefixes(["sim_bridge='x"], [spec.name for spec in graph("random")])


def test_a_namespace_without_a_name_gets_the_default_folder(tmp_path):
    from sgim_nodes.graph.plan import plan_new

    args = _args("random", "--runs-dir", str(tmp_path))
    assert isinstance(args, argparse.Namespace) and args.name is None
    plan = plan_new(args)
    plan.lock.release()
    assert plan.run_dir.name.startswith("random-seed0-")


# --- rules between learner parameters, and the teacher's wait ---------------------------------
@pytest.mark.parametrize(("assignments", "message"), [
    (["zeta=51"], "LearnerConfig.zeta: must be even"),
    (["zeta=120"], "LearnerConfig.zeta: must not exceed max_goals_per_region"),
    (["max_goals_per_region=40"], "LearnerConfig.zeta: must not exceed max_goals_per_region"),
    (["p_mode1=0.5"], "LearnerConfig.p_mode1: p_mode1 + p_mode2 + p_mode3 must equal 1"),
    (["p_mode1=0.7", "p_mode2=0.2", "p_mode3=0.2"], "p_mode1 + p_mode2 + p_mode3 must equal 1"),
])
def test_a_learner_rule_between_parameters_is_refused_before_any_node_starts(
        capsys, tmp_path, assignments, message):
    """Each value is within its own range; together they break a rule the reference page
    states beside the range (core/config.py TIES)."""
    err = _refused(capsys, tmp_path, "sgim-d", *(a for x in assignments for a in ("--param", x)))
    assert message in err and len(err.splitlines()) == 1, err


@pytest.mark.parametrize("value", ["0.5", "1.0e-9", "0.0"])
def test_a_teacher_timeout_shorter_than_the_teachers_casts_is_refused(capsys, tmp_path, value):
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_nodes.nodes.arbiter_params import TEACHER_TIMEOUT_MIN
    from sgim_ros.params import ParameterError

    for learner in ("sgim-d", "sgim-acts"):  # a boundary's word, a request's answer
        with pytest.raises(ParameterError, match=r"'teacher_timeout' = .* it must be >= 1"):
            parameters(RunOptions(learner, overrides={"teacher_timeout": float(value)}))
    err = _refused(capsys, tmp_path, "sgim-d", "--param", f"teacher_timeout={value}")
    assert "parameter 'teacher_timeout'" in err and "must be >= 1" in err, err
    values = parameters(RunOptions("sgim-d", overrides={"teacher_timeout": TEACHER_TIMEOUT_MIN}))
    assert values.shared["teacher_timeout"] == TEACHER_TIMEOUT_MIN
