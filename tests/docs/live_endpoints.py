"""Build nodes of the graph in this process and print what they created, as JSON.

Run by tests/docs/test_reference.py in a child process (rclpy's default context, which the
node classes use, stays out of the test process): `python live_endpoints.py OUTPUT MODULE...`
with OUTPUT the recorder's bag directory. Nothing spins: only the constructors run.
"""

from __future__ import annotations

import inspect
import json
import sys

import rclpy
from rclpy.node import Node

# What rclpy gives every node (its log, its parameter events and services): not the graph's.
EVERY_NODES = {"rosout", "parameter_events"}
PARAMETER_SERVICES = {"describe_parameters", "get_parameter_types", "get_parameters",
                      "get_type_description", "list_parameters", "set_parameters",
                      "set_parameters_atomically"}


def created(node: Node) -> list[tuple[str, str]]:
    """(kind, relative name) of every topic and service the node made, rclpy's left out."""
    rclpy_made = EVERY_NODES | {f"{node.get_name()}/{s}" for s in PARAMETER_SERVICES}
    found = [("publishes", p.topic_name) for p in node.publishers]
    found += [("subscribes", s.topic_name) for s in node.subscriptions]
    found += [("serves", s.srv_name) for s in node.services]
    found += [("calls", c.srv_name) for c in node.clients]
    return sorted({(kind, name.lstrip("/")) for kind, name in found
                   if name.lstrip("/") not in rclpy_made})


def main(output: str, modules: list[str]) -> None:
    import importlib

    rclpy.init(args=["--ros-args", "-p", f"output:={output}"])
    result = {}
    for name in modules:
        module = importlib.import_module(name)
        node_class, = (c for _, c in inspect.getmembers(module, inspect.isclass)
                       if issubclass(c, Node) and c.__module__ == name)
        node = node_class()
        result[name] = created(node)
    print(json.dumps(result))
    rclpy.shutdown()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
