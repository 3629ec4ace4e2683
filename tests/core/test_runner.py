"""The runner's CLI writes a complete, valid JSON-lines file; the core imports no ROS."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from sgim_nodes.core import runner

ROOT = Path(__file__).resolve().parents[2]


def test_cli_writes_every_movement_and_evaluation(tmp_path):
    out = tmp_path / "sub" / "run.jsonl"
    assert runner.main(["--learner", "sgim-d", "--movements", "60", "--seed", "1",
                        "--env", "planar-arm", "--eval-every", "20", "--output", str(out),
                        "--demonstration-period", "25", "--quiet"]) == 0
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert records[0]["type"] == "header" and records[0]["learner"] == "sgim-d"
    assert records[-1]["type"] == "end"
    moves = [r for r in records if r["type"] == "movement"]
    assert [m["index"] for m in moves] == list(range(60))
    assert {m["label"] for m in moves} <= {"goal_directed", "exploration", "imitation", "random"}
    assert all(len(m["action"]) == 12 and m["status"] == 0 and len(m["outcome"]) == 2
               for m in moves)
    evals = [r for r in records if r["type"] == "evaluation"]
    assert [e["movements"] for e in evals] == [0, 20, 40, 60]
    assert all(len(e["distances"]) == records[0]["n_goals"] for e in evals)
    demos = [r for r in records if r["type"] == "demonstration"]
    assert [d["movement"] for d in demos] == [0, 25, 50]
    assert records[-1]["final_mean_distance"] == evals[-1]["mean_distance"]


def test_cli_says_how_many_demonstrations_the_teacher_gave(tmp_path, capsys):
    out = tmp_path / "run.jsonl"
    assert runner.main(["--learner", "sgim-d", "--movements", "100", "--env", "planar-arm",
                        "--eval-every", "0", "--output", str(out), "--demonstration-period", "25",
                        "--reached-rule", "own-movements", "--tolerance-noise", "0"]) == 0
    records = [json.loads(line) for line in out.read_text().splitlines()]
    demos = [r for r in records if r["type"] == "demonstration"]
    assert len(demos) == records[-1]["n_demonstrations"] == 4  # tolerance 0: never reached
    assert records[-1]["n_teacher_turns"] == 4
    assert records[0]["teacher"] == {"period": 25, "rule": "own-movements",
                                     "choice": "random-unreached", "content": "means-and-goal",
                                     "timing": "period", "tolerance_noise": 0.0}
    assert "4 demonstrations in 4 teacher turns (own-movements rule, period)" in \
        capsys.readouterr().err
    with pytest.raises(SystemExit):
        runner.main(["--reached-rule", "lucky", "--output", str(out)])


def test_same_seed_same_file(tmp_path):
    def movements(path):
        runner.main(["--learner", "saggriac", "--movements", "40", "--seed", "3",
                     "--eval-every", "0", "--output", str(path), "--quiet"])
        return [line for line in path.read_text().splitlines() if '"movement"' in line]

    assert movements(tmp_path / "a.jsonl") == movements(tmp_path / "b.jsonl")


def test_help_and_bad_arguments(capsys):
    with pytest.raises(SystemExit) as e:
        runner.main(["--help"])
    assert e.value.code == 0
    assert "--learner" in capsys.readouterr().out
    with pytest.raises(SystemExit) as e:
        runner.main(["--learner", "nope", "--output", "x"])
    assert e.value.code == 2


def test_core_imports_no_ros():
    code = ("import sys, importlib, pkgutil, sgim_nodes.core as c, sgim_nodes.core.teaching\n"
            "for m in pkgutil.iter_modules(c.__path__): importlib.import_module("
            "'sgim_nodes.core.' + m.name)\n"
            "bad = [m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_runtime_py')]\n"
            "assert not bad, bad\n")
    env_path = [str(ROOT / d) for d in ("sgim_nodes", "teacher", "sim_bridge")]
    subprocess.run([sys.executable, "-c", f"import sys; sys.path[:0] = {env_path!r}\n" + code],
                   check=True)
    for f in (ROOT / "sgim_nodes/sgim_nodes/core").glob("*.py"):
        text = f.read_text()
        assert not re.search(r"^\s*(import|from)\s+rclpy", text, re.M), f
        # the core never reaches up into a node package (the teacher's nodes, our nodes)
        assert not re.search(r"^\s*(import|from)\s+(teacher|sgim_nodes\.nodes)\b", text,
                             re.M), f
