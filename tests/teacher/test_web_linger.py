"""--web-linger: after a web-taught run, the launcher keeps the graph up while the web teacher
keeps its page for the person looking at it (the page died with the run)."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

pytestmark = pytest.mark.ros  # the run's description reads the nodes' parameters


def _args(*argv: str):
    from sgim_nodes.graph.experiment_options import parse_args

    return parse_args(list(argv))


def test_web_linger_is_a_run_option_that_reaches_the_web_teacher(tmp_path, capsys):
    from sgim_nodes.graph.description import RunOptions, parameters
    from sgim_nodes.graph.plan import plan_new

    plan = plan_new(_args("sgim-d", "--teacher", "web", "--runs-dir", str(tmp_path),
                          "--name", "web"))
    plan.lock.release()
    web = {spec.name: spec for spec in plan.nodes}["web_teacher"]
    assert plan.values.for_node(web)["linger"] == 600.0  # the default
    # How long a page stays does not change what the learner does.
    assert "linger" not in str(plan.meta["fingerprint"])
    for given, expected in ((["--web-linger", "0"], 0.0), (["--web-linger", "2.5"], 2.5)):
        args = _args("sgim-d", "--teacher", "web", *given)
        values = parameters(RunOptions("sgim-d", teacher="web", web_linger=args.web_linger))
        assert values.shared["linger"] == expected
    for bad in ("-1", "inf", "nan"):
        with pytest.raises(SystemExit):
            _args("sgim-d", "--teacher", "web", "--web-linger", bad)
        assert "--web-linger must be a number of seconds >= 0" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        _args("--resume", "runs/x", "--web-linger", "5")
    assert "--web-linger cannot be given with --resume" in capsys.readouterr().err


class Node:
    """A web teacher as the launcher sees it: a process, and the files it keeps."""

    def __init__(self, tmp_path: Path) -> None:
        self.address = tmp_path / "web_teacher.url"
        self.lingering = tmp_path / "web_teacher.linger"
        self.address.write_text("http://127.0.0.1:1/\n")
        self.process = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])

    def plan(self, linger: float) -> SimpleNamespace:
        return SimpleNamespace(address_file=self.address,
                               values=SimpleNamespace(shared={"linger": linger}))

    def later(self, seconds: float, *actions) -> None:
        def act() -> None:
            time.sleep(seconds)
            for action in actions:
                action()
        threading.Thread(target=act, daemon=True).start()

    def close(self) -> None:
        self.process.kill()
        self.process.wait()


@pytest.fixture
def node(tmp_path):
    n = Node(tmp_path)
    yield n
    n.close()


def _timed(plan, node) -> float:
    from sgim_nodes.graph.experiment import keep_page

    start = time.monotonic()
    keep_page(plan, node.process)
    return time.monotonic() - start


def test_the_launcher_waits_while_the_page_lingers_and_no_longer(node, capsys):
    # The node heard the end with a page open: it lingers until the person closes it.
    node.later(0.2, lambda: node.lingering.write_text("http://127.0.0.1:1/\n"),
               node.address.unlink)
    node.later(0.7, node.lingering.unlink)
    assert 0.6 < _timed(node.plan(600.0), node) < 5.0
    assert "its page stays for at most 600 s" in capsys.readouterr().err


def test_the_launcher_does_not_wait_for_a_page_nobody_looks_at(node):
    node.later(0.2, node.address.unlink)  # heard the end, no page open: no linger file
    assert _timed(node.plan(600.0), node) < 2.0
    node.address.write_text("x")
    assert _timed(node.plan(0.0), node) < 0.1  # --web-linger 0: as before
    node.process.kill()
    node.process.wait()
    assert _timed(node.plan(600.0), node) < 0.5  # a node gone says nothing more
