"""docs/foxglove_layout.json and docs/markers.md name the topics and fields a run really has."""

from __future__ import annotations

import json
import re

import pytest

from sgim_nodes.bag.types import RECORDED_TOPICS, SOURCE_MSG_DIR, TOPICS, VIEW_TOPICS
from tests.conftest import REPO

DOCS = REPO / "docs"
MARKER_TOPICS = {name for name in VIEW_TOPICS if name.startswith("markers/")}


def _panels(tree) -> list[str]:
    """The panel ids a Foxglove layout tree places (leaves of first/second splits)."""
    if isinstance(tree, str):
        return [tree]
    return _panels(tree["first"]) + _panels(tree["second"])


def _fields(message: str) -> set[str]:
    """The field names of one of the project's .msg files."""
    names = set()
    for line in (SOURCE_MSG_DIR / f"{message}.msg").read_text().splitlines():
        words = line.split("#")[0].split()
        if len(words) >= 2 and "=" not in line.split("#")[0]:
            names.add(words[1])
    return names


def test_the_foxglove_layout_shows_the_runs_own_topics():
    layout = json.loads((DOCS / "foxglove_layout.json").read_text())
    configs = layout["configById"]
    placed = _panels(layout["layout"])
    assert sorted(placed) == sorted(configs)  # every configured panel is on screen, once

    (scene,) = [c for pid, c in configs.items() if pid.startswith("3D!")]
    assert scene["followTf"] == "outcome_space"  # the markers' frame (view/markers.py FRAME)
    shown = {topic.lstrip("/") for topic, v in scene["topics"].items() if v["visible"]}
    assert shown == MARKER_TOPICS

    plots = [c for pid, c in configs.items() if pid.startswith("Plot!")]
    for plot in plots:
        for path in plot["paths"]:
            topic, field = re.fullmatch(r"/([\w/]+)\.(\w+)", path["value"]).groups()
            assert topic in TOPICS, path["value"]
            message = TOPICS[topic].rsplit("/", 1)[1]
            assert field in _fields(message), f"{message} has no field {field}"
    raw = [c["topicPath"].lstrip("/") for pid, c in configs.items()
           if pid.startswith("RawMessages!")]
    assert raw and set(raw) <= set(RECORDED_TOPICS)


@pytest.mark.ros  # view/markers.py builds visualization_msgs
def test_the_markers_doc_lists_every_marker_topic_and_the_frame():
    from sgim_nodes.view.markers import FRAME

    text = (DOCS / "markers.md").read_text()
    documented = set(re.findall(r"^\| `(markers/\w+)` \|", text, re.MULTILINE))
    assert documented == MARKER_TOPICS
    assert f"**`{FRAME}`**" in text
