"""The graph of one run: which nodes, how each is started, and with which parameters.

One description serves both ways of starting a run, so they cannot drift apart:
`ros_ws/run_experiment.sh` (graph/experiment.py, each node started as `ros2 run` would) and
`ros2 launch sgim_nodes experiment.launch.py` on a full ROS install (launch/). Both build a
RunOptions from their arguments, ask `graph()` for the nodes and `parameters()` for the values,
and give each node `node_parameters()`: the values of the parameters it declares.

Every node module lists its parameters in a module-level PARAMS (sgim_ros.params.Param), so
a run's parameters are checked here, before any node starts: unknown names and bad values are
refused with one line each, naming them. Beside them, its INTERFACES declare its topics,
services and actions (sgim_ros/interfaces.py).
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from functools import cache
from pathlib import Path
from typing import Any

import yaml

from sgim_nodes.bag.writer import STORAGES  # the recorder's bag formats, named once
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.learner_registry import SGIM_ACTS, is_learner, learner_kind, learner_names
from sgim_nodes.core.social_config import SOCIAL_DEFAULTS
from sgim_ros.interfaces import Endpoint
from sgim_ros.params import Param, ParameterError

LEARNER_CONFIG = Path(__file__).resolve().parents[2] / "config" / "learner.yaml"
WEB_EXPERT = "web"  # teacher/web_expert.WEB_EXPERT: the web teacher among SGIM-ACTS's teachers
TEACHERS = ("automatic", "human", "web", "external")
# The arbiter only knows synchronous (automatic) and asynchronous (human) demonstrations.
ARBITER_TEACHER = {"automatic": "automatic", "human": "human", "web": "human",
                   "external": "human"}
WAIT_FOREVER = -1.0  # wait_for_teacher: until the teacher acts (the arbiter's FOREVER)
MAX_RESPAWNS = 3


@dataclass(frozen=True)
class NodeSpec:
    """One node of the graph: `ros2 run PACKAGE EXECUTABLE`, named EXECUTABLE, in the
    run's namespace or, given `namespace`, in that one (SGIM-ACTS's teachers: /centre/expert)."""

    package: str
    executable: str
    params_module: str  # the module whose PARAMS the node declares
    # The simulator holds no learning state and its clients try a call it never answered
    # again (sim_client.py), so it is restarted when it dies; every other node holds the
    # learner's memory, tree or count, or serves calls that are not retried: losing one ends
    # the run, clearly.
    respawn: bool = False
    # The human teacher's prompt needs the terminal; leaving it (`quit`) does not end the run.
    interactive: bool = False
    namespace: str = ""

    @property
    def name(self) -> str:
        return f"{self.namespace}/{self.executable}" if self.namespace else self.executable

    def in_namespace(self, namespace: str) -> NodeSpec:
        from dataclasses import replace

        return replace(self, namespace=namespace)

    @property
    def params(self) -> tuple[Param, ...]:
        return _params_of(self.params_module)

    @property
    def interfaces(self) -> tuple[Endpoint, ...]:
        """What the node publishes, subscribes to, serves and calls: its module's INTERFACES
        (sgim_ros/interfaces.py)."""
        return tuple(importlib.import_module(self.params_module).INTERFACES)


@cache
def _params_of(module: str) -> tuple[Param, ...]:
    return tuple(importlib.import_module(module).PARAMS)


NODES = {spec.name: spec for spec in (
    NodeSpec("sgim_nodes", "recorder", "sgim_nodes.nodes.recorder"),
    NodeSpec("sim_bridge", "sim_bridge", "sim_bridge.sim_bridge_node", respawn=True),
    NodeSpec("sgim_nodes", "evaluator", "sgim_nodes.nodes.evaluator"),
    NodeSpec("sgim_nodes", "markers", "sgim_nodes.nodes.markers"),
    NodeSpec("sgim_nodes", "interest_computer", "sgim_nodes.nodes.interest_computer"),
    NodeSpec("sgim_nodes", "goal_generator", "sgim_nodes.nodes.goal_generator"),
    NodeSpec("sgim_nodes", "low_level_explorer", "sgim_nodes.nodes.low_level_explorer"),
    NodeSpec("sgim_nodes", "imitation", "sgim_nodes.nodes.imitation"),
    NodeSpec("teacher", "teacher", "teacher.teacher_node"),
    NodeSpec("teacher", "human_input", "teacher.human_input_node", interactive=True),
    NodeSpec("teacher", "web_teacher", "teacher.web_teacher_node"),
    # SGIM-ACTS's teachers (issue 33): one per name, each in the namespace of its name.
    NodeSpec("teacher", "expert", "teacher.expert_node"),
    NodeSpec("sgim_nodes", "social_interaction", "sgim_nodes.nodes.social_interaction"),
)}
ARBITER = "social_interaction"
RECORDER = "recorder"


@dataclass(frozen=True)
class RunOptions:
    """A run's choices, as run_experiment's options and the launch file's arguments name
    them; `overrides` are NAME=VALUE parameters on top of the learner defaults."""

    learner: str
    seed: int = 0
    movements: int = 5000
    eval_every: int = 250
    demonstration_period: int = SOCIAL_DEFAULTS.demonstration_period
    teacher: str = "automatic"
    output: str = ""  # the bag directory
    storage: str = "mcap"
    overrides: Mapping[str, Any] = field(default_factory=dict)
    markers: bool = True  # the markers node (the run's picture for rviz2 and Foxglove)
    wait_for_teacher: float = 0.0  # human or web teacher: seconds at each turn, -1: forever
    web_host: str = "127.0.0.1"
    web_port: int = 8765
    web_token: str = ""
    web_address_file: str = ""  # where the web teacher writes its page's address
    web_linger: float = 600.0  # seconds its page stays after the run for a person looking

    def __post_init__(self) -> None:
        problems = []
        if not is_learner(self.learner):
            problems.append(f"learner must be one of {', '.join(learner_names())}, "
                            f"got {self.learner!r}")
        if self.teacher not in TEACHERS:
            problems.append(f"teacher must be one of {', '.join(TEACHERS)}, got "
                            f"{self.teacher!r}")
        if self.storage not in STORAGES:
            problems.append(f"storage must be one of {', '.join(STORAGES)}")
        for name, low in (("seed", 0), ("movements", 1), ("eval_every", 0),
                          ("demonstration_period", 1)):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < low:
                problems.append(f"{name} must be an integer >= {low}, got {value!r}")
        if not (self.wait_for_teacher >= 0 or self.wait_for_teacher == WAIT_FOREVER):
            problems.append(f"wait_for_teacher must be seconds >= 0 or {WAIT_FOREVER:g} "
                            f"(forever), got {self.wait_for_teacher!r}")
        elif self.wait_for_teacher and self.teacher not in ("human", "web"):
            problems.append("wait_for_teacher needs a human teacher (human or web)")
        if problems:
            raise ParameterError("; ".join(problems))


# Parameters that the run's own options set: a NAME=VALUE for them would be overwritten.
OPTION_PARAMETERS = {"learner": "the learner argument", "seed": "--seed",
                     "movements": "--movements", "eval_every": "--eval-every",
                     "demonstration_period": "--demonstration-period", "teacher": "--teacher",
                     "output": "the run folder", "storage": "--storage",
                     "wait_for_recorder": "the launcher (always true in a run)",
                     "movement_listeners": "the launcher (the graph's nodes that hear the "
                                           "movements)",
                     "resume_from": "--resume", "resume_segments": "--resume",
                     "wait_for_teacher": "--wait-for-teacher", "host": "--web-host",
                     "port": "--web-port", "token": "--web-token", "linger": "--web-linger",
                     "address_file": "the run folder"}
SECRETS = ("token",)  # never written into metadata.yaml


def acts_teachers(overrides: Mapping[str, Any]) -> list[str]:
    """SGIM-ACTS's teachers in a run: its `teachers` parameter, or the default ones."""
    from sgim_nodes.nodes.ros_glue import TEACHERS, teacher_names

    return teacher_names(overrides.get("teachers", TEACHERS.default))


def graph(learner: str, teacher: str = "automatic", markers: bool = True,
          teachers: Sequence[str] | None = None) -> list[NodeSpec]:
    """The nodes a run of `learner` needs, the recorder first and the arbiter last; for
    sgim-acts, an expert per name of `teachers` (None: the default ones), the web teacher
    answering as "web" when the run's teacher is the web page."""
    names = ["recorder", "sim_bridge", "evaluator"] + (["markers"] if markers else [])
    kind = learner_kind(learner)
    if kind.goal_babbling:
        names += ["interest_computer", "goal_generator", "low_level_explorer"]
    if kind.chooses_teachers:
        asked = acts_teachers({}) if teachers is None else teachers
        experts = [NODES["web_teacher"] if name == WEB_EXPERT and teacher == "web"
                   else NODES["expert"].in_namespace(name) for name in asked]
        return [*(NODES[name] for name in names), NODES["imitation"], *experts,
                NODES[ARBITER]]
    if kind.social:
        if kind.imitates:
            names.append("imitation")
        teacher_node = {"automatic": "teacher", "human": "human_input",
                        "web": "web_teacher"}.get(teacher)
        if teacher_node:
            names.append(teacher_node)
    names.append(ARBITER)
    return [NODES[name] for name in names]


# The nodes that subscribe `movements` and cannot go on after missing one; the human prompt is
# left out: it may leave the run (`quit`), and the run goes on without it.
MOVEMENT_LISTENERS = ("recorder", "evaluator", "markers", "low_level_explorer", "imitation",
                      "teacher", "web_teacher")


def movement_listeners(options: RunOptions, teachers: Sequence[str] | None = None
                       ) -> list[str]:
    """The nodes of this run's graph that the simulator waits for (sim_bridge's
    `movement_listeners`) before it serves a movement, at its start and after a restart;
    `teachers`: sgim-acts's (None: those of the options)."""
    names = acts_teachers(options.overrides) if teachers is None else teachers
    return [spec.name for spec in graph(options.learner, options.teacher, options.markers,
                                        names)
            if spec.name in MOVEMENT_LISTENERS]


def learner_defaults() -> dict[str, Any]:
    """The learner parameters' documented defaults (config/learner.yaml)."""
    return dict(yaml.safe_load(LEARNER_CONFIG.read_text())["/**"]["ros__parameters"])


def declared(nodes: Iterable[NodeSpec]) -> dict[str, list[tuple[NodeSpec, Param]]]:
    """Parameter name -> the nodes that declare it (with their declaration)."""
    found: dict[str, list[tuple[NodeSpec, Param]]] = {}
    for spec in nodes:
        for param in spec.params:
            found.setdefault(param.name, []).append((spec, param))
    return found


def check(values: Mapping[str, Any], where: Mapping[str, str] | None = None
          ) -> dict[str, Any]:
    """The values as the nodes will read them (1 -> 1.0 for a float), or ParameterError listing
    every unknown name and bad value. A name is known when any node of the project declares it
    (a study gives every learner the same options); `where` says where a name was given."""
    by_name = declared(NODES.values())
    where = where or {}
    problems: list[str] = []
    for name in values:
        if name not in by_name:
            near = _closest(name, by_name)
            problems.append(f"unknown parameter '{name}'{where.get(name, '')}: no node "
                            "declares it" + (f" (did you mean '{near}'?)" if near else ""))
    checked = dict(values)
    for name, value in values.items():
        for _spec, param in by_name.get(name, ()):
            try:
                checked[name] = param.validate(value)
            except ParameterError as error:
                problems.append(f"{error}{where.get(name, '')}")
                break
    learner_fields = {f.name for f in fields(LearnerConfig)} & set(checked)
    if not problems:
        try:
            LearnerConfig(**{name: checked[name] for name in learner_fields})
        except (TypeError, ValueError) as error:
            problems.append(str(error))
    if problems:
        raise ParameterError("\n".join(problems))
    return checked


def unused(values: Iterable[str], nodes: Iterable[NodeSpec]) -> list[str]:
    """Names that no node of this graph reads (known to other nodes: say so, not refuse)."""
    used = declared(nodes)
    return [name for name in values if name not in used]


def _closest(name: str, known: Iterable[str]) -> str | None:
    import difflib

    found = difflib.get_close_matches(name, list(known), n=1, cutoff=0.75)
    return found[0] if found else None


@dataclass(frozen=True)
class RunParameters:
    """A run's checked values: `shared` ones every node reads (the `/**` section of its
    parameter file) and `per_node` ones (a section named after the node)."""

    shared: dict[str, Any]
    per_node: dict[str, dict[str, Any]] = field(default_factory=dict)

    def for_node(self, spec: NodeSpec) -> dict[str, Any]:
        """The values the node reads: those of the parameters it declares."""
        names = {p.name for p in spec.params}
        own = {k: v for k, v in self.shared.items() if k in names}
        return {**own, **self.per_node.get(spec.name, {})}

    def effective(self, nodes: Iterable[NodeSpec]) -> dict[str, dict[str, Any]]:
        """Node -> every parameter it declares with the value it runs with (given or its
        default): what a run's metadata records (secrets masked)."""
        return {spec.name: masked({**{p.name: p.default for p in spec.params},
                                   **self.for_node(spec)}) for spec in nodes}

    def to_yaml(self) -> dict[str, Any]:
        """The ROS parameter file of the run."""
        return {"/**": {"ros__parameters": dict(self.shared)},
                **{f"/{name}" if "/" in name else name: {"ros__parameters": dict(values)}
                   for name, values in self.per_node.items() if values}}

    @classmethod
    def from_yaml(cls, data: Any) -> RunParameters:
        """Read back a file written by to_yaml (KeyError or TypeError if it is not one)."""
        shared = dict(data["/**"]["ros__parameters"])
        return cls(shared, {name.lstrip("/"): dict(body["ros__parameters"])
                            for name, body in data.items() if name != "/**"})


def fingerprint(values: RunParameters, nodes: Iterable[NodeSpec]):
    """The learner fingerprint of a run of these nodes with these values
    (provenance/fingerprint.py: of every node, the read-only parameters that shape it, and
    the nodes' code)."""
    from sgim_nodes.provenance.fingerprint import fingerprint as make
    from sgim_nodes.provenance.fingerprint import graph_parameters

    nodes = list(nodes)
    read_only = {spec.name: [p.name for p in spec.params if p.read_only] for spec in nodes}
    return make(graph_parameters(values.effective(nodes), read_only), graph=True)


def masked(values: Mapping[str, Any]) -> dict[str, Any]:
    """The values with every secret (the web teacher's token) replaced by a mark."""
    return {k: ("<set>" if v else "") if k in SECRETS else v for k, v in values.items()}


def social_mode_problems(options: RunOptions, values: Mapping[str, Any]) -> list[str]:
    """The social modes a run's learner and teacher cannot play, as the runner refuses them
    (core/learner_registry.LearnerKind.refusal): on-request needs the automatic teacher (it
    answers the asks) and a learner that asks; a learner takes only the demonstration contents
    it declares. Learners without a teacher ignore both settings."""
    kind = learner_kind(options.learner)
    if not kind.social:
        return []
    problems = []
    timing = values.get("timing")
    if timing == "on-request" and options.teacher != "automatic":
        problems.append("timing 'on-request' needs the automatic teacher (--teacher "
                        f"automatic), not {options.teacher!r}: it answers the asks")
    for refusal in (kind.refusal(timing=timing),
                    kind.refusal(content=values.get("demonstration_content"))):
        if refusal:
            problems.append(refusal)
    return problems


def parameters(options: RunOptions, node_overrides: Mapping[str, Mapping[str, Any]] | None = None,
               where: Mapping[str, str] | None = None) -> RunParameters:
    """Every value of a run, checked: the learner defaults, the overrides, then the run's own
    options (which the overrides may not name). `node_overrides`: values for one node only
    (a parameter file's section named after it), checked against what that node declares."""
    node_overrides = node_overrides or {}
    given = {*options.overrides, *(n for v in node_overrides.values() for n in v)}
    clash = sorted(given & set(OPTION_PARAMETERS))
    if clash:
        raise ParameterError("\n".join(
            f"parameter '{name}' is set by {OPTION_PARAMETERS[name]}, not as a parameter"
            for name in clash))
    values = {**learner_defaults(), **options.overrides}
    kind = learner_kind(options.learner)
    if kind.chooses_teachers and options.teacher == "web":  # the page is one of them
        names = acts_teachers(options.overrides)
        values["teachers"] = ",".join([*names, *([] if WEB_EXPERT in names else [WEB_EXPERT])])
    values.update(
        learner=options.learner, seed=options.seed, movements=options.movements,
        eval_every=options.eval_every, demonstration_period=options.demonstration_period,
        teacher=ARBITER_TEACHER[options.teacher] if kind.social else "none",
        storage=options.storage, wait_for_recorder=True,
        movement_listeners=",".join(movement_listeners(options, acts_teachers(values))),
        wait_for_teacher=options.wait_for_teacher)
    if options.output:
        values["output"] = options.output
    if options.teacher == "web" and (kind.social or kind.chooses_teachers):
        values.update(host=options.web_host, port=options.web_port, token=options.web_token,
                      address_file=options.web_address_file, linger=float(options.web_linger))
    if kind.chooses_teachers and WEB_EXPERT in acts_teachers(values):
        if options.teacher != "web":
            raise ParameterError(f"teacher '{WEB_EXPERT}' among {SGIM_ACTS}'s teachers is the "
                                 "web page: run it with --teacher web")
        values["expert"] = True
        values.setdefault("teacher_timeout", 3600.0)  # a person answers, not a node
    problems = []
    try:
        shared = check(values, where)
        problems += social_mode_problems(options, shared)
    except ParameterError as error:
        problems.append(str(error))
    per_node: dict[str, dict[str, Any]] = {}
    for name, own in node_overrides.items():
        spec = NODES.get(name if "/" not in name else name.rsplit("/", 1)[-1])
        if spec is None or ("/" in name and spec.name != "expert"):
            problems.append(f"unknown node '{name}'{(where or {}).get(name, '')}: the nodes "
                            f"are {', '.join(NODES)}")
            continue
        params = {p.name: p for p in spec.params}
        for key, value in own.items():
            if key not in params:
                problems.append(f"unknown parameter '{key}' for node '{name}'"
                                f"{(where or {}).get(name, '')}: it declares "
                                f"{', '.join(sorted(params))}")
                continue
            try:
                per_node.setdefault(name, {})[key] = params[key].validate(value)
            except ParameterError as error:
                problems.append(f"{error} (node '{name}'){(where or {}).get(name, '')}")
    if problems:
        raise ParameterError("\n".join(problems))
    for name, own in per_node.items():  # the learner fields of a node must still agree
        merged = {**shared, **own}
        learner_fields = {f.name for f in fields(LearnerConfig)} & set(merged)
        try:
            LearnerConfig(**{k: merged[k] for k in learner_fields})
        except (TypeError, ValueError) as error:
            raise ParameterError(f"node '{name}': {error}") from None
    return RunParameters(shared, per_node)
