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

`BriefParser` is the argparse parser of every command of the project: a refusal is the one
line that says what is wrong, not the usage before it.

Every parameter file is read here, by the nodes and by the launcher alike (`read_parameter_file`,
and `parse_yaml` for a sweep file or a `--param` value): UTF-8 YAML, where a key given twice
in one mapping is refused (PyYAML and rcl would silently keep the last) and so is an alias
(rcl refuses them). Each problem is one line naming the file, the line and the key.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, NoReturn

import yaml

from sgim_ros.clip import value_text
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


def flat_items(parameters: dict[str, Any], prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(name, value) of a `ros__parameters` mapping, nested mappings joined with '.'."""
    for key, value in parameters.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            yield from flat_items(value, f"{name}.")
        else:
            yield name, value


def flatten(parameters: dict[str, Any], prefix: str = "") -> Iterator[str]:
    """Parameter names of a `ros__parameters` mapping (nested mappings join with '.')."""
    for name, _value in flat_items(parameters, prefix):
        yield name


def shown(text: object) -> str:
    """A path or an argument in a message, kept on one line (repr if it holds a newline or
    another character that does not print)."""
    text = str(text)
    return text if text.isprintable() else repr(text)


def one_line(text: str) -> str:
    """`text` with its unprintable characters escaped: a newline or a carriage return in an
    argument quoted as given would split the line that says what was refused."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class BriefParser(argparse.ArgumentParser):
    """argparse, whose refusal is one line, `PROG: error: MESSAGE (see PROG --help)`, exit
    code 2: argparse's own prints the whole usage first (a dozen lines for the launcher), and
    the line that matters is lost under it. Subcommands' parsers are of this class too."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")


class YamlProblem(ValueError):
    """Why a text is not YAML that a parameter file (or a value) may hold; one line."""


class StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing what rcl reads otherwise or not at all: a key given
    twice in one mapping (both keep the last without a word) and an alias (rcl refuses it)."""

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise YamlProblem(f"line {event.start_mark.line + 1}: an alias (*{event.anchor}): "
                              "ROS does not read aliases")
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            self.flatten_mapping(node)
            seen: dict[Any, int] = {}
            for key_node, _value in node.value:
                key = self.construct_object(key_node, deep=True)
                line = key_node.start_mark.line + 1
                try:
                    first = seen.get(key)
                except TypeError:
                    continue  # an unhashable key: the base class refuses it
                if first is not None:
                    raise YamlProblem(f"line {line}: key {_key(key)} given twice (first at "
                                      f"line {first}); ROS would silently keep the last")
                seen[key] = line
        return super().construct_mapping(node, deep)


def _key(key: Any) -> str:
    return value_text(key, 60)


def parse_yaml(text: str | bytes) -> Any:
    """The YAML document `text` (bytes: must be UTF-8), or YamlProblem saying why not."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as error:
            line = text[:error.start].count(b"\n") + 1
            raise YamlProblem(f"not UTF-8 text (byte 0x{text[error.start]:02x} at line "
                              f"{line}): it must be a YAML text file") from None
    try:
        return yaml.load(text, Loader=StrictLoader)  # a SafeLoader: no Python objects
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        problem = error.problem or error.context or "unreadable"
        raise YamlProblem(f"not valid YAML: {problem}{where}") from None
    except yaml.YAMLError as error:
        raise YamlProblem(f"not valid YAML: {str(error).splitlines()[0]}") from None
    except RecursionError:
        raise YamlProblem("not valid YAML: nested too deeply") from None
    except YamlProblem:
        raise
    except (ValueError, OverflowError) as error:  # a date that does not exist: 2020-13-45
        raise YamlProblem(f"not valid YAML: {error}") from None


def read_yaml_file(path: str | Path, what: str = "parameter file") -> Any:
    """The YAML document of a file, or ParameterError: one line naming `what`, the file and,
    where there is one, the line."""
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        raise ParameterError(f"{what} {shown(path)}: {error.strerror or error}") from None
    except ValueError as error:  # a NUL character in the path
        raise ParameterError(f"{what} {shown(path)}: not a usable path ({error})") from None
    try:
        return parse_yaml(data)
    except YamlProblem as problem:
        raise ParameterError(f"{what} {shown(path)}: {problem}") from None


def read_parameter_file(path: str | Path) -> dict[str, dict[str, Any]]:
    """Section name -> its `ros__parameters`, or ParameterError saying what is wrong."""
    data = read_yaml_file(path)
    path = shown(path)
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
        seen: set[str] = set()
        for name in flatten(body["ros__parameters"]):
            if name in seen:  # {a.b: 1, a: {b: 2}}: two spellings of one name
                raise ParameterError(f"parameter file {path}: section {section!r} gives "
                                     f"parameter {name!r} twice")
            seen.add(name)
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
