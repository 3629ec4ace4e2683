"""The human teacher's decisions, without ROS: what a parsed command does, given what the node
has heard of the learner.

A demonstration the learner cannot take any more (its movement budget is spent, the run is
over) is refused here with the reason, never sent to be silently dropped.

Why ``goal`` offers a stored pair and not the inverse model's interpolated action: a
demonstration must carry the outcome its action produces, and only stored pairs have a known
one. The library is the teaching set plus the learner's landed movements, so the reply states
which of the two the pair came from, and how far its outcome is from the goal: the person
decides whether to ``send`` it (the web page's offer and confirm, at the prompt).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.inverse_model import InverseModel
from sgim_nodes.core.memory import Memory
from sgim_nodes.core.teaching import Teacher
from teacher.human_commands import (
    HELP,
    OUTCOME_SIZE,
    Command,
    CommandError,
    GoalPoint,
    Help,
    ListGoals,
    PaceRequest,
    Quit,
    Send,
    Status,
    Teach,
    YamlFile,
    parse_unit,
)

# The Teacher class's default; the nodes pass the automatic teacher's own tolerance
# (tolerance_noise x outcome_noise, sgim_nodes.nodes.picture_feed.REACH_PARAMS).
DEFAULT_TOLERANCE: float = inspect.signature(Teacher).parameters["tolerance"].default

# --- what the node has heard ---------------------------------------------------------------


@dataclass
class LearnerState:
    """The learner as seen from the outside: landed movements, count, latest evaluation."""

    action_size: int
    movement_count: int = 0
    evaluation: tuple[int, float] | None = None  # (movement index, mean distance)
    demonstrations: int = 0  # given by this node
    listeners: int = 0  # subscribers of the demonstrations topic, as last seen
    total: int = 0  # the run's movement budget (0: not heard yet)
    run_over: str = ""  # why the run is over ("finished", "aborted: ..."); "" while it runs
    actions: list[np.ndarray] = field(default_factory=list)  # of landed movements
    outcomes: list[np.ndarray] = field(default_factory=list)
    indices: list[int] = field(default_factory=list)  # their Movement.index

    def add_movement(self, index: int, landed: bool, action: Any, outcome: Any) -> str | None:
        """Count a movement; keep it in the library if it landed. Returns a problem, if any."""
        self.movement_count = max(self.movement_count, int(index))
        if not landed:
            return None
        a, y = np.asarray(action, dtype=float), np.asarray(outcome, dtype=float)
        if a.shape != (self.action_size,) or y.shape != (OUTCOME_SIZE,):
            return (f"movement {index} ignored: action size {a.size}, outcome size {y.size} "
                    f"(expected {self.action_size} and {OUTCOME_SIZE})")
        if not (np.isfinite(a).all() and np.isfinite(y).all()):
            return f"movement {index} ignored: it holds non-finite values"
        self.actions.append(a)
        self.outcomes.append(y)
        self.indices.append(int(index))
        return None

    def reached(self) -> np.ndarray:
        return np.array(self.outcomes).reshape(-1, OUTCOME_SIZE)

    def refusal(self) -> str:
        """Why the learner can take no demonstration now, or ''."""
        if self.run_over:
            return f"the run is over ({self.run_over}): the learner takes no more demonstrations"
        if self.total and self.movement_count >= self.total:
            return (f"the movement budget is spent ({self.movement_count}/{self.total}): "
                    "the learner takes no more demonstrations")
        return ""


# --- decisions -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Reply:
    """Only text to print."""

    text: str


@dataclass(frozen=True)
class SendDemonstration:
    action: np.ndarray
    outcome: np.ndarray
    teaching_set_index: int  # -1 when the pair is not a teaching-set entry
    text: str  # what is sent and why, for the person


@dataclass(frozen=True)
class ExecuteFirst:
    """The action of a file: its outcome must be measured before it can be demonstrated."""

    action: np.ndarray
    file_outcome: np.ndarray | None  # used only when the simulator cannot be asked
    path: str


Decision = Reply | SendDemonstration | ExecuteFirst | Quit | PaceRequest


class TeachingLibrary:
    """The teaching set, checked once, and the decisions that need it."""

    def __init__(self, actions: Any, outcomes: Any, tolerance: float,
                 config: LearnerConfig | None = None) -> None:
        self.actions = np.asarray(actions, dtype=float)
        self.outcomes = np.asarray(outcomes, dtype=float)
        if (self.actions.ndim != 2 or self.outcomes.shape != (len(self.actions), OUTCOME_SIZE)
                or len(self.actions) == 0):
            raise ValueError(f"teaching set must hold M >= 1 actions (M, A) and outcomes "
                             f"(M, {OUTCOME_SIZE}); got {self.actions.shape} and "
                             f"{self.outcomes.shape}")
        if not (np.isfinite(self.actions).all() and np.isfinite(self.outcomes).all()):
            raise ValueError("teaching set holds non-finite values")
        # The automatic teacher's rule for "not reached", so both teachers agree.
        self.teacher = Teacher(self.actions, self.outcomes, np.random.default_rng(0),
                               tolerance=tolerance)
        self.config = config or LearnerConfig()

    @property
    def action_size(self) -> int:
        return self.actions.shape[1]

    def decide(self, command: Command, state: LearnerState) -> Decision:
        """What to do for one command; raises CommandError for impossible requests."""
        match command:
            case Help():
                return Reply(HELP)
            case Quit():
                return command
            case ListGoals():
                return Reply(self.list_text(state))
            case Status():
                return Reply(status_text(state))
            case PaceRequest() | Send():
                return command
            case Teach(index):
                refuse_if_over(state)
                return self.teach(index, state)
            case GoalPoint(point):
                refuse_if_over(state)
                return self.for_goal(np.array(point), state)
            case YamlFile(path):
                refuse_if_over(state)
                action, outcome = load_action_file(path, self.action_size)
                return ExecuteFirst(action, outcome, path)
        raise CommandError(f"no handler for {command!r}")  # unreachable: parse makes commands

    def closest_distances(self, state: LearnerState) -> np.ndarray:
        reached = state.reached()
        if len(reached) == 0:
            return np.full(len(self.outcomes), np.inf)
        diff = self.outcomes[:, None, :] - reached[None, :, :]
        return np.sqrt((diff**2).sum(-1)).min(1)

    def list_text(self, state: LearnerState) -> str:
        unreached = self.teacher.unreached(state.reached())
        total, tol = len(self.outcomes), self.teacher.tolerance
        if len(unreached) == 0:
            return f"all {total} teaching goals are reached within {tol:g}"
        closest = self.closest_distances(state)
        lines = [f"{len(unreached)} of {total} teaching goals not reached within {tol:g}:"]
        for i in unreached:
            far = "nothing reached yet" if np.isinf(closest[i]) else f"closest {closest[i]:.3f}"
            lines.append(f"  {i:3d}: outcome {fmt(self.outcomes[i])}  ({far})")
        return "\n".join(lines)

    def teach(self, index: int, state: LearnerState) -> SendDemonstration:
        total = len(self.actions)
        if not 0 <= index < total:
            raise CommandError(f"no teaching-set entry {index}: entries are 0 to {total - 1}")
        note = ""
        if index not in self.teacher.unreached(state.reached()):
            note = " (note: the learner already reached it)"
        return SendDemonstration(
            self.actions[index].copy(), self.outcomes[index].copy(), index,
            f"teaching-set entry {index}, outcome {fmt(self.outcomes[index])}{note}")

    def for_goal(self, goal: np.ndarray, state: LearnerState) -> SendDemonstration:
        """The inverse model's most reliable candidate in teaching set + learner movements."""
        memory = Memory(self.action_size, OUTCOME_SIZE)
        for a, y in zip(self.actions, self.outcomes, strict=True):
            memory.add(a, y)
        for a, y in zip(state.actions, state.outcomes, strict=True):
            memory.add(a, y)
        c = self.config
        model = InverseModel(memory, "reliable", c.l_max, c.k_max, c.alpha)
        estimate = model.estimate(goal)
        assert estimate is not None  # the teaching set is never empty
        k = estimate.candidate_index
        action, outcome = memory.actions[k].copy(), memory.outcomes[k].copy()
        distance = float(np.linalg.norm(outcome - goal))
        if k < len(self.actions):
            source, ts_index = f"teaching-set entry {k}", k
        else:
            source, ts_index = f"learner movement {state.indices[k - len(self.actions)]}", -1
        return SendDemonstration(
            action, outcome, ts_index,
            f"for goal {fmt(goal)}: the action of {source}, outcome {fmt(outcome)} "
            f"({distance:.3f} from the goal; cost {estimate.reliability:.3f} = distance + "
            f"{c.alpha:g} x variance of its neighbours' actions, lower is better)")


def refuse_if_over(state: LearnerState) -> None:
    why = state.refusal()
    if why:
        raise CommandError(why)


def status_text(state: LearnerState) -> str:
    if state.evaluation is None:
        error = "no evaluation yet"
    else:
        error = f"{state.evaluation[1]:.4f} (at movement {state.evaluation[0]})"
    budget = f"/{state.total}" if state.total else ""
    over = f" (run over: {state.run_over})" if state.run_over else ""
    return (f"latest evaluation error: {error}\nmovements: {state.movement_count}{budget}{over}\n"
            f"demonstrations given: {state.demonstrations}\n"
            f"listening to demonstrations: {state.listeners}")


def prompt(state: LearnerState) -> str:
    error = "-" if state.evaluation is None else f"{state.evaluation[1]:.3f}"
    budget = f"/{state.total}" if state.total else ""
    return (f"[movements {state.movement_count}{budget} | error {error} | "
            f"demos {state.demonstrations}] human> ")


def fmt(point: Any) -> str:
    return "(" + ", ".join(f"{v:+.3f}" for v in np.asarray(point, dtype=float)) + ")"


# --- action files --------------------------------------------------------------------------


def load_action_file(path: str, action_size: int) -> tuple[np.ndarray, np.ndarray | None]:
    """(action, optional outcome) from a YAML file.

    Accepted: a list of ``action_size`` numbers, or a mapping with ``action`` (that list) and
    optionally ``outcome: [x, y]``, used only when the simulator cannot measure it. Unknown
    keys are refused: a misspelt ``outcome`` must not be silently dropped.
    """
    file = Path(path).expanduser()
    try:
        text = file.read_text()
    except FileNotFoundError:
        raise CommandError(f"no such file: {path}") from None
    except IsADirectoryError:
        raise CommandError(f"{path} is a directory, not a YAML file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise CommandError(f"cannot read {path}: {error}") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        where = getattr(error, "problem_mark", None)
        at = f" (line {where.line + 1})" if where is not None else ""
        raise CommandError(f"{path} is not valid YAML{at}") from None
    outcome = None
    if isinstance(data, dict):
        unknown = sorted(str(k) for k in data if k not in ("action", "outcome"))
        if unknown:
            raise CommandError(f"{path}: unknown keys {unknown}; allowed: action, outcome")
        if "action" not in data:
            raise CommandError(f"{path}: no 'action' key (a list of {action_size} numbers)")
        if "outcome" in data:
            outcome = _vector(data["outcome"], OUTCOME_SIZE, f"{path}: outcome")
        data = data["action"]
    elif not isinstance(data, list):
        raise CommandError(f"{path} must hold a list of {action_size} numbers or a mapping "
                           f"with 'action', not {type(data).__name__}")
    return _vector(data, action_size, f"{path}: action"), outcome


def _vector(values: Any, size: int, what: str) -> np.ndarray:
    if not isinstance(values, list):
        raise CommandError(f"{what} must be a list of {size} numbers, "
                           f"not {type(values).__name__}")
    if len(values) != size:
        raise CommandError(f"{what} has {len(values)} values, {size} are needed")
    return np.array([parse_unit(v, f"{what}[{i}]") for i, v in enumerate(values)])


def executed_demonstration(request: ExecuteFirst, landed: bool, outcome: Any,
                           message: str) -> SendDemonstration:
    """The demonstration of a file's action once the simulator has executed it."""
    if not landed:
        raise CommandError(f"the action of {request.path} did not land "
                           f"({message or 'no outcome'}): nothing sent")
    y = np.asarray(outcome, dtype=float)
    note = ""
    if request.file_outcome is not None:
        note = (f"; the file's outcome {fmt(request.file_outcome)} is "
                f"{np.linalg.norm(y - request.file_outcome):.3f} away and was not used")
    return SendDemonstration(request.action, y, -1,
                             f"the action of {request.path}, executed: outcome {fmt(y)}{note}")


def unexecuted_demonstration(request: ExecuteFirst, why: str) -> SendDemonstration:
    """The file's own outcome, when the simulator cannot be asked (``why``)."""
    if request.file_outcome is None:
        raise CommandError(f"cannot measure the outcome of {request.path}: {why}; start "
                           f"sim_bridge, or add 'outcome: [x, y]' to the file")
    return SendDemonstration(request.action, request.file_outcome, -1,
                             f"the action of {request.path} with the file's outcome "
                             f"{fmt(request.file_outcome)} (not executed: {why})")
