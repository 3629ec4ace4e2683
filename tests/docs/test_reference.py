"""docs/reference.md is what the code declares (regenerated, it must not change), and what it
is generated from agrees with itself and with nodes built for real."""

from __future__ import annotations

import difflib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.ros

PAGE = REPO / "docs" / "reference.md"
# Who answers each kind of endpoint: a subscription nobody publishes is a misspelt name.
COUNTERPART = {"subscribes": "publishes", "publishes": "subscribes", "calls": "serves",
               "serves": "calls", "action client": "action server",
               "action server": "action client"}
# Nodes whose constructors run here with their defaults (human_input wants a terminal and
# web_teacher a port; their endpoints are read by the same scan).
BUILT = ("sgim_nodes.nodes.recorder", "sim_bridge.sim_bridge_node", "sgim_nodes.nodes.evaluator",
         "sgim_nodes.nodes.markers", "sgim_nodes.nodes.interest_computer",
         "sgim_nodes.nodes.goal_generator", "sgim_nodes.nodes.low_level_explorer",
         "sgim_nodes.nodes.imitation", "teacher.teacher_node",
         "sgim_nodes.nodes.social_interaction")


@pytest.fixture(scope="module")
def found():
    from sgim_nodes.graph.description import NODES
    from sgim_nodes.graph.endpoints import endpoints

    return {spec.name: endpoints(spec) for spec in NODES.values()}


def test_the_reference_page_is_what_the_code_declares():
    from sgim_nodes.graph.reference import COMMAND, render

    current, expected = PAGE.read_text(encoding="utf-8"), render()
    if current != expected:
        diff = list(difflib.unified_diff(current.splitlines(), expected.splitlines(),
                                         "docs/reference.md", "generated", lineterm="", n=0))
        pytest.fail(f"docs/reference.md is out of date: run {COMMAND}\n"
                    + "\n".join(diff[:20]))


def test_the_recorder_records_every_topic_a_node_publishes(found):
    """Two declarations of the topics, made apart: the publishers' calls and the recorder's
    table (bag.types)."""
    from sgim_nodes.bag.types import RECORDED_TOPICS

    published = {(e.name.removeprefix("/"), e.type) for ends in found.values() for e in ends
                 if e.kind == "publishes"}
    assert published == set(RECORDED_TOPICS.items())


def test_every_endpoint_has_its_counterpart(found):
    # The graph's nodes live in the root namespace, where "x" and "/x" are one topic; an
    # expert, in its own namespace, names the run's topics absolutely.
    have = {(e.kind, e.name.removeprefix("/"), e.type) for ends in found.values() for e in ends}
    alone = [f"{node} {e.kind} {e.name} ({e.type})" for node, ends in found.items()
             for e in ends
             if (COUNTERPART[e.kind], e.name.removeprefix("/"), e.type) not in have]
    assert not alone


def test_built_nodes_create_what_the_scan_reads(found, ros_domain, tmp_path):
    """The scan reads calls; here the constructors run (no spinning) and rclpy lists what they
    made: everything the scan found unconditionally, nothing it did not find. Actions are not
    listed by rclpy (the pairing test above covers their names)."""
    from sgim_nodes.graph.description import NODES

    child = subprocess.run(
        [sys.executable, str(Path(__file__).with_name("live_endpoints.py")),
         str(tmp_path / "bag"), *BUILT],
        capture_output=True, text=True, timeout=300, env=dict(os.environ), cwd=tmp_path)
    assert child.returncode == 0, child.stderr[-3000:]
    live = json.loads(child.stdout.splitlines()[-1])
    by_module = {spec.params_module: spec.name for spec in NODES.values()}
    for module in BUILT:
        scanned = [e for e in found[by_module[module]]
                   if e.kind in ("publishes", "subscribes", "serves", "calls")]
        made = {tuple(pair) for pair in live[module]}
        sure = {(e.kind, e.name) for e in scanned if not (e.condition or e.note)}
        assert sure <= made, (module, sure - made)
        assert made <= {(e.kind, e.name) for e in scanned}, (module, made)


def test_a_learner_parameter_is_described_by_its_config_docstring():
    from sgim_nodes.graph.reference import _description
    from sgim_nodes.nodes.ros_glue import learner_params

    undescribed = [p.name for p in learner_params() if _description(p) == p.description]
    assert not undescribed


FAKE_HELPERS = '''
from rclpy.node import Node
from sgim_msgs.srv import RecorderReady


def serve(node: Node, service: str):
    return node.create_service(RecorderReady, service, None)


class Jobs:
    def __init__(self, node, kind, name):
        from rclpy.action import ActionServer

        self.server = ActionServer(node, kind, name, execute_callback=None)
'''
FAKE_NODE = '''"""fake: a node for the reference's own tests.

Not in any run."""
from rclpy.node import Node
from sgim_msgs.action import Imitate
from sgim_msgs.msg import Movement
from sgim_ros import qos
from sgim_ros.params import Param, positive
from fakepkg.helpers import Jobs, serve

PARAMS = (Param("speed", 1.0, "how fast it goes", positive, read_only=False),)


class FakeNode(Node):
    def __init__(self, asks: bool) -> None:
        super().__init__("fake")
        self.create_publisher(Movement, "moves", qos.RECORDS)
        if asks:
            self.create_subscription(Movement, "asks", print, qos.LATEST_STATE)
        serve(self, "fake_ready")
        Jobs(self, Imitate, "copy")
'''
FAKE_LOOP = '''
from rclpy.node import Node
from sgim_msgs.msg import Movement


class LoopNode(Node):
    def __init__(self) -> None:
        super().__init__("loop")
        for name in ("a", "b"):
            self.create_publisher(Movement, name, 10)
'''


@pytest.fixture
def fake_package(tmp_path, monkeypatch):
    """A package `fakepkg` in the tree the scan reads, importable for its PARAMS."""
    from sgim_nodes.graph import endpoints

    package = tmp_path / "fakepkg"
    package.mkdir()
    for name, text in (("__init__", ""), ("helpers", FAKE_HELPERS), ("node", FAKE_NODE),
                       ("loop", FAKE_LOOP)):
        (package / f"{name}.py").write_text(text)
    monkeypatch.setitem(endpoints.SOURCES, "fakepkg", tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    endpoints._module.cache_clear()
    yield package
    endpoints._module.cache_clear()
    for name in [m for m in sys.modules if m.split(".")[0] == "fakepkg"]:
        del sys.modules[name]


def test_the_scan_follows_helpers_and_keeps_the_nodes_conditions(fake_package):
    from sgim_nodes.graph.description import NodeSpec
    from sgim_nodes.graph.endpoints import Endpoint, endpoints

    assert endpoints(NodeSpec("fakepkg", "fake", "fakepkg.node")) == [
        Endpoint("publishes", "moves", "sgim_msgs/msg/Movement", "RECORDS"),
        Endpoint("subscribes", "asks", "sgim_msgs/msg/Movement", "LATEST_STATE", "asks"),
        Endpoint("serves", "fake_ready", "sgim_msgs/srv/RecorderReady"),
        Endpoint("action server", "copy", "sgim_msgs/action/Imitate"),
    ]


def test_a_name_computed_at_run_time_stops_the_scan(fake_package):
    from sgim_nodes.graph.description import NodeSpec
    from sgim_nodes.graph.endpoints import ComputedName, endpoints

    with pytest.raises(ComputedName, match=r"loop\.py:10: .*endpoints\.DYNAMIC"):
        endpoints(NodeSpec("fakepkg", "loop", "fakepkg.loop"))


def test_a_page_of_one_node(fake_package):
    from sgim_nodes.graph.description import NodeSpec
    from sgim_nodes.graph.reference import COMMAND, render

    page = render([NodeSpec("fakepkg", "fake", "fakepkg.node")])
    assert page.startswith(f"*Generated by `{COMMAND}`")
    assert "### fake\n\nfake: a node for the reference's own tests.\n" in page
    assert "- in the graph of: no run (started by hand)" in page
    assert "| `speed` | `1.0` | > 0 | no |  | how fast it goes |" in page
    assert ("| subscribes | `asks` | [`sgim_msgs/msg/Movement`](#msgmovement) | LATEST_STATE "
            "| `asks` |") in page
    assert "| `moves` | [`sgim_msgs/msg/Movement`](#msgmovement) | RECORDS | fake |  |" in page


def test_an_interface_file_becomes_its_prose_and_field_tables(tmp_path):
    from sgim_nodes.graph.reference import interface

    path = tmp_path / "srv" / "Ask.srv"
    path.parent.mkdir()
    path.write_text("# Ask something.\n# Twice.\n\nuint8 LOUD = 1   # shouted\n"
                    "# The question:\nstring text \"hi\"  # what is asked,\n"
                    "                  # on two lines\n---\nbool ok  # answered | not\n")
    assert interface(path) == [
        "### srv/Ask", "", "Ask something. Twice.", "", "**Request**", "",
        "| field | type | value / default | comment |", "|---|---|---|---|",
        "| `LOUD` | `uint8` | `1` | shouted |", "", "The question:", "",
        "| field | type | value / default | comment |", "|---|---|---|---|",
        "| `text` | `string` | `\"hi\"` | what is asked, on two lines |", "",
        "**Response**", "",
        "| field | type | value / default | comment |", "|---|---|---|---|",
        "| `ok` | `bool` |  | answered \\| not |", ""]


def test_check_fails_with_the_command_that_regenerates(tmp_path, monkeypatch, capsys):
    from sgim_nodes.graph import reference

    monkeypatch.setattr(reference, "render", lambda: "the page\n")
    page = tmp_path / "reference.md"
    assert reference.main(["--check", str(page)]) == 1  # missing
    assert capsys.readouterr().err == f"{page} is out of date: run {reference.COMMAND}\n"
    assert reference.main(["--write", str(page)]) == 0
    assert page.read_text() == "the page\n"
    assert reference.main(["--check", str(page)]) == 0
