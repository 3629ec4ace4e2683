"""One graph description: checked parameters before any node starts, and the same nodes with
the same parameters whether a run is started by run_experiment or by `ros2 launch`."""

from __future__ import annotations

import importlib.util
import sys
import types
from dataclasses import fields
from pathlib import Path

import pytest
import yaml

from tests.conftest import REPO

pytestmark = pytest.mark.ros

LAUNCH_FILE = REPO / "sgim_nodes" / "launch" / "experiment.launch.py"


def _launch_module():
    spec = importlib.util.spec_from_file_location("experiment_launch", LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _args(*argv):
    from sgim_nodes.graph.experiment_options import parse_args

    return parse_args(list(argv))


# --- the graph ------------------------------------------------------------------------------
BASE = ["recorder", "sim_bridge", "evaluator", "markers"]
GOALS = ["interest_computer", "goal_generator", "low_level_explorer"]


@pytest.mark.parametrize(("learner", "teacher", "expected"), [
    ("random", "automatic", [*BASE, "social_interaction"]),
    ("saggriac", "automatic", [*BASE, *GOALS, "social_interaction"]),
    ("sgim-d", "automatic", [*BASE, *GOALS, "imitation", "teacher", "social_interaction"]),
    ("sgim-d", "human", [*BASE, *GOALS, "imitation", "human_input", "social_interaction"]),
    ("sgim-d", "web", [*BASE, *GOALS, "imitation", "web_teacher", "social_interaction"]),
    ("demo-only", "external", [*BASE, "social_interaction"]),  # hosted by the arbiter
    ("random-goals", "automatic", [*BASE, *GOALS, "social_interaction"]),
    ("sgim-acts", "automatic", [*BASE, *GOALS, "imitation", "centre/expert", "west/expert",
                                "rough/expert", "social_interaction"]),
])
def test_each_learner_gets_its_nodes(learner, teacher, expected):
    from sgim_nodes.graph.description import graph

    assert [spec.name for spec in graph(learner, teacher)] == expected
    without = [spec.name for spec in graph(learner, teacher, markers=False)]
    assert without == [name for name in expected if name != "markers"]


def test_every_node_parameter_has_a_description_and_learner_fields_have_ranges():
    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.graph.description import NODES
    from sgim_nodes.nodes.ros_glue import LEARNER_BOUNDS

    for spec in NODES.values():
        for param in spec.params:
            assert param.description, (spec.name, param.name)
            if param.name != "output":  # the recorder's bag: no default, it must be given
                param.validate(param.default)  # every other default passes its own check
    missing = {f.name for f in fields(LearnerConfig)} - set(LEARNER_BOUNDS)
    assert not missing, f"add the range of {missing} to ros_glue.LEARNER_BOUNDS"


def _learner_bounds() -> list[str]:
    try:
        from sgim_nodes.nodes.ros_glue import LEARNER_BOUNDS
    except ImportError:  # no ROS here: the module's tests are skipped anyway
        return []
    return sorted(LEARNER_BOUNDS)


# Ranges the descriptors give that LearnerConfig does not check (core/config.py): none, since
# both read core/config.RANGES; a name here would be accepted by the core.
CORE_UNCHECKED: set[str] = set()


@pytest.mark.parametrize("name", _learner_bounds())
def test_learner_ranges_agree_with_the_learner_config(name):
    """A value just outside a descriptor's range (or on an open edge, or not among its
    choices) is one LearnerConfig refuses too, naming the field."""
    import dataclasses

    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.nodes.ros_glue import LEARNER_BOUNDS
    from sgim_ros.params import OneOf

    check = LEARNER_BOUNDS[name]
    default = getattr(LearnerConfig(), name)
    if isinstance(check, OneOf):
        outside = ["no-such-choice"]
        assert set(check.choices) >= {default}
    else:
        step = 1 if isinstance(default, int) else 1e-6
        outside = []
        if check.low is not None:
            outside.append(check.low if check.low_open else check.low - step)
        if check.high is not None:
            outside.append(check.high + step)
        outside = [type(default)(value) for value in outside]
    assert outside
    for value in outside:
        assert not check(value)
        if name in CORE_UNCHECKED:
            dataclasses.replace(LearnerConfig(), **{name: value})  # accepted: see the set
            continue
        with pytest.raises(ValueError, match=name):
            dataclasses.replace(LearnerConfig(), **{name: value})


# --- parameters before any node starts ------------------------------------------------------
def test_an_unknown_parameter_is_refused_with_a_suggestion():
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError, match=r"unknown parameter 'goal_budgte'.*did you mean "
                                             r"'goal_budget'"):
        parameters(RunOptions("sgim-d", overrides={"goal_budgte": 1}))


def test_a_parameter_of_another_learner_is_accepted_but_not_used():
    from sgim_nodes.graph.description import RunOptions, graph, parameters, unused

    values = parameters(RunOptions("saggriac", overrides={"execute_timeout": 5.0}))
    assert values.shared["execute_timeout"] == 5.0  # the human teacher's: checked, recorded
    assert unused(["execute_timeout", "goal_budget"], graph("saggriac")) == ["execute_timeout"]


@pytest.mark.parametrize(("overrides", "message"), [
    ({"goal_budget": 0}, "'goal_budget' = 0 is invalid: it must be >= 1"),
    ({"noise": "loud"}, "'noise' must be of type float"),
    ({"zeta": 7}, "zeta: must be even"),
    ({"p_mode1": 0.9}, "must equal 1"),
    ({"seed": 4}, "'seed' is set by --seed"),
    ({"service_timeout": -1.0}, "'service_timeout' = -1.0 is invalid: it must be > 0"),
])
def test_bad_values_are_refused_by_name(overrides, message):
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        parameters(RunOptions("sgim-d", overrides=overrides))


@pytest.mark.parametrize(("learner", "teacher", "overrides", "message"), [
    ("sgim-d", "human", {"timing": "on-request"}, "needs the automatic teacher"),
    ("sgim-d", "external", {"timing": "on-request"}, "needs the automatic teacher"),
    ("demo-only", "automatic", {"timing": "on-request"}, "demo-only attempts no goals"),
    ("demo-only", "automatic", {"demonstration_content": "goal-only"},
     "cannot learn from a goal-only"),
    ("sgim-d", "automatic", {"demonstration_content": "both"}, "'demonstration_content'"),
    ("sgim-d", "automatic", {"timing": "when-asked"}, "'timing'"),
])
def test_social_modes_a_run_cannot_play_are_refused_before_it_starts(learner, teacher,
                                                                     overrides, message):
    """What the runner refuses (issue 14), the launcher refuses too, before any node starts."""
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError, match=message):
        parameters(RunOptions(learner, teacher=teacher, overrides=overrides))


@pytest.mark.parametrize(("learner", "overrides"), [
    ("sgim-d", {"timing": "on-request", "demonstration_content": "goal-only"}),
    ("demo-only", {"demonstration_content": "means-only"}),
    ("saggriac", {"timing": "on-request", "demonstration_content": "goal-only"}),  # no teacher
])
def test_social_modes_reach_the_arbiter_and_the_teacher(learner, overrides):
    from sgim_nodes.graph.description import NODES, RunOptions, parameters

    values = parameters(RunOptions(learner, overrides=overrides))
    for name, value in overrides.items():
        assert values.shared[name] == value
    assert values.for_node(NODES["teacher"])["demonstration_content"] == overrides[
        "demonstration_content"]
    if "timing" in overrides:
        assert values.for_node(NODES["social_interaction"])["timing"] == "on-request"
        assert values.for_node(NODES["teacher"])["timing"] == "on-request"


@pytest.mark.parametrize(("learner", "teacher", "listeners"), [
    ("random", "automatic", "recorder,evaluator,markers"),
    ("saggriac", "automatic", "recorder,evaluator,markers,low_level_explorer"),
    ("sgim-d", "automatic", "recorder,evaluator,markers,low_level_explorer,imitation,teacher"),
    ("sgim-d", "human", "recorder,evaluator,markers,low_level_explorer,imitation"),
    ("sgim-d", "web", "recorder,evaluator,markers,low_level_explorer,imitation,web_teacher"),
])
def test_the_simulator_waits_for_every_node_of_the_graph_that_hears_movements(
        learner, teacher, listeners):
    """After a restart, a simulator that served before the evaluator matched it would leave
    the evaluator a movement short for the rest of the run (CI saw that run time out)."""
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    values = parameters(RunOptions(learner, teacher=teacher))
    assert values.shared["movement_listeners"] == listeners
    with pytest.raises(ParameterError, match="'movement_listeners' is set by the launcher"):
        parameters(RunOptions(learner, overrides={"movement_listeners": "recorder"}))


def test_node_sections_are_checked_against_that_node():
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_ros.params import ParameterError

    values = parameters(RunOptions("sgim-d"), {"sim_bridge": {"noise": 0.01}})
    assert values.per_node == {"sim_bridge": {"noise": 0.01}}
    with pytest.raises(ParameterError, match="unknown parameter 'noize' for node 'sim_bridge'"):
        parameters(RunOptions("sgim-d"), {"sim_bridge": {"noize": 0.01}})
    with pytest.raises(ParameterError, match="unknown node 'simbridge'"):
        parameters(RunOptions("sgim-d"), {"simbridge": {"noise": 0.01}})


@pytest.mark.parametrize(("items", "message"), [
    (["goal_budget=[1,"], "'[1,' is not a valid value"),
    (["goal_budget"], "expects NAME=VALUE"),
    (["=3"], "expects NAME=VALUE"),
    (["goal_budget={a: 1}"], "not '{a: 1}'"),
])
def test_malformed_assignments_are_one_line(items, message):
    from sgim_nodes.graph.overrides import parse_assignments
    from sgim_ros.params import ParameterError

    with pytest.raises(ParameterError) as refused:
        parse_assignments(items)
    assert message in str(refused.value) and "\n" not in str(refused.value)


@pytest.mark.parametrize(("text", "message"), [
    ('"just a string"\n', "it holds a str"),
    ("- 1\n- 2\n", "it holds a list"),
    ("sim_bridge:\n  noise: 1\n", "section 'sim_bridge' must map"),
    ("/**:\n  ros__parameters: [1]\n", "section '/**' must map"),
    ("/sim*:\n  ros__parameters:\n    noise: 1\n", "sections /** (every node) or a node's"),
    ("a: [unclosed\n", "not valid YAML"),
])
def test_parameter_files_that_ros_would_misread_are_refused(tmp_path, text, message):
    from sgim_nodes.graph.overrides import read_parameter_files
    from sgim_ros.params import ParameterError

    path = tmp_path / "p.yaml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=message.replace("*", r"\*").replace("(", r"\(")
                       .replace(")", r"\)")):
        read_parameter_files([path])


def test_the_launcher_refuses_bad_parameters_before_making_the_run_folder(tmp_path, capsys):
    from sgim_nodes.graph.experiment import run

    code = run(_args("sgim-d", "--runs-dir", str(tmp_path), "--param", "goal_budgte=1",
                     "--param", "noise=-1"))
    err = capsys.readouterr().err
    assert code == 2
    assert "unknown parameter 'goal_budgte'" in err and "'noise' = -1" in err
    assert "Traceback" not in err and not list(tmp_path.iterdir())


def test_the_launcher_refuses_a_misspelt_name_in_a_parameter_file(tmp_path, capsys):
    """A wildcard section is given to every node: a name no node declares would be ignored."""
    from sgim_nodes.graph.experiment import run

    params_file = tmp_path / "mine.yaml"
    params_file.write_text("/**:\n  ros__parameters:\n    goal_budgte: 1\n")
    runs = tmp_path / "runs"
    code = run(_args("sgim-d", "--runs-dir", str(runs), "--params-file", str(params_file)))
    err = capsys.readouterr().err
    assert code == 2 and "unknown parameter 'goal_budgte'" in err and "goal_budget" in err
    assert "Traceback" not in err and not runs.exists()


def test_metadata_holds_every_parameter_of_every_node_with_the_value_it_runs_with(tmp_path):
    """What an audit of a run needs: the teacher's tolerance, the simulator's noise, the
    recorder's settings, ... whether given or left at their defaults."""
    from sgim_nodes.graph.plan import plan_new

    params_file = tmp_path / "extra.yaml"
    params_file.write_text("sim_bridge:\n  ros__parameters:\n    noise: 0.01\n")
    plan = plan_new(_args("sgim-d", "--runs-dir", str(tmp_path), "--name", "run",
                          "--params-file", str(params_file), "--param", "tolerance_noise=2.0"))
    plan.lock.release()
    recorded = yaml.safe_load(yaml.safe_dump(plan.meta))["node_parameters"]
    assert set(recorded) == {spec.name for spec in plan.nodes}
    for spec in plan.nodes:
        assert set(recorded[spec.name]) == {p.name for p in spec.params}, spec.name
    assert recorded["sim_bridge"]["noise"] == 0.01  # its own section
    assert recorded["evaluator"]["noise"] != 0.01  # the section is the simulator's
    assert recorded["teacher"]["tolerance_noise"] == 2.0
    assert recorded["recorder"]["chunk_seconds"] > 0 and recorded["recorder"]["chunk_messages"]
    assert recorded["recorder"]["output"] == str(tmp_path / "run" / "bag")


@pytest.mark.parametrize("argv", [["--timeout", "-1"], ["--timeout", "0"],
                                  ["--timeout", "nan"], ["--timeout", "inf"]])
def test_a_timeout_must_be_a_positive_number_of_seconds(argv, capsys):
    with pytest.raises(SystemExit) as refused:
        _args("random", *argv)
    assert refused.value.code == 2 and "--timeout must be" in capsys.readouterr().err


def test_the_default_timeout_is_bounded_and_grows_with_the_budget():
    from sgim_nodes.graph.experiment_options import default_timeout

    assert _args("random").timeout is None  # then default_timeout(movements)
    assert 600 < default_timeout(1000) < default_timeout(5000) < 4 * 3600


def test_web_teacher_options_become_its_parameters_and_the_token_stays_out_of_metadata(
        tmp_path):
    from sgim_nodes.graph.plan import plan_new

    plan = plan_new(_args("sgim-d", "--teacher", "web", "--web-host", "0.0.0.0",
                          "--wait-for-teacher", "forever", "--runs-dir", str(tmp_path),
                          "--name", "web"))
    plan.lock.release()
    web = {spec.name: spec for spec in plan.nodes}["web_teacher"]
    values = plan.values.for_node(web)
    assert values["host"] == "0.0.0.0" and len(values["token"]) >= 16  # made for it
    assert values["address_file"] == str(tmp_path / "web" / "web_teacher.url")
    assert plan.values.shared["wait_for_teacher"] == -1.0
    assert plan.meta["node_parameters"]["web_teacher"]["token"] == "<set>"
    assert values["token"] not in yaml.safe_dump(plan.meta)


@pytest.mark.parametrize(("argv", "message"), [
    (["--wait-for-teacher", "30"], "needs a human teacher"),
    (["--teacher", "web", "--web-token", "short"], "at least 16 characters"),
    (["--web-port", "70000"], "--web-port must be in 0..65535"),
])
def test_web_and_human_teacher_options_are_checked(argv, message, capsys):
    with pytest.raises(SystemExit):
        _args("sgim-d", *argv)
    assert message in capsys.readouterr().err


def test_run_options_cannot_be_changed_on_resume(capsys):
    with pytest.raises(SystemExit):
        _args("--resume", "runs/x", "--param", "goal_budget=3", "--seed", "2")
    assert "--seed, --param cannot be given with --resume" in capsys.readouterr().err


# --- one description, two launchers ---------------------------------------------------------
def _what_nodes_read(params_file: Path, spec) -> dict:
    """The values a node started with `--params-file params_file` reads, as rcl resolves a
    file: the `/**` values it declares, then its own section."""
    data = yaml.safe_load(params_file.read_text())
    declared = {p.name for p in spec.params}
    values = {k: v for k, v in data["/**"]["ros__parameters"].items() if k in declared}
    values.update(data.get(spec.name, {}).get("ros__parameters", {}))
    return values


@pytest.mark.parametrize(("learner", "teacher"), [("sgim-d", "automatic"),
                                                  ("saggriac", "automatic"),
                                                  ("demo-only", "external"),
                                                  ("sgim-d", "web"),
                                                  ("sgim-acts", "automatic"),
                                                  ("sgim-acts", "web"),
                                                  ("random", "automatic")])
def test_the_launch_file_starts_what_run_experiment_starts(tmp_path, learner, teacher):
    from sgim_nodes.graph.plan import plan_new

    params_file = tmp_path / "extra.yaml"
    params_file.write_text("/**:\n  ros__parameters:\n    goal_budget: 7\n"
                           "sim_bridge:\n  ros__parameters:\n    noise: 0.01\n")
    argv = [learner, "--seed", "4", "--movements", "300", "--eval-every", "100",
            "--demonstration-period", "50", "--teacher", teacher, "--runs-dir", str(tmp_path),
            "--name", "run", "--params-file", str(params_file), "--param", "imitation_count=3"]
    web = ["--wait-for-teacher", "30", "--web-port", "0"] if teacher == "web" else []
    plan = plan_new(_args(*argv, *web))
    plan.lock.release()
    plan.params_file.write_text(yaml.safe_dump(plan.values.to_yaml()))  # as launch() does
    launcher = {spec.name: (spec.package, spec.executable, _what_nodes_read(plan.params_file,
                                                                            spec))
                for spec in plan.nodes}

    launch = _launch_module().node_arguments({
        "learner": learner, "seed": "4", "movements": "300", "eval_every": "100",
        "demonstration_period": "50", "teacher": teacher, "storage": "mcap",
        "output": str(tmp_path / "run" / "bag"), "params_file": str(params_file),
        "param": "imitation_count=3",
        **({"wait_for_teacher": "30", "web_port": "0"} if teacher == "web" else {})})
    launched = {name: (kw["package"], kw["executable"], kw["parameters"][0])
                for name, kw in launch}
    assert launched == launcher
    assert launched["sim_bridge"][2]["noise"] == 0.01
    assert launched["evaluator"][2].get("noise") is None  # the section is the simulator's
    assert all(kw["respawn"] == (name == "sim_bridge") for name, kw in launch)

    # Composed, the nodes share the launcher's processes (the recorder alone: its end is the
    # run's), and each member reads from the run's file what the launcher's nodes read.
    from sgim_nodes.graph.process_plan import process_plan

    module = _launch_module()
    arguments = {"learner": learner, "seed": "4", "movements": "300", "eval_every": "100",
                 "demonstration_period": "50", "teacher": teacher, "storage": "mcap",
                 "output": str(tmp_path / "run" / "bag"), "params_file": str(params_file),
                 "param": "imitation_count=3",
                 **({"wait_for_teacher": "30", "web_port": "0"} if teacher == "web" else {})}
    run_file = tmp_path / "launch_params.yaml"
    run_file.write_text(yaml.safe_dump(module.run_parameter_file(arguments)))
    processes = module.process_arguments(arguments, run_file)
    expected = process_plan(plan.nodes, alone=("recorder",))
    assert [(name, members) for name, members, _ in processes] == [
        (p.name, tuple(spec.name for spec in p.members)) for p in expected]
    assert learner in ("demo-only", "random") or any(len(m) > 1 for _, m, _ in processes)
    by_name = {spec.name: spec for spec in plan.nodes}
    for name, members, kw in processes:
        if len(members) == 1:
            assert (kw["package"], kw["executable"], kw["parameters"][0]) == launcher[name]
            continue
        assert (kw["package"], kw["executable"], "name" in kw) == ("sgim_nodes", "composed",
                                                                   False)
        assert kw["parameters"] == [str(run_file)]
        hosted = kw["arguments"][kw["arguments"].index("--process") + 2:]
        assert hosted == [a for m in members for a in
                          ("--node", f"{m}={by_name[m].params_module}")]
        for member in members:
            assert (by_name[member].package, by_name[member].executable,
                    _what_nodes_read(run_file, by_name[member])) == launcher[member]
    separate = module.process_arguments({**arguments, "compose": "false"}, run_file)
    assert [(name, kw) for name, _, kw in separate] == launch


def test_sgim_acts_teachers_are_experts_in_their_namespaces_and_the_page_is_web():
    """Issue 33: each of sgim-acts's teachers is an expert node in the namespace of its name,
    the launcher starts it there, and the web page joins them as 'web' with --teacher web."""
    from sgim_nodes.graph.description import RunOptions, acts_teachers, graph, parameters
    from sgim_ros.params import ParameterError

    values = parameters(RunOptions("sgim-acts", overrides={"teachers": "west,north_arm"}))
    nodes = graph("sgim-acts", "automatic", True, acts_teachers(values.shared))
    experts = [(s.namespace, s.executable) for s in nodes if s.namespace]
    assert experts == [("west", "expert"), ("north_arm", "expert")]
    web = parameters(RunOptions("sgim-acts", teacher="web"))
    assert web.shared["teachers"] == "centre,west,rough,web" and web.shared["expert"] is True
    assert web.shared["teacher_timeout"] == 3600.0  # a person answers
    names = [s.name for s in graph("sgim-acts", "web", True, acts_teachers(web.shared))]
    assert "web_teacher" in names and "web/expert" not in names
    with pytest.raises(ParameterError, match="--teacher web"):
        parameters(RunOptions("sgim-acts", overrides={"teachers": "centre,web"}))
    with pytest.raises(ParameterError, match="teachers"):
        parameters(RunOptions("sgim-acts", overrides={"teachers": "centre,9bad"}))
    # A per-node section for one expert is checked against the expert's parameters.
    own = parameters(RunOptions("sgim-acts"), {"west/expert": {"precision": 0.05}})
    assert own.per_node["west/expert"] == {"precision": 0.05}
    assert "/west/expert" in own.to_yaml()
    with pytest.raises(ParameterError, match="unknown parameter 'zeta2'"):
        parameters(RunOptions("sgim-acts"), {"west/expert": {"zeta2": 1}})


def test_the_launch_file_builds_a_launch_description_with_launch_ros(monkeypatch, tmp_path):
    """launch and launch_ros are not on PyPI: stand-ins that record what the file asks of
    them check that it builds its actions from the arguments it declares."""
    made: dict[str, list] = {}

    def recorder(kind):
        class Action:
            def __init__(self, *args, **kwargs):
                self.args, self.kwargs = args, kwargs
                made.setdefault(kind, []).append(self)
        Action.__name__ = kind
        return Action

    class LaunchConfiguration:
        def __init__(self, name):
            self.name = name

        def perform(self, context):
            return context[self.name]

    modules = {
        "launch": {"LaunchDescription": recorder("LaunchDescription")},
        "launch.actions": {k: recorder(k) for k in ("DeclareLaunchArgument", "EmitEvent",
                                                    "LogInfo", "OpaqueFunction",
                                                    "RegisterEventHandler")},
        "launch.event_handlers": {"OnProcessExit": recorder("OnProcessExit")},
        "launch.events": {"Shutdown": recorder("Shutdown")},
        "launch.substitutions": {"LaunchConfiguration": LaunchConfiguration},
        "launch_ros": {}, "launch_ros.actions": {"Node": recorder("Node")},
    }
    for name, attributes in modules.items():
        monkeypatch.setitem(sys.modules, name, types.SimpleNamespace(**attributes))
    module = _launch_module()
    description = module.generate_launch_description()
    declared = {a.args[0]: a.kwargs["default_value"] for a in made["DeclareLaunchArgument"]}
    assert declared["learner"] == "sgim-d" and declared["movements"] == "5000"
    setup = made["OpaqueFunction"][0].kwargs["function"]
    context = dict(declared, learner="saggriac", output=str(tmp_path / "bag"))
    actions = setup(context)
    nodes = [a for a in actions if type(a).__name__ == "Node"]

    def name(node) -> str:
        kwargs = node.kwargs
        return kwargs.get("name") or kwargs["arguments"][kwargs["arguments"].index("--process")
                                                         + 1]

    assert [name(n) for n in nodes] == ["recorder", "sim_bridge", "evaluator", "observers",
                                        "chain"]
    written = tmp_path / "params.yaml"
    assert nodes[3].kwargs["parameters"] == [str(written)]
    assert yaml.safe_load(written.read_text()) == module.run_parameter_file(context)
    assert (tmp_path / "record.key").is_file()
    # Every process but the simulator's (restarted) and the lone arbiter's (the recorder
    # follows it) ends the launch when it ends; the chain ends only if a member fails.
    watched = [name(h.args[0].kwargs["target_action"])
               for h in actions if type(h).__name__ == "RegisterEventHandler"]
    assert watched == ["recorder", "evaluator", "observers", "chain"]
    # compose:=false: one process per node, as run_experiment's --separate.
    made.clear()
    actions = setup(dict(context, compose="false"))
    nodes = [a for a in actions if type(a).__name__ == "Node"]
    assert [n.kwargs["name"] for n in nodes] == [*BASE, *GOALS, "social_interaction"]
    watched = [h.args[0].kwargs["target_action"].kwargs["name"]
               for h in actions if type(h).__name__ == "RegisterEventHandler"]
    assert watched == ["recorder", "evaluator", "markers", *GOALS]
    assert description is not None


def test_a_node_checks_its_run_level_settings_as_the_core_does():
    """A node given teachers taking turns and timing on-request refuses them with the core's
    words (core/social_config.py), not words of its own."""
    from sgim_nodes.core.social_config import SocialConfig
    from sgim_nodes.nodes.ros_glue import social_config
    from sgim_ros.params import ParameterError

    values = {"timing": "on-request", "teacher_turns": "centre, left", "seed": 3}
    with pytest.raises(ValueError) as core:
        SocialConfig(timing="on-request", teacher_turns=("centre", "left"))
    with pytest.raises(ParameterError) as node:
        social_config(values)
    assert str(node.value) == f"parameter {core.value}"
    assert social_config({**values, "timing": "period"}).teacher_turns == ("centre", "left")
    assert social_config({"teacher_turns": ""}) == SocialConfig()
