"""One run of the learner's graph, for a full ROS 2 install:

    ros2 launch sgim_nodes experiment.launch.py learner:=sgim-d seed:=3 movements:=5000

It starts the same nodes with the same parameters as `ros_ws/run_experiment.sh`, because both
take them from one graph description (sgim_nodes.graph.description); the arguments are that
script's options. What the script adds stays with it: a reserved ROS domain, metadata.yaml,
resuming, and the human teacher's prompt (with teacher:=human, run
`ros2 run teacher human_input` in a terminal of its own). The run ends when the recorder has
written it; a node that stops before (the simulator excepted: it is restarted) ends it too.

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
)


def node_arguments(arguments: Mapping[str, str]) -> list[tuple[str, dict[str, Any]]]:
    """(node name, keyword arguments of launch_ros.actions.Node) of every node of the run,
    from the graph description; ParameterError (one line per problem) before anything
    starts."""
    from sgim_nodes.graph.description import (
        MAX_RESPAWNS,
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
    output = arguments.get("output") or str(
        Path("runs") / f"{learner}-seed{seed}-{datetime.now(UTC):%Y%m%d-%H%M%S}" / "bag")
    try:
        wait = float(arguments.get("wait_for_teacher", "0"))
    except ValueError:
        raise ParameterError(f"launch argument wait_for_teacher:="
                             f"{arguments['wait_for_teacher']!r} must be seconds") from None
    markers = arguments.get("markers", "true").lower() not in ("false", "0", "no")
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
    return [(spec.name, {"package": spec.package, "executable": spec.executable,
                         "name": spec.executable, "parameters": [values.for_node(spec)],
                         **({"namespace": spec.namespace} if spec.namespace else {}),
                         "output": "screen", "respawn": spec.respawn,
                         "respawn_max_retries": MAX_RESPAWNS if spec.respawn else -1})
            for spec in graph(learner, options.teacher, markers,
                              acts_teachers(values.shared))
            if not spec.interactive]


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
        from sgim_ros import record_key

        arguments = {name: LaunchConfiguration(name).perform(context)
                     for name, _, _ in ARGUMENTS}
        actions: list[Any] = []
        nodes = node_arguments(arguments)
        # The run's secret its simulator signs movements with (sgim_ros/record_key.py), kept
        # beside the bag for the readers and handed to the nodes in their environment.
        key = record_key.new_key()
        bag = Path(dict(nodes)["recorder"]["parameters"][0]["output"])
        bag.parent.mkdir(parents=True, exist_ok=True)
        record_key.write_key(bag.parent, key)
        for name, node_kwargs in nodes:
            node = Node(**node_kwargs, additional_env={record_key.ENV: key})
            actions.append(node)
            # The recorder ends the run once it has written it (after the arbiter's final
            # status); any other node that ends first ends it too, the simulator excepted
            # (launch restarts it).
            if name not in ("sim_bridge", "social_interaction"):
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
