"""Parameters given on a node's command line that the node would silently ignore.

rclpy takes `--ros-args -p NAME:=VALUE` and `--params-file FILE` and simply ignores a name the
node never declares, and rcl reads a parameter file that is a plain string as "no parameters":
a misspelt name then leaves the node on its default without a word. This module finds those
cases so that the node can refuse to start.

Sections of a parameter file are matched as rcl does: `/**` (every node) or a name that ends in
the node's name (`sim_bridge`, `/sim_bridge`, `/**/sim_bridge`, `/ns/sim_bridge`). Names in a
section addressed to this node, and every `-p` name, must be declared by it. Names under `/**`
are shared by a whole graph (the run scripts give every node one file), so a node cannot tell a
typo there from another node's parameter: the launcher checks those against the whole graph.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import yaml

from sgim_ros.params import ParameterError

# Parameters rclpy declares on every node by itself.
ROS_OWN = {"use_sim_time", "start_type_description_service"}
# ROS arguments that take a value we must skip (remaps, logging, enclave).
_WITH_VALUE = {"-r", "--remap", "--log-level", "--log-config-file", "-e", "--enclave",
               "--log-file-name"}


def ros_arguments(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """The `-p` assignments and the parameter files among argv's ROS arguments."""
    assignments: list[str] = []
    files: list[str] = []
    inside = False
    tokens = iter(argv)
    for token in tokens:
        if token == "--ros-args":
            inside = True
        elif token == "--":
            inside = False
        elif inside and token in ("-p", "--param"):
            assignments.append(next(tokens, ""))
        elif inside and token == "--params-file":
            files.append(next(tokens, ""))
        elif inside and token in _WITH_VALUE:
            next(tokens, None)
    return assignments, files


def flatten(parameters: dict[str, Any], prefix: str = "") -> Iterator[str]:
    """Parameter names of a `ros__parameters` mapping (nested mappings join with '.')."""
    for key, value in parameters.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            yield from flatten(value, f"{name}.")
        else:
            yield name


def read_parameter_file(path: str | Path) -> dict[str, dict[str, Any]]:
    """Section name -> its `ros__parameters`, or ParameterError saying what is wrong."""
    try:
        data = yaml.safe_load(Path(path).read_text())
    except OSError as error:
        raise ParameterError(f"parameter file {path}: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise ParameterError(f"parameter file {path} is not valid YAML: "
                             f"{str(error).splitlines()[0]}") from None
    shape = ("must map node names (or /**) to {ros__parameters: {name: value, ...}}")
    if not isinstance(data, dict):
        raise ParameterError(f"parameter file {path} {shape}; it holds a "
                             f"{type(data).__name__}: {str(data)[:60]!r}")
    sections = {}
    for section, body in data.items():
        if not isinstance(body, dict) or not isinstance(body.get("ros__parameters"), dict):
            raise ParameterError(f"parameter file {path}: section {section!r} {shape}")
        extra = sorted(str(k) for k in body if k != "ros__parameters")
        if extra:
            raise ParameterError(f"parameter file {path}: section {section!r} holds "
                                 f"{', '.join(extra)} beside ros__parameters")
        sections[str(section)] = body["ros__parameters"]
    return sections


def addressed_to(section: str, node_name: str) -> bool:
    """True when the section names this node (not a wildcard for every node)."""
    return section.rstrip("/").rsplit("/", 1)[-1] == node_name


def unknown_parameters(node_name: str, declared: set[str], argv: Sequence[str]) -> list[str]:
    """Descriptions of the parameters addressed to this node that it does not declare.

    Raises ParameterError for a parameter file it cannot read as ROS does.
    """
    unknown: list[str] = []
    assignments, files = ros_arguments(argv)
    for assignment in assignments:
        name = assignment.partition(":=")[0]
        target, _, name = name.rpartition(":")
        if (not target or target == node_name) and name not in declared:
            unknown.append(f"'{name}' (-p {assignment})")
    for path in files:
        for section, parameters in read_parameter_file(path).items():
            if not addressed_to(section, node_name):
                continue
            unknown += [f"'{name}' (section {section} of {path})"
                        for name in flatten(parameters) if name not in declared]
    return unknown


def check_command_line(node, argv: Sequence[str]) -> None:
    """ParameterError when argv gives this node a parameter it does not declare."""
    declared = set(node._parameters)  # rclpy has no public list of declared names
    unknown = unknown_parameters(node.get_name(), declared, argv)
    if unknown:
        known = ", ".join(sorted(declared - ROS_OWN))
        raise ParameterError(f"unknown parameter {', '.join(unknown)} for node "
                             f"'{node.get_name()}'; it declares: {known}")
