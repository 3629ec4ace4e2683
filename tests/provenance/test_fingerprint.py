"""The learner fingerprint: what changes a run changes it, and nothing else does."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from sgim_nodes.provenance import fingerprint as fp
from sgim_nodes.provenance.record import Provenance


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


def test_source_digest_ignores_comments_and_docstrings_not_code(tmp_path):
    base = '''\
        """Module doc."""
        def f(x):
            """Doc."""
            return x + 1  # a comment

        class Config:
            """Class doc."""
            width: float = 0.05
            """Field doc."""
            if True:
                """Text in a branch."""
        '''
    a = _write(tmp_path, "a.py", base)
    first = fp.source_digest([a])
    _write(tmp_path, "a.py", base.replace("Doc.", "Other words.").replace("a comment", "c")
           .replace("Field doc.", "Other.").replace("Text in", "Words in"))
    assert fp.source_digest([a]) == first
    _write(tmp_path, "a.py", base.replace("0.05", "0.2"))
    assert fp.source_digest([a]) != first
    _write(tmp_path, "a.py", base.replace("x + 1", "x + 2"))
    assert fp.source_digest([a]) != first
    _write(tmp_path, "a.py", base)
    b = _write(tmp_path, "b.py", "y = 1\n")
    assert fp.source_digest([a, b]) != first  # a new module counts


def test_environment_holds_code_world_data_and_versions():
    env = fp.environment()
    assert set(env) == set(fp.ENVIRONMENT_FIELDS)
    assert all(len(env[k]) == 16 for k in ("code", "world", "data"))
    import numpy

    assert env["numpy"] == numpy.__version__


def test_a_python_patch_release_gives_the_same_versions_a_minor_one_does_not(monkeypatch):
    """Machines differ in Python's patch release (Debian 12 has 3.11.2): a run made on one
    is today's run on the other, and the kept references stay valid."""
    import platform

    monkeypatch.setattr(platform, "python_version_tuple", lambda: ("3", "11", "2"))
    debian = fp.library_versions()
    monkeypatch.setattr(platform, "python_version_tuple", lambda: ("3", "11", "7"))
    assert fp.library_versions() == debian and debian["python"] == "3.11"
    monkeypatch.setattr(platform, "python_version_tuple", lambda: ("3", "12", "1"))
    assert fp.library_versions() != debian


def test_the_same_parameters_give_the_same_value_whatever_their_order():
    a = fp.fingerprint({"x": 1, "nested": {"b": 2.0, "a": [1, 2]}})
    b = fp.fingerprint({"nested": {"a": [1, 2], "b": 2.0}, "x": 1})
    assert a.value == b.value and not a.differences(b)
    c = fp.fingerprint({"x": 1, "nested": {"b": 2.5, "a": [1, 2]}})
    assert c.value != a.value and a.differences(c) == ["parameters (b)"]


def test_differences_name_the_fields_and_the_parameters():
    a = fp.fingerprint({"node": {"zeta": 50, "seedless": 1}})
    other_env = {**a.fields, "numpy": "1.0", "code": "0" * 16}
    b = fp.Fingerprint({**other_env, "parameters": fp.fingerprint(
        {"node": {"zeta": 20, "seedless": 1}, "teacher": {"p": 1}}).fields["parameters"]},
        {"node": {"zeta": 20, "seedless": 1}, "teacher": {"p": 1}})
    assert a.differences(b) == ["code", "numpy", "parameters (node teacher, zeta)"]
    again = fp.Fingerprint.from_dict(b.to_dict())
    assert again is not None and again.value == b.value and not again.differences(b)
    assert fp.Fingerprint.from_dict(None) is None
    assert fp.Fingerprint.from_dict({"value": "abc"}) is None


def test_a_recorded_python_patch_release_reads_as_its_minor_release():
    today = fp.fingerprint({"x": 1})
    assert today.fields["python"].count(".") == 1
    older = {**today.to_dict(), "fields": {**today.fields,
                                           "python": today.fields["python"] + ".7"}}
    read = fp.Fingerprint.from_dict(older)
    assert read is not None and read.value == today.value and not read.differences(today)
    other = {**today.to_dict(), "fields": {**today.fields, "python": "2.7.18"}}
    assert fp.Fingerprint.from_dict(other).differences(today) == ["python"]


@pytest.mark.ros
def test_a_graph_runs_fingerprint_depends_on_what_shapes_it_only():
    from sgim_nodes.graph.description import RunOptions, fingerprint, graph, parameters

    def of(learner="sgim-d", **kw):
        overrides = kw.pop("overrides", {})
        options = RunOptions(learner, overrides=overrides, **kw)
        return fingerprint(parameters(options), graph(learner))

    base = of(seed=0, output="/tmp/a")
    assert of(seed=7, output="/tmp/b", storage="sqlite3").value == base.value
    assert of(seed=0, output="/tmp/a", overrides={"service_timeout": 99.0}).value == base.value
    # how patient the nodes are (read-only, but operational) does not make another learner
    patient = {"startup_timeout": 600.0, "settle_time": 9.0, "map_timeout": 300.0}
    assert of(overrides=patient).value == base.value
    assert of(overrides={"zeta": 20}).differences(base) == ["parameters (zeta)"]
    assert of(demonstration_period=50).differences(base) == ["parameters (demonstration_period)"]
    assert of(movements=1000).value != base.value
    assert "node teacher" in of("saggriac").differences(base)[0]
    # what it was made from is readable, by node, without the per-run names
    assert "seed" not in base.parameters["low_level_explorer"]
    assert base.parameters["low_level_explorer"]["zeta"] == 50


def test_the_provenance_block_reads_back():
    p = Provenance.now("ros_ws/reproduce.sh study", "study", "f" * 16, fp.environment(), 3725,
                       ["a note"])
    text = f"# Title\n\n{p.markdown()}\n\nprose"
    assert Provenance.parse(text) == p
    assert "1 h 02 min on" in text and "| note | a note |" in text
    assert Provenance.parse("no block here") is None


def test_a_reports_own_pages_and_figures_do_not_make_the_tree_dirty(tmp_path):
    """The study report draws its figures and writes one page before the next page's block is
    made: those writes are the command's output, not a change of the code that made it."""
    import subprocess

    from sgim_nodes.provenance.record import git_state

    def git(*args: str) -> None:
        subprocess.run(["git", "-C", str(tmp_path), *args], check=True, capture_output=True)

    (tmp_path / "docs" / "figures").mkdir(parents=True)
    for name in ("code.py", "docs/results.md", "docs/figures/curve.png"):
        (tmp_path / name).write_text("before\n")
    git("init", "-q")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qam", "x", "--allow-empty")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "files")
    outputs = ["docs/results.md", "docs/figures"]
    (tmp_path / "docs" / "results.md").write_text("after\n")
    (tmp_path / "docs" / "figures" / "curve.png").write_text("after\n")
    assert git_state(tmp_path, outputs)[1] is False
    assert git_state(tmp_path)[1] is True
    (tmp_path / "code.py").write_text("after\n")
    assert git_state(tmp_path, outputs)[1] is True


OWN_MODULES_SCRIPT = """
import sys
from sgim_nodes.core.runner import main
from sgim_nodes.provenance.fingerprint import LEARNER_MODULES
learner, output, extra = sys.argv[1], sys.argv[2], sys.argv[3:]
code = main(["--env", "planar-arm", "--learner", learner, "--movements", "40",
             "--eval-every", "20", "--seed", "3", "--quiet", "--output", output, *extra])
loaded = {m.rsplit(".", 1)[-1] for m in sys.modules if m.startswith("sgim_nodes.core.")}
for owner, names in LEARNER_MODULES.items():
    print(owner, sorted(loaded & set(names)))
sys.exit(code)
"""


@pytest.mark.parametrize("learner, extra, group", [
    ("sgim-d", [], ()), ("demo-only", [], ()), ("sgim-acts", [], ("sgim-acts",)),
    ("sgim-d", ["--teacher-turns", "west,east,rough"], ("sgim-acts",))])
def test_the_optional_modules_are_imported_by_the_runs_that_count_them(learner, extra, group,
                                                                      tmp_path):
    """The claim that lets work on SGIM-ACTS leave the other learners' pages fresh: a run
    imports the modules of LEARNER_MODULES' groups that module_groups gives it, and no other,
    so the others cannot change it."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", OWN_MODULES_SCRIPT, learner,
                           str(tmp_path / "run.jsonl"), *extra], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    loaded = dict(line.split(" ", 1) for line in done.stdout.splitlines() if line)
    options = {"teacher_turns": extra[1]} if extra else {}
    assert fp.module_groups(fp.runner_parameters("planar-arm", learner, {}, options)) == group
    for owner, names in fp.LEARNER_MODULES.items():
        imported = set(eval(loaded[owner]))
        assert imported <= set(names) and bool(imported) == (owner in group), imported


def test_only_the_learners_own_code_is_in_its_learner_code_field():
    own = fp.fingerprint(fp.runner_parameters("planar-arm", "sgim-acts", {}, {}))
    other = fp.fingerprint(fp.runner_parameters("planar-arm", "sgim-d", {}, {}))
    assert other.fields["learner_code"] == "" and len(own.fields["learner_code"]) == 16
    assert other.fields["code"] == own.fields["code"] == fp.environment()["code"]
    assert own.differences(other) == ["learner_code", "parameters (learner)"]
    shared = {p.stem for p in fp.shared_core_files()}
    assert "runner" in shared and not shared & set(fp.LEARNER_MODULES["sgim-acts"])
    assert fp.learner_of({"arbiter": {"learner": "sgim-d"}, "simulator": {}}) == "sgim-d"
    with pytest.raises(ValueError, match="several learners"):
        fp.learner_of({"a": {"learner": "sgim-d"}, "b": {"learner": "random"}})


def test_a_parameter_only_another_learner_reads_is_left_out():
    """SGIM-ACTS's `teachers` is declared by nodes every learner runs, and read by its own
    runs only: it shapes the fingerprint of those alone."""
    def shaping(learner: str) -> dict:
        values = {"goal_generator": {"learner": learner, "teachers": "a,b", "zeta": 50}}
        return fp.graph_parameters(values, {"goal_generator": ["learner", "teachers", "zeta"]})

    assert shaping("sgim-d") == {"goal_generator": {"learner": "sgim-d", "zeta": 50}}
    assert shaping("sgim-acts")["goal_generator"]["teachers"] == "a,b"


def test_a_graph_run_counts_its_nodes_code_and_a_runners_keeps_its_value(tmp_path, monkeypatch):
    """A node edited locally changes what a graph run does: its fingerprint must change with
    it (so a sweep makes the run again), while a docstring edit must not; a runner's run has
    no node code and keeps the value it had before node code counted."""
    import importlib
    import sys

    package = tmp_path / "scratch_nodes"
    package.mkdir()
    (package / "__init__.py").write_text("")
    node = package / "imitation.py"
    node.write_text('"""Imitation."""\nSIGMA = 0.02\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    monkeypatch.setattr(fp, "GRAPH_PACKAGES", ("scratch_nodes",))

    def graph_run() -> fp.Fingerprint:
        fp.graph_code.cache_clear()
        return fp.fingerprint({"explorer": {"zeta": 50}}, graph=True)

    made = graph_run()
    node.write_text('"""Imitation, with a longer docstring."""\nSIGMA = 0.02  # noise\n')
    assert graph_run().value == made.value
    node.write_text('"""Imitation."""\nSIGMA = 0.01\n')
    edited = graph_run()
    assert edited.differences(made) == ["graph_code"]
    runner = fp.fingerprint({"explorer": {"zeta": 50}})
    assert "graph_code" not in runner.fields
    assert runner.value == fp._digest(f"{k}={runner.fields.get(k, '')}".encode()
                                      for k in fp.FIELDS if k != "graph_code")
    sys.modules.pop("scratch_nodes", None)
    fp.graph_code.cache_clear()


def test_the_graphs_node_code_covers_every_node_module():
    """Every module a graph node is made from counts (the world's own modules count in
    ``world``)."""
    names = {(f.parent.name, f.stem) for f in fp.graph_files()}
    for module in ("imitation", "low_level_explorer", "social_interaction", "recorder"):
        assert ("nodes", module) in names
    assert ("teacher", "teacher_node") in names and ("sgim_ros", "record_key") in names
    assert ("sim_bridge", "sim_bridge_node") in names
    assert ("sim_bridge", "fishing_world") not in names
