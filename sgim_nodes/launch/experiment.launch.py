"""One run of the learner's graph, for a full ROS 2 install:

    ros2 launch sgim_nodes experiment.launch.py learner:=sgim-d seed:=3 movements:=5000

It starts the same nodes with the same parameters as `ros_ws/run_experiment.sh`, because both
take them from one graph description (sgim_nodes.graph.description); the arguments are that
script's options. What the script adds stays with it: a reserved ROS domain, metadata.yaml,
resuming, and the human teacher's prompt (with teacher:=human, run
`ros2 run teacher human_input` in a terminal of its own). The run ends when the recorder has
written it; a node that stops before (the simulator excepted: it is restarted) ends it too.

The nodes share processes as the script's do (docs/node_graph.md, "Processes"), except the
recorder, which runs alone here: its end is the run's end, and launch sees a process's end
only. `compose:=false` starts one process per node, as the script's --separate.

`launch` and `launch_ros` are imported only by generate_launch_description(), so that the
rest of this file (node_arguments) can be checked where they are not installed (tests/graph/).
"""

from __future__ import annotations

import shlex
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from sgim_nodes.core.learner_registry import OWN_NAMES, SGIM_D
from sgim_nodes.core.social_config import SOCIAL_DEFAULTS

ARGUMENTS = (
    ("learner", SGIM_D, ", ".join(OWN_NAMES) + ", or another package's"),
    ("seed", "0", "seed of the run"),
    ("movements", "5000", "movement budget (the paper's: 5000)"),
    ("eval_every", "250", "movements between evaluations"),
    ("demonstration_period", str(SOCIAL_DEFAULTS.demonstration_period),
     "movements between demonstrations"),
    ("teacher", "automatic", "automatic, human, web or external (see run_experiment.sh "
     "--help)"),
    ("wait_for_teacher", "0", "human or web teacher: seconds to wait at each turn (-1: until "
     "the teacher acts)"),
    ("web_host", "127.0.0.1", "web teacher: the interface of its page"),
    ("web_port", "8765", "web teacher: the port of its page"),
    ("web_token", "", "web teacher: the access token (needed off loopback)"),
    ("markers", "true", "start the markers node (the run's picture for rviz2 and Foxglove)"),
    ("storage", "mcap", "bag storage: mcap or sqlite3"),
    ("output", "", "bag directory (default: runs/<learner>-seed<N>-<time>/bag)"),
    ("params_file", "", "a ROS parameter file, checked as run_experiment's --params-file"),
    ("param", "", "NAME=VALUE assignments separated by spaces, as run_experiment's --param"),
    ("compose", "true", "share processes as run_experiment does (false: one process per "
     "node, as its --separate)"),
)
ALONE_IN_LAUNCH = ("recorder",)
"""Nodes launched in a process of their own even when composing: the recorder's end ends the
run, and launch learns of a process's end, not of a node's."""


def node_arguments(arguments: Mapping[str, str]) -> list[tuple[str, dict[str, Any]]]:
    """(node name, keyword arguments of launch_ros.actions.Node) of every node of the run,
    from the graph description; ParameterError (one line per problem) before anything
    starts."""
    specs, values = _run_nodes(arguments)
    return [(spec.name, _node_kwargs(spec, values.for_node(spec))) for spec in specs]


def process_arguments(arguments: Mapping[str, str], params_file: Path
                      ) -> list[tuple[str, tuple[str, ...], dict[str, Any]]]:
    """(process name, its nodes, keyword arguments of launch_ros.actions.Node) of every
    process of the run: a lone node as node_arguments gives it; a composed process runs
    `ros2 run sgim_nodes composed` and reads `params_file`, the run's parameter file
    (RunParameters.to_yaml, each node's section its own), which the caller writes."""
    specs, values = _run_nodes(arguments)
    return _processes(specs, values, params_file, _separate(arguments))


def _separate(arguments: Mapping[str, str]) -> bool:
    """compose:=false: one process per node."""
    return not _flag(arguments, "compose")


def _flag(arguments: Mapping[str, str], name: str) -> bool:
    """A true-or-false launch argument, true unless given as false, 0 or no."""
    return arguments.get(name, "true").lower() not in ("false", "0", "no")


def _processes(specs, values, params_file: Path, separate: bool
               ) -> list[tuple[str, tuple[str, ...], dict[str, Any]]]:
    from sgim_nodes.graph.process_plan import process_plan

    result = []
    for process in process_plan(specs, separate=separate, alone=ALONE_IN_LAUNCH):
        names = tuple(spec.name for spec in process.members)
        if not process.composed:
            spec = process.members[0]
            result.append((process.name, names, _node_kwargs(spec, values.for_node(spec))))
            continue
        # No `name`: launch_ros would rename every node of the process to it.
        result.append((process.name, names, {
            "package": "sgim_nodes", "executable": "composed",
            "arguments": ["--process", process.name, *process.node_options()],
            "parameters": [str(params_file)], "output": "screen",
            "respawn": process.respawn,
            "respawn_max_retries": _max_respawns() if process.respawn else -1}))
    return result


def run_parameter_file(arguments: Mapping[str, str]) -> dict[str, Any]:
    """The run's ROS parameter file, as run_experiment writes it."""
    return _run_nodes(arguments)[1].to_yaml()


def bag_path(arguments: Mapping[str, str]) -> Path:
    """The run's bag: output:=, or a new folder under runs/ named by learner, seed and time
    (so fix it once per launch: see setup)."""
    return Path(arguments.get("output") or Path("runs") / (
        f"{arguments['learner']}-seed{arguments['seed']}-{datetime.now(UTC):%Y%m%d-%H%M%S}")
        / "bag").resolve()


def _max_respawns() -> int:
    from sgim_nodes.graph.description import MAX_RESPAWNS

    return MAX_RESPAWNS


def _node_kwargs(spec, values: dict[str, Any]) -> dict[str, Any]:
    return {"package": spec.package, "executable": spec.executable, "name": spec.executable,
            "parameters": [values], **({"namespace": spec.namespace} if spec.namespace else {}),
            "output": "screen", "respawn": spec.respawn,
            "respawn_max_retries": _max_respawns() if spec.respawn else -1}


def _run_nodes(arguments: Mapping[str, str]):
    """The run's nodes (the terminal prompt left out) and their parameter values."""
    from sgim_nodes.graph.description import (
        RunOptions,
        acts_teachers,
        graph,
        parameters,
    )
    from sgim_nodes.graph.overrides import parse_assignments, read_parameter_files
    from sgim_ros.params import ParameterError

    def integer(name: str) -> int:
        try:
            return int(arguments[name])
        except ValueError:
            raise ParameterError(f"launch argument {name}:={arguments[name]!r} must be an "
                                 "integer") from None

    files = [Path(arguments["params_file"])] if arguments.get("params_file") else []
    shared, per_node, where = read_parameter_files(files)
    assigned, assigned_where = parse_assignments(shlex.split(arguments.get("param", "")))
    learner, seed = arguments["learner"], integer("seed")
    output = str(bag_path(arguments))
    try:
        wait = float(arguments.get("wait_for_teacher", "0"))
    except ValueError:
        raise ParameterError(f"launch argument wait_for_teacher:="
                             f"{arguments['wait_for_teacher']!r} must be seconds") from None
    markers = _flag(arguments, "markers")
    options = RunOptions(learner, seed, integer("movements"), integer("eval_every"),
                         integer("demonstration_period"), arguments["teacher"],
                         str(Path(output).resolve()), arguments["storage"],
                         {**shared, **assigned}, markers=markers, wait_for_teacher=wait,
                         web_host=arguments.get("web_host", "127.0.0.1"),
                         web_port=integer("web_port") if "web_port" in arguments else 8765,
                         web_token=arguments.get("web_token", ""),
                         web_address_file=str(Path(output).resolve().parent
                                              / "web_teacher.url"))
    values = parameters(options, per_node, {**where, **assigned_where})
    specs = [spec for spec in graph(learner, options.teacher, markers,
                                    acts_teachers(values.shared)) if not spec.interactive]
    return specs, values


def generate_launch_description():
    from launch import LaunchDescription
    from launch.actions import (
        DeclareLaunchArgument,
        EmitEvent,
        LogInfo,
        OpaqueFunction,
        RegisterEventHandler,
    )
    from launch.event_handlers import OnProcessExit
    from launch.events import Shutdown
    from launch.substitutions import LaunchConfiguration
    from launch_ros.actions import Node

    def setup(context, *args, **kwargs):
        import yaml

        from sgim_ros import record_key

        arguments = {name: LaunchConfiguration(name).perform(context)
                     for name, _, _ in ARGUMENTS}
        bag = bag_path(arguments)
        arguments["output"] = str(bag)  # one run folder for every node and file below
        actions: list[Any] = []
        specs, values = _run_nodes(arguments)  # the parameter files read once
        bag.parent.mkdir(parents=True, exist_ok=True)
        params_file = bag.parent / "params.yaml"
        params_file.write_text(yaml.safe_dump(values.to_yaml(), sort_keys=False))
        # The run's secret its simulator signs movements with (sgim_ros/record_key.py), kept
        # beside the bag for the readers and handed to the nodes in their environment.
        key = record_key.new_key()
        record_key.write_key(bag.parent, key)
        for name, members, node_kwargs in _processes(specs, values, params_file,
                                                     _separate(arguments)):
            node = Node(**node_kwargs, additional_env={record_key.ENV: key})
            actions.append(node)
            # The recorder ends the run once it has written it (after the arbiter's final
            # status); any other process that ends first ends it too, except the simulator's
            # (launch restarts it) and the arbiter's alone (it ends before the recorder; in a
            # composed process, its end is not the process's, and a failed member's is).
            if members not in (("sim_bridge",), ("social_interaction",)):
                actions.append(RegisterEventHandler(OnProcessExit(
                    target_action=node,
                    on_exit=[EmitEvent(event=Shutdown(reason=f"{name} ended"))])))
        if arguments["teacher"] == "human":
            actions.append(LogInfo(msg="teacher:=human: run `ros2 run teacher human_input` in "
                                       "a terminal of its own to teach"))
        return actions

    return LaunchDescription([
        *(DeclareLaunchArgument(name, default_value=default, description=text)
          for name, default, text in ARGUMENTS),
        OpaqueFunction(function=setup),
    ])
