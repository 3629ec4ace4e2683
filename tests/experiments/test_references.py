"""A page goes stale when its runs would change, and only then (experiments/references.py).

On a scratch copy of the learner's code, with two tiny runner experiments (SAGG-RIAC alone,
random goals alone, on the 7-joint arm): an edit of the core that changes no movement leaves
both fingerprints as they were once the reference runs are made again, and a one-line change
of random goals' behaviour changes the fingerprint of the experiment that runs it, and only
that one. The check says when the kept references are not today's code's.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from sgim_nodes.experiments.pinned import pin_of
from sgim_nodes.provenance.fingerprint import data_files
from tests.conftest import REPO

pytestmark = pytest.mark.slow

EXPERIMENT = """\
    name: {name}
    maker: runner
    pages: [docs/{name}.md]
    runs:
      movements: 120
      eval_every: 60
      seeds: 2
      grid:
        - world: arm-7
          learner: {learner}
    """


def scratch_copy(root: Path) -> Path:
    """The learner's and the world's packages, two experiments and their pages."""
    shutil.copytree(REPO / "sgim_nodes" / "sgim_nodes", root / "sgim_nodes" / "sgim_nodes",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(REPO / "sim_bridge", root / "sim_bridge",
                    ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
    (root / "experiments").mkdir()
    (root / "docs").mkdir()
    pins = "".join(f"  {n}: {pin_of(p)}\n" for n, p in sorted(data_files().items()))
    for name, learner in (("alpha", "saggriac"), ("beta", "random-goals")):
        (root / "experiments" / f"{name}.yaml").write_text(
            textwrap.dedent(EXPERIMENT.format(name=name, learner=learner)) + "data:\n" + pins)
        (root / "docs" / f"{name}.md").write_text(f"# {name}\n")
    return root


def reproduce(root: Path, *argv: str) -> subprocess.CompletedProcess:
    """experiments/cli.py of the scratch copy, on its own experiments."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(root / "sgim_nodes"), str(root / "sim_bridge"), env.get("PYTHONPATH", "")])
    env.pop("SIM_BRIDGE_DATA_DIR", None)
    return subprocess.run([sys.executable, "-m", "sgim_nodes.experiments.cli", *argv],
                          cwd=root, env=env, capture_output=True, text=True, timeout=600)


def fingerprints(said: str) -> dict[str, str]:
    """Experiment -> fingerprint, as `--references` says them."""
    return dict(re.findall(r"\] (\w+): its runs .*\(fingerprint (\w+)\)", said))


def edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1))


def test_pages_go_stale_when_the_runs_change_and_only_then(tmp_path):
    root = scratch_copy(tmp_path)
    made = reproduce(root, "--references")
    assert made.returncode == 0, made.stderr
    assert "alpha: its runs are known" in made.stderr, made.stderr
    first = fingerprints(made.stderr)
    assert set(first) == {"alpha", "beta"} and first["alpha"] != first["beta"]
    core = root / "sgim_nodes" / "sgim_nodes" / "core"

    # A refactor that changes no movement: the check says the references are another code's,
    # and once they are made again both experiments keep their fingerprints.
    edit(core / "competence.py", "    excess = max(0.0, d - success_tolerance)\n",
         "    beyond = max(0.0, d - success_tolerance)\n    excess = beyond\n")
    checked = reproduce(root, "--check")
    assert checked.returncode == 1 and "--references" in checked.stdout, checked.stdout
    again = reproduce(root, "--references")
    assert again.returncode == 0, again.stderr
    for name in ("alpha", "beta"):
        assert f"{name}: its runs do what they did" in again.stderr, again.stderr
    assert fingerprints(again.stderr) == first

    # One line of random goals' behaviour: beta's runs change, alpha's do not.
    edit(core / "learner_registry.py", "UNIFORM_GOALS = (0.0, 1.0, 0.0)",
         "UNIFORM_GOALS = (0.5, 0.5, 0.0)")
    changed = reproduce(root, "--references")
    assert changed.returncode == 0, changed.stderr
    assert "alpha: its runs do what they did" in changed.stderr, changed.stderr
    assert "beta: its runs changed: its pages are stale" in changed.stderr, changed.stderr
    last = fingerprints(changed.stderr)
    assert last["alpha"] == first["alpha"] and last["beta"] != first["beta"]
