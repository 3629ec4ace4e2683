"""Several nodes of the graph in one process, on one executor (composition).

    ros2 run sgim_nodes composed --process light \\
        --node recorder=sgim_nodes.nodes.recorder --node markers=sgim_nodes.nodes.markers \\
        --ros-args --params-file run/params.yaml

Each node is named as the launcher knows it (a namespace before the last slash:
``centre/expert=teacher.expert_node``) and given by the module that declares its ``ENTRY``; each
reads its own section of the parameter files. The run launcher groups the nodes so
(graph/processes.py, ``process_plan``); see docs/node_graph.md, "Processes".
"""

from __future__ import annotations

import argparse
import importlib
import sys

from sgim_ros.host import Member, NodeEntry, run_nodes


def parse(argv: list[str]) -> argparse.Namespace:
    own = argv[: argv.index("--ros-args")] if "--ros-args" in argv else argv
    parser = argparse.ArgumentParser(
        prog="composed", description="Run several nodes of the graph in one process, on one "
        "rclpy EventsExecutor; ROS arguments (a parameter file) follow --ros-args.")
    parser.add_argument("--process", required=True, help="the process's name, for its "
                        "messages and profile")
    parser.add_argument("--node", action="append", required=True, metavar="NAME=MODULE",
                        help="a node: its name (namespace/name for a namespaced one) and the "
                        "module that declares its ENTRY; repeat, in the order to start them")
    parser.add_argument("--ends-fd", type=int, metavar="FD", help="an inherited pipe to "
                        "write 'NAME CODE' to as each node ends (the run launcher reads it)")
    return parser.parse_args(own)


def member(spec: str) -> Member:
    """NAME=MODULE -> its member; ValueError saying what is wrong."""
    name, _, module = spec.partition("=")
    if not name or not module:
        raise ValueError(f"--node {spec!r}: give NAME=MODULE")
    try:
        entry = importlib.import_module(module).ENTRY
    except (ImportError, AttributeError) as error:
        raise ValueError(f"--node {spec!r}: {module} declares no node ENTRY ({error})") from None
    if not isinstance(entry, NodeEntry):
        raise ValueError(f"--node {spec!r}: {module}.ENTRY is not a NodeEntry")
    return Member(name, entry)


def main(args: list[str] | None = None) -> int:
    argv = sys.argv if args is None else args
    options = parse(argv[1:])
    try:
        members = [member(spec) for spec in options.node]
    except ValueError as error:
        print(f"[{options.process}] {error}", file=sys.stderr, flush=True)
        return 2
    names = [m.name for m in members]
    if len(set(names)) != len(names):
        print(f"[{options.process}] a node is named twice: {', '.join(names)}",
              file=sys.stderr, flush=True)
        return 2
    return run_nodes(options.process, members, argv, options.ends_fd)


if __name__ == "__main__":
    raise SystemExit(main())
