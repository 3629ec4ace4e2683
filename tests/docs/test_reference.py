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
# web_teacher a port; their endpoints are declared alike).
BUILT = ("sgim_nodes.nodes.recorder", "sim_bridge.sim_bridge_node", "sgim_nodes.nodes.evaluator",
         "sgim_nodes.nodes.markers", "sgim_nodes.nodes.interest_computer",
         "sgim_nodes.nodes.goal_generator", "sgim_nodes.nodes.low_level_explorer",
         "sgim_nodes.nodes.imitation", "teacher.teacher_node",
         "sgim_nodes.nodes.social_interaction")


@pytest.fixture(scope="module")
def found():
    from sgim_nodes.graph.description import NODES

    return {spec.name: list(spec.interfaces) for spec in NODES.values()}


def test_the_reference_page_is_what_the_code_declares():
    from sgim_nodes.graph.reference import COMMAND, render

    current, expected = PAGE.read_text(encoding="utf-8"), render()
    if current != expected:
        diff = list(difflib.unified_diff(current.splitlines(), expected.splitlines(),
                                         "docs/reference.md", "generated", lineterm="", n=0))
        pytest.fail(f"docs/reference.md is out of date: run {COMMAND}\n"
                    + "\n".join(diff[:20]))


def test_the_recorder_records_every_topic_a_node_publishes(found):
    """The recorder subscribes to the topic table; the publishers declare their own."""
    from sgim_ros.interfaces import RECORDED_TOPICS

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


def test_built_nodes_create_what_they_declare(found, ros_domain, tmp_path):
    """The constructors run (no spinning) and rclpy lists what they made: every endpoint the
    node declares without a condition, nothing it does not declare. Actions are not listed by
    rclpy (the pairing test above covers their names)."""
    from sgim_nodes.graph.description import NODES

    child = subprocess.run(
        [sys.executable, str(Path(__file__).with_name("live_endpoints.py")),
         str(tmp_path / "bag"), *BUILT],
        capture_output=True, text=True, timeout=300, env=dict(os.environ), cwd=tmp_path)
    assert child.returncode == 0, child.stderr[-3000:]
    live = json.loads(child.stdout.splitlines()[-1])
    by_module = {spec.params_module: spec.name for spec in NODES.values()}
    for module in BUILT:
        declared = [e for e in found[by_module[module]]
                    if e.kind in ("publishes", "subscribes", "serves", "calls")]
        made = {tuple(pair) for pair in live[module]}
        sure = {(e.kind, e.name.lstrip("/")) for e in declared if not e.conditional}
        assert sure <= made, (module, sure - made)
        assert made <= {(e.kind, e.name.lstrip("/")) for e in declared}, (module, made)


def test_nodes_make_endpoints_only_from_their_declarations():
    """No node module or helper calls rclpy's create_* itself: an endpoint made outside
    Endpoint.create would be missing from the reference and from the checks above."""
    import ast

    creators = {"create_publisher", "create_subscription", "create_service", "create_client",
                "ActionServer", "ActionClient"}
    folders = [REPO / "sgim_nodes" / "sgim_nodes" / "nodes", REPO / "teacher" / "teacher",
               REPO / "sim_bridge" / "sim_bridge"]
    found = []
    for path in (p for folder in folders for p in folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                func = node.func
                name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
                if name in creators:
                    found.append(f"{path.relative_to(REPO)}:{node.lineno} {name}")
    assert not found


def test_a_learner_parameter_is_described_by_its_config_docstring():
    from sgim_nodes.graph.reference import _description
    from sgim_nodes.nodes.ros_glue import learner_params

    undescribed = [p.name for p in learner_params() if _description(p) == p.description]
    assert not undescribed


FAKE_NODE = '''"""fake: a node for the reference's own tests.

Not in any run."""
from sgim_ros.interfaces import action_server, declared, publishes, serves, subscribes
from sgim_ros.params import Param, positive

PARAMS = (Param("speed", 1.0, "how fast it goes", positive, read_only=False),)
INTERFACES = declared(publishes("movements"), subscribes("region_map", "it asks"),
                      serves("fake_ready"), action_server("imitate"))
'''


@pytest.fixture
def fake_package(tmp_path, monkeypatch):
    """A package `fakepkg` in the tree the reference reads, importable for its PARAMS and
    INTERFACES."""
    from sgim_nodes.graph import reference

    package = tmp_path / "fakepkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "node.py").write_text(FAKE_NODE)
    monkeypatch.setitem(reference.SOURCES, "fakepkg", tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield package
    for name in [m for m in sys.modules if m.split(".")[0] == "fakepkg"]:
        del sys.modules[name]


def test_a_declaration_is_typed_by_the_tables_and_refused_when_unknown():
    from sgim_ros.interfaces import (
        Endpoint,
        UnknownEndpoint,
        action_client,
        calls,
        publishes,
        subscribes,
    )

    assert publishes("markers/regions").qos == "LATEST_STATE"
    assert subscribes("markers/regions", keep_all=True).qos == "LATEST_STATE, keep-all"
    assert subscribes("/help_requests").type == "sgim_msgs/msg/HelpRequest"
    assert calls("/centre/expert_ready").type == "sgim_msgs/srv/RecorderReady"
    assert action_client("reach_goal").type == "sgim_msgs/action/ReachGoal"
    with pytest.raises(UnknownEndpoint, match=r"'movement'.*no such topic"):
        publishes("movement")
    with pytest.raises(UnknownEndpoint, match="kind must be one of"):
        Endpoint("listens", "movements")


def test_a_node_made_under_another_name_is_refused():
    from sgim_ros.interfaces import UnknownEndpoint, calls

    with pytest.raises(UnknownEndpoint, match="not the declared calls 'expert_ready'"):
        calls("expert_ready").create(object(), name="/centre/teacher_ready")


def test_an_endpoint_declared_twice_is_listed_once():
    from sgim_ros.interfaces import declared, publishes, subscribes

    assert declared(subscribes("goals"), subscribes("goals", "an expert"),
                    publishes("goals", "a"), (publishes("goals", "b"),)) == (
        publishes("goals", "a or b"), subscribes("goals"))


def test_a_page_of_one_node(fake_package):
    from sgim_nodes.graph.description import NodeSpec
    from sgim_nodes.graph.reference import COMMAND, render

    page = render([NodeSpec("fakepkg", "fake", "fakepkg.node")])
    assert page.startswith(f"*Generated by `{COMMAND}`")
    assert "### fake\n\nfake: a node for the reference's own tests.\n" in page
    assert "- in the graph of: no run (started by hand)" in page
    assert "| `speed` | `1.0` | > 0 | no |  | how fast it goes |" in page
    assert ("| subscribes | `region_map` | [`sgim_msgs/msg/RegionMap`](#msgregionmap) "
            "| LATEST_STATE | it asks |") in page
    assert ("| `movements` | [`sgim_msgs/msg/Movement`](#msgmovement) | RECORDS | fake |  |"
            in page)


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
