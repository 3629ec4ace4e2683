"""The sweep file: settings in YAML, expanded into one ``RunSpec`` per run.

    # sgim_nodes/config/sweeps/example.yaml
    runs_dir: runs/example        # results directory (relative to the repository)
    movements: 1000               # every setting at the top applies to every block below
    seeds: 3                      # 0, 1, 2; or a list [0, 4]; or {first: 10, count: 5}
    grid:                         # a list of blocks; each block is a cartesian product
      - learner: [saggriac, demo-only]
      - learner: sgim-d
        demonstration_period: [50, 150, 500]  # the paper's P -> --demonstration-period
        param:                    # anything else -> run_experiment --param NAME=VALUE
          imitation_count: [3, 5]

A list is swept; to pass a list as one value, wrap it: ``[[1, 2]]``. Every parameter value, and
every combination of them, is checked as run_experiment checks it (graph/description.py), so a
misspelt name or a bad value stops the sweep before any run starts. A run of a learner without
a teacher (saggriac, random-goals, random) ignores ``demonstration_period``, ``teacher`` and the
teacher's parameters (``teacher_choice``, ``demonstration_content``, ``timing``, ...), so those
runs are made once, not once per P or per social mode; a social mode a learner cannot play
(demo-only with ``timing: on-request`` or goal-only demonstrations) stops the sweep before any
run. Runs are named ``<learner>[-P<p>][-<name>=<value>...]-seed<N>`` (P: the
``demonstration_period``) from the settings that differ from run_experiment's and
learner.yaml's defaults, so the paper's default runs keep ``run_study.sh``'s names
(``sgim-d-seed3``) and a sweep file can grow new blocks without renaming the runs already done.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.core.learner_registry import is_learner, learner_kind, learner_names
from sgim_nodes.graph import experiment_options
from sgim_nodes.graph.description import (
    ARBITER_TEACHER,
    OPTION_PARAMETERS,
    STORAGES,
    RunOptions,
    acts_teachers,
    check,
    fingerprint,
    graph,
    learner_defaults,
    parameters,
    social_mode_problems,
    unused,
)
from sgim_nodes.graph.experiment_options import REPO
from sgim_nodes.graph.run_folder import run_name_problem
from sgim_nodes.provenance.fingerprint import Fingerprint
from sgim_ros.clip import value_text
from sgim_ros.command_line import YamlProblem, parse_yaml, shown
from sgim_ros.params import SEED_MAX, ParameterError, seed_problem

# Settings of one run: the file's keys (param: -> run_experiment --param NAME=VALUE).
SETTINGS = ("learner", "demonstration_period", "movements", "eval_every", "teacher", "storage",
            "seeds", "param")
TOP_ONLY = ("name", "runs_dir", "run_timeout", "grid")
TEACHERS = ("automatic", "external")  # human and web need a person: not in a sweep
# The parameters run_experiment sets from its options, and the sweep setting that sets them.
SETTING_OF_PARAM = {"learner": "learner", "seed": "seeds", "movements": "movements",
                    "eval_every": "eval_every", "demonstration_period": "demonstration_period",
                    "teacher": "teacher", "storage": "storage"}
# run_experiment's own defaults.
DEFAULTS = {key: experiment_options.DEFAULTS[key]
            for key in ("demonstration_period", "movements", "eval_every", "teacher", "storage")}
MAX_SEEDS = 100_000  # of one block: a sweep of more runs than that is a typo, not a plan
_UNSAFE = re.compile(r"[^A-Za-z0-9._+=,-]+")


class SweepFileError(ValueError):
    """A sweep file that cannot be expanded; the message names the file and the key."""


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: what run_experiment is told, and the folder it lands in."""

    learner: str
    seed: int
    movements: int
    eval_every: int
    demonstration_period: int | None  # None: a learner without a teacher
    teacher: str | None
    storage: str
    params: tuple[tuple[str, str], ...] = ()  # (name, YAML text), sorted by name
    name: str = field(default="", compare=False)

    @property
    def social(self) -> bool:
        return learner_kind(self.learner).social

    def argv(self) -> list[str]:
        """run_experiment's arguments (without --runs-dir, --name and the launcher's own)."""
        args = [self.learner, "--seed", str(self.seed), "--movements", str(self.movements),
                "--eval-every", str(self.eval_every), "--storage", self.storage]
        if self.social:
            args += ["--demonstration-period", str(self.demonstration_period), "--teacher",
                     str(self.teacher)]
        for name, text in self.params:
            args += ["--param", f"{name}={text}"]
        return args

    def settings(self) -> dict[str, Any]:
        """Every setting as a plain mapping (for status files and the run's sweep record)."""
        out: dict[str, Any] = {"learner": self.learner, "seed": self.seed,
                               "movements": self.movements, "eval_every": self.eval_every,
                               "storage": self.storage}
        if self.social:
            out.update(demonstration_period=self.demonstration_period, teacher=self.teacher)
        out["param"] = {name: yaml.safe_load(text) for name, text in self.params}
        return out

    def expected_parameters(self) -> dict[str, Any]:
        """What a run folder's metadata must say for it to be this run."""
        expected: dict[str, Any] = {"learner": self.learner, "seed": self.seed,
                                    "movements": self.movements, "eval_every": self.eval_every,
                                    "storage": self.storage}
        if self.social:
            expected["demonstration_period"] = self.demonstration_period
            expected["teacher"] = ARBITER_TEACHER[str(self.teacher)]
        else:
            expected["teacher"] = "none"
        expected.update(checked_params(self.params))
        return expected


@dataclass(frozen=True)
class Sweep:
    path: Path
    name: str
    runs_dir: Path
    run_timeout: float | None
    runs: tuple[RunSpec, ...]


def spec_fingerprint(spec: RunSpec) -> Fingerprint:
    """The learner fingerprint run_experiment gives this spec's run (its options as
    run_experiment reads spec.argv(); the seed and the folder do not count)."""
    return _fingerprint_of(spec.learner, spec.movements, spec.eval_every,
                           spec.demonstration_period or DEFAULTS["demonstration_period"],
                           spec.teacher or DEFAULTS["teacher"], spec.storage, spec.params)


@cache
def _fingerprint_of(learner: str, movements: int, eval_every: int, demonstration_period: int,
                    teacher: str, storage: str,
                    params: tuple[tuple[str, str], ...]) -> Fingerprint:
    options = RunOptions(learner, 0, movements, eval_every, demonstration_period, teacher, "",
                         storage, checked_params(params))
    return fingerprint(parameters(options), graph(learner, teacher,
                                                  teachers=acts_teachers(options.overrides)))


def checked_params(params: Iterable[tuple[str, str]]) -> dict[str, Any]:
    """The values as the nodes read them (and metadata.yaml records them): 1 -> 1.0 for a
    float parameter; ParameterError for an unknown name or a bad value."""
    return check({name: yaml.safe_load(text) for name, text in params})


@cache
def checked_defaults() -> dict[str, Any]:
    """Every parameter of learner.yaml at its default, as the nodes read it."""
    return check(learner_defaults())


def yaml_text(value: Any, where: str) -> str:
    """The value as one line of YAML that reads back as the same value."""
    if isinstance(value, Mapping):
        raise SweepFileError(f"{where}: a parameter value cannot be a mapping ({value!r})")
    text = yaml.safe_dump(value, default_flow_style=True, width=10**6).strip()
    text = text.removesuffix("...").strip()
    if yaml.safe_load(text) != value or "\n" in text:
        raise SweepFileError(f"{where}: {value!r} cannot be passed as one --param value")
    return text


def _tag(name: str, text: str) -> str:
    value = yaml.safe_load(text)
    shown = ",".join(map(str, value)) if isinstance(value, list) else str(value)
    return _UNSAFE.sub("_", f"{name}={shown}")


def run_name(spec: RunSpec) -> str:
    """<learner>[-P<p>][-teacher=<t>][-<name>=<value>...]-seed<N>: the non-default settings
    (a spec's params hold only values that differ from learner.yaml's)."""
    tags = []
    if spec.social and spec.demonstration_period != DEFAULTS["demonstration_period"]:
        tags.append(f"P{spec.demonstration_period}")  # the paper's P, kept in run names
    if spec.social and spec.teacher != DEFAULTS["teacher"]:
        tags.append(f"teacher={spec.teacher}")
    tags += [_tag(name, text) for name, text in spec.params]
    return "-".join([spec.learner, *tags, f"seed{spec.seed}"])


def _as_list(value: Any) -> list[Any]:
    return list(value) if isinstance(value, list) else [value]


def _seeds(value: Any, where: str) -> list[int]:
    if isinstance(value, bool):
        raise SweepFileError(f"{where}: seeds must be a count, a list or {{first, count}}")
    if isinstance(value, int):
        _seed_count(value, 0, where)
        seeds = list(range(value))
    elif isinstance(value, list):
        seeds = value
    elif isinstance(value, Mapping) and set(value) <= {"first", "count"} and "count" in value:
        first, count = value.get("first", 0), value["count"]
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (first, count)):
            raise SweepFileError(f"{where}: seeds' first and count must be integers")
        _seed_count(count, first, where)
        seeds = list(range(first, first + count))
    else:
        raise SweepFileError(f"{where}: seeds must be a count (N: 0..N-1), a list of seeds or "
                             f"{{first: F, count: N}}, got {value!r}")
    if not seeds or any(not isinstance(s, int) or isinstance(s, bool) or s < 0 for s in seeds):
        raise SweepFileError(f"{where}: seeds must be integers >= 0, at least one, got "
                             f"{value_text(value)}")
    if any(seed_problem(s) for s in seeds):
        raise SweepFileError(f"{where}: seeds must be in 0..{SEED_MAX} (2**32 - 1), the "
                             f"graph's range, got {value_text(value)}")
    return seeds


def _seed_count(count: int, first: int, where: str) -> None:
    """Refuse a count of seeds before it is spelt out as a list (10**12 would never end)."""
    if count > MAX_SEEDS or (count > 0 and first + count - 1 > SEED_MAX):
        raise SweepFileError(f"{where}: seeds must be in 0..{SEED_MAX} (2**32 - 1) and at most "
                             f"{MAX_SEEDS} of them, got {count} from {first}")


def _positive_int(value: Any, key: str, where: str, minimum: int = 1) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise SweepFileError(f"{where}: {key} must be an integer >= {minimum}, got {value!r}")
    return value


def _check_block(block: Any, where: str) -> dict[str, Any]:
    if not isinstance(block, Mapping):
        raise SweepFileError(f"{where}: expected a mapping of settings, got {block!r}")
    unknown = sorted(map(str, set(block) - set(SETTINGS)))
    if unknown:
        top_only = [k for k in unknown if k in TOP_ONLY]
        if top_only:
            raise SweepFileError(f"{where}: {', '.join(top_only)} belongs at the top of the file")
        raise SweepFileError(f"{where}: unknown setting(s) {', '.join(unknown)}; the settings "
                             f"are {', '.join(SETTINGS)}, and every node parameter goes under "
                             "'param:' (e.g. param: {imitation_count: [3, 5]})")
    param = block.get("param", {})
    if not isinstance(param, Mapping):
        raise SweepFileError(f"{where}: 'param' must map parameter names to values")
    for name in param:
        if not isinstance(name, str) or not name:
            raise SweepFileError(f"{where}: parameter names must be strings, got {name!r}")
        if name in OPTION_PARAMETERS:
            key = SETTING_OF_PARAM.get(name)
            instead = (f"use the setting '{key}'" if key else
                       f"run_experiment sets it ({OPTION_PARAMETERS[name]})")
            raise SweepFileError(f"{where}: param {name} is not a parameter to sweep: "
                                 f"{instead}")
    return dict(block)


def teacher_parameters(learner: str, names: Iterable[str]) -> set[str]:
    """The names a learner without a teacher never reads: those no node of its graph declares
    (the teacher's), and the arbiter's `timing`, which only a social learner's reads."""
    names = list(names)
    return set(unused(names, graph(learner))) | ({"timing"} & set(names))


def _expand_block(block: dict[str, Any], where: str) -> Iterable[RunSpec]:
    if "learner" not in block:
        raise SweepFileError(f"{where}: no learner (give 'learner' at the top or in the block)")
    learners = _as_list(block["learner"])
    for learner in learners:
        if not is_learner(learner):
            raise SweepFileError(f"{where}: unknown learner {learner!r}; choose among "
                                 f"{', '.join(learner_names())}")
    seeds = _seeds(block.get("seeds", 1), where)
    axes = {key: _as_list(block.get(key, DEFAULTS[key])) for key in DEFAULTS}
    for value in axes["demonstration_period"]:
        _positive_int(value, "demonstration_period", where)
    for value in axes["movements"]:
        _positive_int(value, "movements", where)
    for value in axes["eval_every"]:
        _positive_int(value, "eval_every", where, minimum=0)
    for value in axes["teacher"]:
        if value not in TEACHERS:
            raise SweepFileError(f"{where}: teacher must be one of {', '.join(TEACHERS)} (the "
                                 f"human and web teachers need a person), got {value!r}")
    for value in axes["storage"]:
        if value not in STORAGES:
            raise SweepFileError(f"{where}: storage must be one of {', '.join(STORAGES)}")
    params = block.get("param", {})
    names = sorted(params)
    values = [[yaml_text(v, f"{where}: param {n}") for v in _as_list(params[n])] for n in names]
    for name, texts in zip(names, values, strict=True):
        for text in texts:  # every value checked as run_experiment would, before any run
            try:
                checked_params([(name, text)])
            except ParameterError as error:
                raise SweepFileError(f"{where}: {error}") from None
    defaults = checked_defaults()
    for chosen in itertools.product(*values):  # values that must agree (p_mode1..3, ...)
        try:
            checked_params(zip(names, chosen, strict=True))
        except ParameterError as error:
            raise SweepFileError(f"{where}: {error}") from None
    for seed, learner, movements, eval_every, storage, period, teacher, chosen in (
            itertools.product(seeds, learners, axes["movements"], axes["eval_every"],
                              axes["storage"], axes["demonstration_period"], axes["teacher"],
                              itertools.product(*values))):
        social = learner_kind(learner).social
        problems = social_mode_problems(RunOptions(learner, teacher=teacher),
                                        checked_params(zip(names, chosen, strict=True)))
        if problems:
            raise SweepFileError(f"{where}: {learner}: {'; '.join(problems)}")
        ignored = set() if social else teacher_parameters(learner, names)
        # A parameter at its learner.yaml default is the default run: one spec, one name.
        given = tuple((n, t) for n, t in zip(names, chosen, strict=True) if n not in ignored
                      and (n not in defaults or checked_params([(n, t)])[n] != defaults[n]))
        spec = RunSpec(learner, seed, movements, eval_every, period if social else None,
                       teacher if social else None, storage, given)
        name = run_name(spec)
        if run_name_problem(name):  # a folder name the file system refuses: too long
            raise SweepFileError(f"{where}: the run folder {name[:60]}...: "
                                 f"{run_name_problem(name)}")
        yield RunSpec(**{**spec.__dict__, "name": name})


def expand(document: Mapping[str, Any], where: str = "sweep file") -> list[RunSpec]:
    """Every run of the document, seed-major (a sweep cut short has every setting at its
    first seeds), each once."""
    if not isinstance(document, Mapping):
        raise SweepFileError(f"{where}: expected a mapping at the top, "
                             f"got {type(document).__name__}")
    top = _check_block({k: v for k, v in document.items() if k not in TOP_ONLY}, where)
    grid = document.get("grid", [{}])
    if not isinstance(grid, list) or not grid:
        raise SweepFileError(f"{where}: 'grid' must be a non-empty list of blocks")
    found: dict[str, RunSpec] = {}
    order: list[tuple[int, int, str]] = []
    for b, block in enumerate(grid):
        here = f"{where}, grid block {b + 1}"
        block = _check_block(block, here)
        merged = {**top, **block, "param": {**top.get("param", {}), **block.get("param", {})}}
        for spec in _expand_block(merged, here):
            if spec.name in found:
                if found[spec.name] != spec:
                    raise SweepFileError(
                        f"{here}: two different runs would share the folder {spec.name} "
                        f"({_difference(found[spec.name], spec)}): movements, eval_every and "
                        "storage are not part of run names, so sweep them in separate sweeps")
                continue
            found[spec.name] = spec
            order.append((spec.seed, len(order), spec.name))
    return [found[name] for _, _, name in sorted(order)]


def _difference(a: RunSpec, b: RunSpec) -> str:
    sa, sb = a.settings(), b.settings()
    return ", ".join(f"{k}: {sa.get(k)!r} vs {sb.get(k)!r}" for k in sorted(set(sa) | set(sb))
                     if sa.get(k) != sb.get(k))


def load(path: str | Path, runs_dir: Path | None = None) -> Sweep:
    """Read and expand a sweep file; `runs_dir` (the command line's) wins over the file's."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except (OSError, ValueError) as error:  # ValueError: a NUL in the path
        raise SweepFileError(f"cannot read the sweep file {shown(path)}: "
                             f"{getattr(error, 'strerror', None) or error}") from None
    try:  # as a parameter file is read: UTF-8, a key given twice refused (not last-wins)
        document = parse_yaml(raw)
    except YamlProblem as problem:
        raise SweepFileError(f"{shown(path)}: {problem}") from None
    runs = expand(document, str(path))
    name = str(document.get("name", path.stem))
    if runs_dir is None:
        runs_dir = REPO / str(document.get("runs_dir", f"runs/{path.stem}"))
    timeout = document.get("run_timeout")
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, int | float)
                                or timeout <= 0):
        raise SweepFileError(f"{path}: run_timeout must be a number of seconds > 0")
    return Sweep(path, name, Path(runs_dir).absolute(), timeout, tuple(runs))
