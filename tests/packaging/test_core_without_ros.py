"""The learner as a library: `pip install ./sgim_nodes ./sim_bridge` in a fresh venv without
ROS, by Debian 12's stock pip (23.0.1), gives the core, the fishing world and the `sgim-learn`
command on the venv's PATH, puts no ROS-only or generic command there, leaves no build folder
in the packages' source trees, `sgim-learn --env fishing` learns, and
examples/own_environment.py runs SGIM-D on its own world.

The venv is made from the base interpreter with no system site-packages and an environment
cleared of everything ros_ws/env.sh sets, so nothing of the ROS workspace can leak in; numpy,
scipy, tqdm and pybullet come from the package index (at the versions requirements.txt pins,
so from pip's cache once ./bootstrap.sh has run). The packages are copied first, so that the
builds run on copies whose folders the test can inspect, never in the shared source tree.
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ROS_MODULES = ("rclpy", "sgim_msgs", "sgim_ros", "sim_bridge", "teacher")
# Imports every module of the core, then reports which ROS or node packages came with them.
IMPORT_CORE = f"""
import importlib, pkgutil, sys
import sgim_nodes.core as core
names = [m.name for m in pkgutil.walk_packages(core.__path__, "sgim_nodes.core.")]
for name in names:
    importlib.import_module(name)
leaked = sorted({{m.split(".")[0] for m in sys.modules}} & set({ROS_MODULES!r}))
print(len(names), core.__file__, leaked)
"""

pytestmark = pytest.mark.slow


def clean_env() -> dict[str, str]:
    """The caller's environment without the ROS workspace and the project's venv."""
    drop = ("PYTHON", "AMENT_", "COLCON_", "ROS_", "RMW_", "CMAKE_PREFIX_PATH", "VIRTUAL_ENV",
            "LD_LIBRARY_PATH", "SIM_BRIDGE_")
    return {k: v for k, v in os.environ.items() if not k.startswith(drop)}


def pip_install(python: Path | str, *args: str, cwd: Path, into: Path | None = None) -> None:
    """`python -m pip install ARGS` (into the venv of `into` if given), quiet, under
    requirements.txt's pins.

    --no-compile: byte-compiling numpy and scipy was a third of the set-up, and only .pyc
    files differ; what the test imports is compiled as it is imported.
    """
    where = ["--python", str(into)] if into else []
    subprocess.run([str(python), "-m", "pip", *where, "install", "--quiet",
                    "--no-compile", "--disable-pip-version-check",
                    "-c", str(REPO / "requirements.txt"), *args],
                   check=True, env=clean_env(), cwd=cwd, timeout=400)


PACKAGES = ("sgim_nodes", "sim_bridge")  # what the guide has pip install


@pytest.fixture(scope="module")
def plain_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A venv without ROS where pip 23.0.1 ran `pip install ./sgim_nodes ./sim_bridge` (on
    copies, in root/)."""
    root = tmp_path_factory.mktemp("plain")
    for package in PACKAGES:
        shutil.copytree(REPO / package, root / package,
                        ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build"))
    venv.EnvBuilder(with_pip=False, system_site_packages=False).create(root / "venv")
    python = root / "venv" / "bin" / "python"
    # What a fresh venv on Debian 12 holds: pip 23.0.1 and setuptools, no `wheel`, with which
    # such a pip fell back to `setup.py install` and put the commands in lib/sgim_nodes/
    # (issue 30). The running pip puts them in (`pip --python`: no ensurepip, five seconds),
    # with the core's dependencies, which pip 23 takes a second longer to find in the index.
    # Then the venv's own pip 23.0.1 builds and installs the packages, as a user's would, and
    # finds pybullet from sim_bridge's own requirements.
    pip_install(sys.executable, "pip==23.0.1", "setuptools", "numpy", "scipy", "tqdm",
                into=python, cwd=root)
    pip_install(python, *(f"./{package}" for package in PACKAGES), cwd=root)
    return python


def colcon_commands() -> set[str]:
    """The command names the setup.py files give colcon's build (sgim_nodes' ROS_SCRIPTS,
    sim_bridge's console_scripts): none is for pip."""
    names: set[str] = set()
    tree = ast.parse((REPO / "sgim_nodes" / "setup.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and [getattr(t, "id", None)
                                             for t in node.targets] == ["ROS_SCRIPTS"]:
            names |= {entry.split("=")[0].strip() for entry in ast.literal_eval(node.value)}
    assert names, "sgim_nodes/setup.py has no ROS_SCRIPTS list"
    tree = ast.parse((REPO / "sim_bridge" / "setup.py").read_text(encoding="utf-8"))
    entries = [ast.literal_eval(n) for n in ast.walk(tree) if isinstance(n, ast.Constant)
               and isinstance(n.value, str) and " = sim_bridge." in n.value]
    assert entries, "sim_bridge/setup.py names no command"
    return names | {entry.split("=")[0].strip() for entry in entries}


def run_in(python: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(python), *args], capture_output=True, text=True,
                          env=clean_env(), cwd=python.parent.parent.parent, timeout=300)


def test_venv_has_no_ros(plain_venv: Path) -> None:
    probe = run_in(plain_venv, "-c", "import rclpy")
    assert probe.returncode != 0
    assert "No module named 'rclpy'" in probe.stderr


def test_installed_by_debian_12_pip(plain_venv: Path) -> None:
    """The install ran on the pip that showed the bug, in the set-up that triggered it, and
    each package asks for what it imports (the fixture installed the core's beforehand; pip
    found pybullet from sim_bridge's requirements, at least requirements.txt's pins)."""
    probe = run_in(plain_venv, "-c", "import importlib.metadata as m, importlib.util as u; "
                                     "print(m.version('pip'), u.find_spec('wheel') is None, "
                                     "m.version('pybullet'), *m.requires('sgim_nodes')); "
                                     "print(*m.requires('sim_bridge'))")
    first, world = probe.stdout.splitlines()
    pip, no_wheel, pybullet, *requires = first.split()
    assert (pip, no_wheel) == ("23.0.1", "True"), probe.stderr
    assert {"numpy", "scipy", "tqdm"} <= set(requires)
    pins = dict(re.findall(r"^(numpy|pybullet)==(\S+)$", (REPO / "requirements.txt").read_text(),
                           re.MULTILINE))
    assert {f"{name}>={version}" for name, version in pins.items()} <= set(world.split())
    assert pybullet == pins["pybullet"]


def test_no_build_folder_left_in_the_sources(plain_venv: Path) -> None:
    """pip builds in the package's folder; setup.py sends setuptools' build/ and egg-info to
    a temporary folder, which the build removes."""
    root = plain_venv.parents[2]
    for package in PACKAGES:
        left = sorted(p.name for p in (root / package).iterdir()
                      if p.name == "build" or p.name.endswith(".egg-info"))
        assert not left, (package, left)


def test_core_imports_without_ros(plain_venv: Path) -> None:
    result = run_in(plain_venv, "-c", IMPORT_CORE)
    assert result.returncode == 0, result.stderr
    count, path, leaked = result.stdout.split(maxsplit=2)
    assert int(count) >= 15  # every module of core/, not an empty namespace
    assert Path(path).is_relative_to(plain_venv.parent.parent)  # the installed copy
    assert leaked.strip() == "[]"


def test_only_namespaced_commands_on_path(plain_venv: Path) -> None:
    """pip installs `sgim-` commands into bin/, and none of colcon's generic, ROS-only ones."""
    bin_dir = plain_venv.parent
    ros_only = colcon_commands()
    assert {"learn", "analyze", "replay", "recorder"} <= ros_only
    assert not ros_only & {path.name for path in bin_dir.iterdir()}
    for package in PACKAGES:  # colcon's layout, unused
        assert not (bin_dir.parent / "lib" / package).exists()
    probe = run_in(plain_venv, "-c", "import importlib.metadata as m; print(*(e.name for d in "
                                     f"{PACKAGES!r} for e in m.distribution(d).entry_points "
                                     "if e.group == 'console_scripts'))")
    commands = probe.stdout.split()
    assert "sgim-learn" in commands, probe.stderr
    for command in commands:
        assert command.startswith("sgim-")
        assert (bin_dir / command).is_file()


def test_runner_command_learns(plain_venv: Path) -> None:
    """`sgim-learn`, the single-process runner, runs from the venv's bin/ without ROS."""
    output = plain_venv.parents[2] / "run.jsonl"
    result = subprocess.run([str(plain_venv.parent / "sgim-learn"), "--env", "planar-arm",
                             "--movements", "200", "--output", str(output)],
                            capture_output=True, text=True, env=clean_env(), timeout=300)
    assert result.returncode == 0, result.stderr
    assert "sgim-d: final mean distance" in result.stderr
    records = [json.loads(line) for line in output.read_text().splitlines()]
    header, end = records[0], records[-1]
    assert (header["type"], header["env"], header["movements"]) == ("header", "planar-arm", 200)
    assert sum(r["type"] == "movement" for r in records) == 200
    errors = [(r["movements"], r["mean_distance"]) for r in records if r["type"] == "evaluation"]
    assert [n for n, _ in errors] == [0, 200]
    assert end["type"] == "end" and end["final_mean_distance"] == errors[-1][1]
    assert errors[-1][1] < 0.5 * errors[0][1]  # it learned


def test_runner_learns_on_the_fishing_world(plain_venv: Path) -> None:
    """`sgim-learn --env fishing`: the installed world, with its data sets from the venv's
    share/sim_bridge/data, casts the rod in pybullet without ROS."""
    probe = run_in(plain_venv, "-c", "import sim_bridge, sim_bridge.data_files as d; "
                                     "print(sim_bridge.__file__); print(d.data_dir())")
    assert probe.returncode == 0, probe.stderr
    for path in probe.stdout.splitlines():  # the installed copies, not the source tree's
        assert Path(path).is_relative_to(plain_venv.parents[1]), path
    output = plain_venv.parents[2] / "fishing.jsonl"
    result = subprocess.run([str(plain_venv.parent / "sgim-learn"), "--env", "fishing",
                             "--movements", "20", "--output", str(output)],
                            capture_output=True, text=True, env=clean_env(), timeout=300)
    assert result.returncode == 0, result.stderr
    records = [json.loads(line) for line in output.read_text().splitlines()]
    header, end = records[0], records[-1]
    assert (header["type"], header["env"], header["action_dim"]) == ("header", "fishing", 24)
    moves = [r for r in records if r["type"] == "movement"]
    assert len(moves) == 20 and end["type"] == "end"
    landed = [r for r in moves if r.get("outcome")]
    assert landed and all(len(r["outcome"]) == 2 for r in landed)  # hooks on the water
    # The same world as the project's: its venv, from the source tree, makes the same casts.
    mine = plain_venv.parents[2] / "fishing-project.jsonl"
    subprocess.run([sys.executable, "-m", "sgim_nodes.core.runner", "--env", "fishing",
                    "--movements", "20", "--output", str(mine)], check=True,
                   capture_output=True, cwd=REPO, timeout=300)
    assert moves == [r for r in map(json.loads, mine.read_text().splitlines())
                     if r["type"] == "movement"]


def test_example_learns_on_its_own_world(plain_venv: Path) -> None:
    result = run_in(plain_venv, str(REPO / "examples" / "own_environment.py"),
                    "--movements", "500")
    assert result.returncode == 0, result.stderr
    curve = [(int(n), float(e)) for n, e in
             re.findall(r"after\s+(\d+) movements: mean error ([\d.]+)", result.stdout)]
    assert [n for n, _ in curve] == [0, 250, 500]
    summary = re.search(r"first error ([\d.]+), final error ([\d.]+), (\d+) demonstrations",
                        result.stdout)
    assert summary, result.stdout
    first, final, demonstrations = float(summary[1]), float(summary[2]), int(summary[3])
    assert (first, final) == (curve[0][1], curve[-1][1])
    # The teacher took part (a turn at 0, 150, 300 and 450, each with an unreached goal
    # while the learner is this young) and the learner got much better at its goals.
    assert 1 <= demonstrations <= 4
    assert final < 0.5 * first
