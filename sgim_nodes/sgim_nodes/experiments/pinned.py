"""A pinned experiment: one file under experiments/ that fixes everything that makes its runs.

Why: a page's figures must be remade by today's code from a file under version control, and a
reader must be able to tell whether they still are. The file names its runs (learners, every
non-default parameter, seeds, movements, evaluation), the world's data files by content, the
pages it writes, and how its runs are made:

- ``graph``: through the node graph, one run_experiment per run, as a sweep file says them
  (sweep/sweep_file.py: ``runs`` is a sweep document), here or on Ray;
- ``runner``: the single-process runner (core/runner.py), for worlds the graph does not have
  (the analytic arms) and for measurements inside the learner (experiments/runner_jobs.py);
- ``world``: casts of random actions, no learner (experiments/world_jobs.py).

Its fingerprint says what its runs do: the digests of reference runs of its configurations,
its runs' names (which carry the seeds) and its data files (experiments/references.py). A page
made from it is fresh while today's checkout gives the same one.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass, fields
from functools import cached_property
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.provenance import fingerprint as fp

REPO = Path(__file__).resolve().parents[3]
EXPERIMENTS = REPO / "experiments"
RUNS_ROOT = REPO / "runs" / "experiments"
MAKERS = ("graph", "runner", "world")
KEYS = ("name", "title", "maker", "pages", "report", "data", "runs", "run_timeout")


def runs_root() -> Path:
    """Where experiments' runs go (SGIM_EXPERIMENT_RUNS, else runs/experiments)."""
    import os

    return Path(os.environ.get("SGIM_EXPERIMENT_RUNS") or RUNS_ROOT)


class ExperimentError(ValueError):
    """An experiment file that cannot be used; the message names the file and the key."""


class _StrictLoader(yaml.SafeLoader):
    """YAML where a key given twice is an error, not the last one silently winning."""


def _mapping(loader: _StrictLoader, node: yaml.MappingNode) -> dict:
    seen: set = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node)
        if key in seen:
            raise ExperimentError(f"line {key_node.start_mark.line + 1}: the key {key!r} is "
                                  "given twice")
        seen.add(key)
    return loader.construct_mapping(node)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)


def read_yaml(path: Path) -> Any:
    try:
        text = Path(path).read_text(encoding="utf-8")
        return yaml.load(text, Loader=_StrictLoader)  # a SafeLoader underneath
    except OSError as error:
        raise ExperimentError(f"cannot read {path}: {error.strerror}") from None
    except UnicodeDecodeError:
        raise ExperimentError(f"{path}: not UTF-8 text") from None
    except yaml.YAMLError as error:
        raise ExperimentError(f"{path}: not valid YAML: {error}") from None
    except ExperimentError as error:
        raise ExperimentError(f"{path}: {error}") from None


@dataclass(frozen=True)
class Experiment:
    path: Path
    name: str
    title: str
    maker: str
    pages: tuple[str, ...]
    report: str
    data: Mapping[str, str]
    runs: Mapping[str, Any]
    run_timeout: float | None = None

    @property
    def runs_dir(self) -> Path:
        return runs_root() / self.name

    @cached_property
    def graph_runs(self):
        """The sweep's RunSpecs (graph maker)."""
        from sgim_nodes.sweep.sweep_file import SweepFileError, expand

        try:
            return expand(dict(self.runs), f"{self.path}: runs")
        except SweepFileError as error:
            raise ExperimentError(str(error)) from None

    @cached_property
    def runner_jobs(self):
        """The runner's jobs (runner maker)."""
        from sgim_nodes.experiments.runner_jobs import expand_jobs

        try:
            return expand_jobs(self.runs, str(self.path))
        except ValueError as error:
            raise ExperimentError(str(error)) from None

    @cached_property
    def world_jobs(self):
        from sgim_nodes.experiments.world_jobs import expand_jobs

        try:
            return expand_jobs(self.runs, str(self.path))
        except ValueError as error:
            raise ExperimentError(str(error)) from None

    def run_fingerprints(self) -> dict[str, str]:
        """Run name -> the learner fingerprint today's checkout gives it."""
        if self.maker == "graph":
            from sgim_nodes.sweep.sweep_file import spec_fingerprint

            return {spec.name: spec_fingerprint(spec).value for spec in self.graph_runs}
        jobs = self.runner_jobs if self.maker == "runner" else self.world_jobs
        return {job.name: job.fingerprint().value for job in jobs}

    @property
    def references_path(self) -> Path:
        """The kept reference digests of the experiments of this folder (references.py)."""
        from sgim_nodes.experiments.references import table_path

        return table_path(self.path.parent)

    def fingerprint(self, table: Mapping[str, Any] | None = None, todays: bool = True) -> str:
        """What its runs do (references.py): the digests of its configurations' reference
        runs, its runs' names and its data files. ReferencesOutdated when the kept digests
        (``table``, else the folder's references.yaml) are not today's code's."""
        from sgim_nodes.experiments.references import experiment_fingerprint, read_table

        return experiment_fingerprint(self, read_table(self.references_path)
                                      if table is None else table, todays)

    def source_fingerprint(self) -> str:
        """The fingerprint of its runs' sources, as pages were stamped before reference runs:
        its runs' learner fingerprints and names (which carry the seeds)."""
        runs = self.run_fingerprints()
        return fp._digest([fp.canonical(sorted(runs.items())).encode(),
                           fp.canonical(dict(self.data)).encode()])

    def data_problems(self) -> list[str]:
        """How the checkout's data files differ from the ones the file pins."""
        found = {name: pin_of(path) for name, path in fp.data_files().items()}
        problems = []
        for name in sorted(set(found) | set(self.data)):
            if name not in self.data:
                problems.append(f"{name} is not pinned (its content: {found[name]})")
            elif name not in found:
                problems.append(f"{name} is pinned but the world has no such file")
            elif found[name] != self.data[name]:
                problems.append(f"{name} is {found[name]}, the file pins {self.data[name]}")
        return problems


def pin_of(path: Path) -> str:
    """How an experiment file pins a data file: its content's hash, as a string YAML keeps."""
    return f"sha256:{fp.file_digest(path)}"


def load(path: str | Path) -> Experiment:
    """Read and check an experiment file (its runs are expanded when asked for)."""
    path = Path(path)
    doc = read_yaml(path)
    if not isinstance(doc, Mapping):
        raise ExperimentError(f"{path}: expected a mapping at the top")
    unknown = sorted(map(str, set(doc) - set(KEYS)))
    if unknown:
        raise ExperimentError(f"{path}: unknown key(s) {', '.join(unknown)}; the keys are "
                              f"{', '.join(KEYS)}")
    missing = [k for k in ("name", "maker", "pages", "data", "runs") if k not in doc]
    if missing:
        raise ExperimentError(f"{path}: missing {', '.join(missing)}")
    name = doc["name"]
    if name != path.stem:
        raise ExperimentError(f"{path}: name {name!r} must be the file's name ({path.stem!r})")
    if doc["maker"] not in MAKERS:
        raise ExperimentError(f"{path}: maker must be one of {', '.join(MAKERS)}")
    pages = doc["pages"]
    if (not isinstance(pages, list) or not pages
            or not all(isinstance(p, str) and (REPO / p).is_file() for p in pages)):
        raise ExperimentError(f"{path}: pages must list existing pages of the repository, "
                              f"got {pages!r}")
    data = doc["data"]
    if not isinstance(data, Mapping) or not all(isinstance(v, str) for v in data.values()):
        raise ExperimentError(f"{path}: data must map each data file to its content hash")
    if not isinstance(doc["runs"], Mapping):
        raise ExperimentError(f"{path}: runs must be a mapping")
    timeout = doc.get("run_timeout")
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, int | float)
                                or timeout <= 0):
        raise ExperimentError(f"{path}: run_timeout must be a number of seconds > 0")
    return Experiment(path, name, str(doc.get("title", name)), doc["maker"], tuple(pages),
                      str(doc.get("report", name)), dict(data), dict(doc["runs"]), timeout)


def all_experiments(folder: Path | None = None) -> list[Experiment]:
    return [load(p) for p in experiment_files(folder or EXPERIMENTS)]


def experiment_files(folder: Path) -> list[Path]:
    """The experiment files of a folder: every YAML file but the kept reference digests."""
    from sgim_nodes.experiments.references import TABLE_NAME

    return [p for p in sorted(folder.glob("*.yaml")) if p.name != TABLE_NAME]


def find(name: str, folder: Path | None = None) -> Experiment:
    folder = folder or EXPERIMENTS
    path = folder / f"{name}.yaml"
    if not path.is_file() or path not in experiment_files(folder):
        known = ", ".join(p.stem for p in experiment_files(folder))
        raise ExperimentError(f"no experiment {name!r} (experiments/: {known})")
    return load(path)


def product(block: Mapping[str, Any], axes: tuple[str, ...]) -> list[dict[str, Any]]:
    """The cartesian product of a block's listed axes (a scalar is a one-value axis)."""
    lists = [block[a] if isinstance(block[a], list) else [block[a]] for a in axes]
    return [dict(zip(axes, values, strict=True)) for values in itertools.product(*lists)]


def dataclass_fields(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in fields(cls))
