"""Reference runs: a page's fingerprint is what its runs do, not the source that does it.

Why: hashing the source made every page stale at any refactor, even one that changes no
movement, and remaking them costs hours. Here each distinct configuration an experiment pins
(its runs less their seeds) has a reference run: one seed, a short budget that still passes
every path the configuration uses (the teacher's turns, imitation, requests, evaluations),
made the way the experiment makes its runs (through the graph for a graph experiment, so that
a node's change shows too). The digest of its movements and evaluations stands for the
configuration; an experiment's fingerprint is made of these digests, its runs' names and its
data files (``experiment_fingerprint``). An experiment that runs no learner (the world maker)
is fingerprinted by the world's source alone.

Making the reference runs takes minutes, so their digests are kept in
experiments/references.yaml beside the pages, under the key of what can change them
(``maker_key``: the sources of the maker's code path by syntax tree, the libraries' versions
and the data files). While the key is today's, the check reads the digests (cheap); when it is
not, the check says so and ``ros_ws/reproduce.sh --references`` makes them again, then says
which experiments' behaviour changed. What this cannot see is in docs/guide.md
("How a page knows it is fresh").
"""

from __future__ import annotations

import ast
import dataclasses
import hashlib
import subprocess
import tempfile
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from functools import cache
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from sgim_nodes.provenance import fingerprint as fp

REPO = Path(__file__).resolve().parents[3]
REFERENCE_SEED = 0
REFERENCE_MOVEMENTS = 400
"""Movements of a reference run, or more: one teacher's turn and its imitation past the
period (REFERENCE_AFTER_TURN), never more than the experiment's own budget."""
REFERENCE_AFTER_TURN = 100
REFERENCE_EVALUATIONS = 2  # evaluations in a reference run, the last at its end
TABLE_NAME = "references.yaml"
WORLD_JOB_MODULES = ("bezier", "data_files", "fishing_world", "lake", "rod_urdf", "scaling")
"""The sim_bridge modules a world experiment's casts run through."""


NOT_RUN_CODE = ("reference.py",)
"""Modules of graph/ that no run goes through (the generated reference page's)."""


class ReferencesOutdated(RuntimeError):
    """The kept reference digests are not today's code's; the message says what to run."""


# --- what can change a maker's runs --------------------------------------------------------

def maker_sources(maker: str) -> list[Path]:
    """The source files of this checkout that a maker's runs go through; an edit of any of
    them may change a run, so it makes the kept references another key's. Read from the
    checkout, not from where Python imports them (a build folder, an installed copy)."""
    package = REPO / "sgim_nodes" / "sgim_nodes"
    bridge = REPO / "sim_bridge" / "sim_bridge"
    world = [bridge / f"{name}.py" for name in fp.WORLD_MODULES]
    experiments = package / "experiments"
    if maker == "world":  # casts of FishingWorld, not the learner's World around it
        cast = [path for path in world if path.stem in WORLD_JOB_MODULES]
        return [*cast, experiments / "world_jobs.py", experiments / "world_probes.py"]
    core = sorted((package / "core").glob("*.py"))
    if maker == "runner":
        return [*core, *world, experiments / "runner_jobs.py", experiments / "probes.py"]
    launcher = [path for path in (package / "graph").glob("*.py")
                if path.name not in NOT_RUN_CODE]
    graph = [*(package / "nodes").glob("*.py"), *launcher,
             *(package / "bag").glob("*.py"), *(REPO / "teacher" / "teacher").rglob("*.py"),
             *(REPO / "sgim_msgs" / "sgim_ros").glob("*.py"), *bridge.glob("*.py")]
    return sorted({*core, *world, *graph})


def sources_digest(files: Iterable[Path]) -> str:
    """The files' code by syntax tree (comments and docstrings do not count), each named by
    its path in the checkout, in the order of those names."""
    parts = []
    for path in files:
        tree = fp._without_docstrings(ast.parse(path.read_text(encoding="utf-8")))
        parts.append(path.relative_to(REPO).as_posix().encode() + b"\0"
                     + ast.dump(tree).encode())
    return fp._digest(sorted(parts))


def interface_files() -> list[Path]:
    """The message, service and action definitions the graph's nodes talk in."""
    root = REPO / "sgim_msgs"
    return sorted(p for kind in ("msg", "srv", "action") for p in (root / kind).glob("*"))


@cache
def maker_key(maker: str) -> str:
    """What the kept references of this maker were made by: its sources by syntax tree (the
    graph's interfaces by content), the libraries' versions and the data files."""
    env = fp.environment()
    parts = [sources_digest(maker_sources(maker))]
    if maker == "graph":
        parts += [f"{p.name}:{fp.file_digest(p)}" for p in interface_files()]
    parts += [f"{k}={env[k]}" for k in ("data", *fp.LIBRARIES, "python")]
    return fp._digest(part.encode() for part in parts)


# --- the kept digests ----------------------------------------------------------------------

def table_path(experiments_dir: Path) -> Path:
    return experiments_dir / TABLE_NAME


def read_table(path: Path) -> dict[str, Any]:
    """The kept references: maker -> {key, runs: config -> digest}, and aliases."""
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}
    return data if isinstance(data, dict) else {}


HEADER = """\
# What the pinned experiments' runs do, by reference runs (experiments/references.py): for each
# maker, the key of the code that made them and one digest per configuration (a run less its
# seed); aliases name page fingerprints of code that behaved the same. Written by
# `ros_ws/reproduce.sh --references`; read by `ros_ws/reproduce.sh --check`. Do not edit.
"""


def write_table(path: Path, table: Mapping[str, Any]) -> None:
    text = HEADER + yaml.safe_dump(dict(table), sort_keys=True, default_flow_style=False)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def kept_digests(entry: Mapping[str, Any]) -> dict[str, str]:
    """A maker's entry of the table: configuration id -> the digest of its reference run."""
    return {str(k): str(v) for k, v in (entry.get("runs") or {}).items()}


def check_todays(table: Mapping[str, Any], maker: str) -> None:
    """ReferencesOutdated unless the maker's kept references are today's code's."""
    entry = table.get(maker) or {}
    today = maker_key(maker)
    if entry.get("key") != today:
        raise ReferencesOutdated(
            f"the {maker} experiments' reference runs were made by other code (key "
            f"{entry.get('key') or 'none'}, today {today}): `ros_ws/reproduce.sh --references` "
            "makes them again and says which experiments' runs changed")


# --- configurations and their reference runs -----------------------------------------------

def configurations(experiment: Any) -> dict[str, str]:
    """Run name -> its configuration's id (the digest of its shaping parameters, which leave
    out the seed): runs that differ only by seed share one reference run."""
    if experiment.maker == "graph":
        from sgim_nodes.sweep.sweep_file import spec_fingerprint

        return {s.name: spec_fingerprint(s).fields["parameters"] for s in experiment.graph_runs}
    jobs = experiment.runner_jobs if experiment.maker == "runner" else experiment.world_jobs
    return {job.name: job.fingerprint().fields["parameters"] for job in jobs}


def reference_length(movements: int, period: int | None) -> tuple[int, int]:
    """(movements, eval_every) of a reference run: REFERENCE_MOVEMENTS, or one turn of the
    teacher past its period, within the experiment's budget; evaluated twice."""
    length = max(REFERENCE_MOVEMENTS, (period or 0) + REFERENCE_AFTER_TURN)
    length = min(length, movements)
    return length, max(1, length // REFERENCE_EVALUATIONS)


def reference_specs(experiment: Any) -> dict[str, Any]:
    """Configuration id -> the run (a graph RunSpec or a RunnerJob) that stands for it."""
    first: dict[str, Any] = {}
    runs = experiment.graph_runs if experiment.maker == "graph" else experiment.runner_jobs
    for run, config in zip(runs, configurations(experiment).values(), strict=True):
        if config in first:
            continue
        movements, every = reference_length(run.movements,
                                            getattr(run, "demonstration_period", None))
        first[config] = dataclasses.replace(run, seed=REFERENCE_SEED, movements=movements,
                                            eval_every=every)
    return first


def digest_arrays(parts: Iterable[Any]) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(np.ascontiguousarray(np.asarray(part, dtype="<f8")).tobytes())
        h.update(b"|")
    return h.hexdigest()[:20]


def graph_reference(spec: Any, work: Path, name: str, timeout: float = 900.0) -> str:
    """Make one reference run through the graph, in ``work/name``, and give its digest
    (bag_digest). RuntimeError naming the run when it fails."""
    argv = [str(REPO / "ros_ws" / "run_experiment.sh"), *spec.argv(), "--runs-dir", str(work),
            "--name", name, "--quiet", "--no-markers", "--timeout", str(timeout)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout + 120)
    if done.returncode != 0:
        raise RuntimeError(f"the reference run {' '.join(spec.argv())} failed (exit "
                           f"{done.returncode}): {(done.stderr or done.stdout).strip()[-400:]}")
    return bag_digest(work / name / "bag")


def bag_digest(bag: Path) -> str:
    """The digest of a graph run's movements (action, process, status, outcome) and
    evaluations (movement, mean distance, where each goal's cast came down)."""
    from sgim_nodes.bag.reader import load_run

    run = load_run(bag, ["movements", "evaluations"])
    parts: list[Any] = []
    for m in run.movements:
        parts += [m.action, [m.process, m.status], m.outcome if m.status == 0 else []]
    for e in run.evaluations:
        parts += [[e.movement_index, e.mean_distance], e.reached]
    return digest_arrays(parts)


def runner_reference(job: Any) -> str:
    """Make one reference run with the runner: the digest of everything its result holds
    but its timing and its own description."""
    from sgim_nodes.experiments.runner_jobs import run_job

    result = run_job(job)
    kept = {k: v for k, v in result.items() if k not in ("seconds", "fingerprint", "job")}
    return hashlib.sha256(fp.canonical(kept).encode()).hexdigest()[:20]


def make_references(experiments: Iterable[Any], table: dict[str, Any], parallel: int,
                    say: Callable[[str], None]) -> dict[str, Any]:
    """The table with today's references of these experiments' makers: a maker whose key is
    today's keeps its digests and makes only configurations it lacks; another key's are all
    made again."""
    by_maker: dict[str, dict[str, Any]] = {}
    for exp in experiments:
        if exp.maker != "world":
            by_maker.setdefault(exp.maker, {}).update(reference_specs(exp))
    new = dict(table)
    for maker in ("world", *sorted(by_maker)):
        key = maker_key(maker)
        entry = table.get(maker) or {}
        runs = kept_digests(entry) if entry.get("key") == key else {}
        todo = {c: s for c, s in by_maker.get(maker, {}).items() if c not in runs}
        if todo:
            say(f"{maker}: {len(todo)} reference run(s) to make, {parallel} side by side")
        runs.update(_make(maker, todo, parallel, say))
        new[maker] = {"key": key, **({"runs": runs} if maker != "world" else {})}
    return new


def _make(maker: str, todo: Mapping[str, Any], parallel: int,
          say: Callable[[str], None]) -> dict[str, str]:
    if not todo:
        return {}
    made: dict[str, str] = {}
    configs, specs = list(todo), list(todo.values())
    with tempfile.TemporaryDirectory(prefix="sgim-references-") as work:
        if maker == "graph":  # each run is processes of its own: threads wait for them
            pool: Any = ThreadPoolExecutor(parallel)
            digests = pool.map(lambda c, s: graph_reference(s, Path(work), f"reference-{c}"),
                               configs, specs)
        else:  # the runner computes in this process: spawned processes, not threads
            pool = ProcessPoolExecutor(parallel, mp_context=get_context("spawn"))
            digests = pool.map(runner_reference, specs)
        with pool:
            for config, spec, digest in zip(configs, specs, digests, strict=True):
                made[config] = digest
                say(f"{maker}: reference of {config} ({spec.learner}) made")
    return made


# --- an experiment's fingerprint -----------------------------------------------------------

def experiment_fingerprint(experiment: Any, table: Mapping[str, Any],
                           todays: bool = True) -> str:
    """What the experiment's runs do: for each run (by its name, seed included), the reference
    digest of its configuration (the world's source for a world experiment), and its data
    files. A configuration's id only says which runs share a reference run: a change that
    renames a configuration but leaves its runs' movements alone (a node that leaves a graph
    it did nothing in) leaves the fingerprint as it was. ReferencesOutdated when the kept
    references are not today's code's (``todays``; without it, what the table's code did) or
    lack a configuration."""
    runs = reference_digests(experiment, table, todays)
    return fp._digest([fp.canonical(sorted(runs.items())).encode(),
                       fp.canonical(dict(experiment.data)).encode()])


def run_behaviours(experiment: Any, table: Mapping[str, Any], todays: bool = True
                   ) -> dict[str, str]:
    """Run name -> what that one run does: its configuration's reference digest and the data
    files. A shipped run (experiments/shipped.py) stands for today's run while this holds."""
    data = fp.canonical(dict(experiment.data)).encode()
    return {name: fp._digest([digest.encode(), data])
            for name, digest in reference_digests(experiment, table, todays).items()}


def reference_digests(experiment: Any, table: Mapping[str, Any], todays: bool = True
                      ) -> dict[str, str]:
    """Run name -> the reference digest of its configuration (see experiment_fingerprint)."""
    configs = configurations(experiment)
    entry = table.get(experiment.maker) or {}
    if todays:
        check_todays(table, experiment.maker)
    elif not entry.get("key"):
        raise ReferencesOutdated(f"no reference of the {experiment.maker} experiments is kept")
    if experiment.maker == "world":
        return {name: str(entry.get("key")) for name in configs}
    digests = kept_digests(entry)
    missing = sorted(set(configs.values()) - set(digests))
    if missing:
        raise ReferencesOutdated(
            f"{experiment.name}: {len(missing)} configuration(s) have no reference run "
            "yet: `ros_ws/reproduce.sh --references` makes them")
    return {name: digests[config] for name, config in configs.items()}


def aliases_of(table: Mapping[str, Any], experiment: str) -> dict[str, str]:
    """Page fingerprint -> the behaviour fingerprint of the code that made it."""
    found = (table.get("aliases") or {}).get(experiment) or {}
    return {str(k): str(v) for k, v in found.items()}
