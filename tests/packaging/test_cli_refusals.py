"""A command refusing its command line says so in one line, `PROG: error: MESSAGE (see PROG
--help)`, exit code 2, without argparse's usage before it; and no command shows pybullet's
build-time line."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys

import pytest

from tests.conftest import REPO

ONE_LINE = re.compile(r"^(\S[^:]*): error: .+ \(see \1 --help\)$")
# (module, its parsing function, a refused argument list)
COMMANDS = [
    ("sgim_nodes.graph.experiment_options", "parse_args", ["sgim-d", "--movements", "x"]),
    ("sgim_nodes.core.runner", "parse_args", ["--movements", "-1"]),
    ("sgim_nodes.graph.batch", "parse_args", ["--bogus"]),
    ("sgim_nodes.sweep.driver", "parse_args", ["--bogus"]),
    ("sgim_nodes.experiments.cli", "parse_args", ["--bogus"]),
    ("sgim_nodes.analysis.cli", "parse_args", ["--bogus"]),
    ("sgim_nodes.bag.replay", "main", ["bag", "--rate", "x"]),
    ("sgim_nodes.bag.rebuild", "main", ["--bogus"]),
    ("sgim_nodes.bag.repair", "main", ["--bogus"]),
    ("sgim_nodes.graph.reference", "main", ["--bogus"]),
    ("sim_bridge.tools.render_cast", "main", ["--size", "1"]),
    ("sim_bridge.tools.make_floor", "main", ["--bogus"]),
    ("sim_bridge.tools.make_teaching_set", "main", ["--bogus"]),
    ("sim_bridge.tools.map_reachable", "main", ["--bogus"]),
    ("sim_bridge.tools.make_benchmark_set", "main", ["--bogus"]),
]


@pytest.mark.parametrize(("module", "function", "argv"), COMMANDS,
                         ids=[c[0].rsplit(".", 1)[-1] for c in COMMANDS])
def test_a_refused_command_line_is_one_line(module, function, argv, capsys):
    parse = getattr(importlib.import_module(module), function)
    with pytest.raises(SystemExit) as stop:
        parse(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2, err
    assert "usage:" not in err
    assert len(err.splitlines()) == 1 and ONE_LINE.match(err.strip()), err


def test_an_argument_with_a_newline_is_refused_on_one_line(capsys):
    from sgim_nodes.graph.experiment_options import parse_args

    with pytest.raises(SystemExit):
        parse_args(["sgim-d", "--seed", "1\n2"])
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "'1\\n2'" in err, err


def test_a_command_that_imports_pybullet_shows_only_its_own_line():
    """render_cast imports the world (pybullet) before it parses its command line."""
    done = subprocess.run([sys.executable, "-m", "sim_bridge.tools.render_cast", "--size", "1"],
                          capture_output=True, text=True, timeout=60, cwd=REPO)
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr == ("render_cast: error: argument --size: size must be WIDTHxHEIGHT, "
                           "got '1' (see render_cast --help)\n")


def test_what_else_is_written_while_pybullet_loads_is_kept_in_order():
    script = ("import sys\nprint('before', file=sys.stderr)\n"
              "from sim_bridge.fishing_world import FishingWorld\n"
              "print('after', file=sys.stderr)\nprint('out')\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=60, cwd=REPO)
    assert done.returncode == 0, done.stderr
    assert (done.stderr, done.stdout) == ("before\nafter\n", "out\n")
