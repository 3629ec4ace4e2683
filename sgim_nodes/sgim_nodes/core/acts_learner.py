"""SGIM-ACTS (Nguyen & Oudeyer 2012) as an ask/tell learner: for each episode it chooses a
(strategy, region) pair and a goal (strategy_choice.py), learns by the strategy, and records
its competence at that goal in the pair's history (strategy_regions.py).

Driving it (the runner does this; the ROS nodes will do the same):

    while (request := learner.request()) is not None:      # a social strategy was chosen
        learner.on_answer(request, experts[request.teacher].answer(request.goal,
                                                                   request.wants_action))
    action, label = learner.next_action()
    learner.observe(action, world.execute(action))

- autonomous: a GoalAttempt toward the goal (goal_reaching.py), as SAGG-RIAC's;
- mimicry: the answer's (action, outcome) is stored as a demonstration, as SGIM-D stores it,
  then its action is imitated ``imitation_count`` times (imitation.py);
- emulation: the answer's outcome becomes the goal of a GoalAttempt; the teacher's action is
  not asked for and never enters memory, so every movement is the learner's own.

Every strategy's competence is measured at the goal the learner chose, against the closest
outcome memory held before the episode (competence.py): how much nearer that goal the episode
brought the learner, whoever showed what. An unanswered request ("none there") ends the
episode at once with no movement and competence -1: the pair shows no progress, and the
request's cost was spent. Movements keep their process labels (goal_directed, exploration,
imitation: what the graph's codes know); ``movement_strategy`` says which strategy made the
movement, and ``choices`` logs every choice for analysis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .acts_episode import EMULATE, IMITATE, after_answer
from .competence import NearestOutcome, start_distance
from .config import LearnerConfig
from .environment import ResultLike
from .experts import ExpertAnswer
from .goal_reaching import GoalAttempt, probe_scale_for
from .imitation import Imitation
from .learner_base import DEMONSTRATION, Learner, region_tree_for
from .random_streams import component_rng
from .scale import WorldScale
from .strategies import AUTONOMOUS, MIMICRY, Strategy, all_strategies
from .strategy_choice import PairChoice, StrategyChooser
from .strategy_regions import StrategyRegions


def _vec(x: np.ndarray | None) -> list[float] | None:
    return None if x is None else [float(v) for v in np.asarray(x).ravel()]


@dataclass(frozen=True)
class Request:
    """The learner asks ``teacher`` about ``goal``: for its action and outcome (mimicry,
    ``wants_action``) or for the outcome only (emulation)."""

    index: int  # requests made so far, from 0
    movement: int  # movements done when it was asked
    strategy: Strategy
    goal: np.ndarray

    @property
    def teacher(self) -> str:
        return self.strategy.teacher

    @property
    def wants_action(self) -> bool:
        return self.strategy.wants_action

    def to_record(self) -> dict:
        return {"type": "request", "request": self.index, "movement": self.movement,
                "strategy": self.strategy.name, "teacher": self.teacher,
                "goal": _vec(self.goal), "wants_action": self.wants_action,
                "cost": self.strategy.cost}


@dataclass
class ChoiceLog:
    """One episode's choice, for analysis: when, how, where, and what came of it."""

    movement: int
    strategy: str
    teacher: str | None
    mode: int
    region_low: list[float]
    region_high: list[float]
    goal: list[float]
    request: int | None = None
    answered: bool | None = None
    competence: float | None = None

    def to_record(self) -> dict:
        return {"type": "strategy_choice", **self.__dict__}


@dataclass
class Episode:
    """One chosen (strategy, goal) and the process carrying it out; tracks the outcome
    nearest the chosen goal over the episode's successful movements."""

    choice: PairChoice
    start_distance: float
    log: ChoiceLog
    process: GoalAttempt | Imitation | None = None
    nearest: NearestOutcome | None = None

    def __post_init__(self) -> None:
        self.nearest = NearestOutcome(self.choice.goal)

    @property
    def done(self) -> bool:
        return self.process is None or self.process.done

    def observe(self, action: np.ndarray, result: ResultLike) -> None:
        self.nearest.observe(result)
        self.process.observe(action, result)


class SgimActsLearner(Learner):
    """SGIM-ACTS over the teachers named ``teachers`` (module docstring); ``strategies``
    (default: autonomous, then mimicry and emulation of each teacher) are Strategy values,
    e.g. from strategies.parse_strategies."""

    social = True

    def __init__(self, action_dim: int, outcome_dim: int, seed: int,
                 config: LearnerConfig | None = None, scale: WorldScale | None = None,
                 teachers: Sequence[str] = (),
                 strategies: Sequence[Strategy] | None = None) -> None:
        super().__init__(action_dim, outcome_dim, seed, config, scale)
        c = self.config
        self.teachers = tuple(teachers)
        self.strategies = (all_strategies(self.teachers, c) if strategies is None
                           else tuple(strategies))
        for s in self.strategies:
            if s.teacher is not None and s.teacher not in self.teachers:
                raise ValueError(f"strategy {s.name} asks unknown teacher {s.teacher!r}; "
                                 f"known teachers: {', '.join(self.teachers) or 'none'}")
        self.regions = StrategyRegions(region_tree_for(c, self.scale),
                                       [s.name for s in self.strategies])
        self.chooser = StrategyChooser(self.regions, self.strategies,
                                       (c.p_mode1, c.p_mode2, c.p_mode3),
                                       c.distances(self.scale).mode3_radius,
                                       c.strategy_choice_order, c.strategy_value)
        self.choice_rng = component_rng(seed, "strategies")
        self.probe_scale = probe_scale_for(c, self.scale, action_dim)
        self.episode: Episode | None = None
        self.pending: Request | None = None
        self.choices: list[ChoiceLog] = []
        self.cost_spent: dict[str, float] = {s.name: 0.0 for s in self.strategies}
        self.n_requests = 0
        self.n_unanswered = 0
        self.movement_strategy = ""

    # --- the request API ---
    def request(self) -> Request | None:
        """The question the learner needs answered before its next movement, or None. While
        an episode runs there is none; a pending request is returned again until answered."""
        if self.pending is not None:
            return self.pending
        if self.episode is not None and not self.episode.done:
            return None
        return self.begin(self.chooser.sample(self.choice_rng))

    def begin(self, choice: PairChoice) -> Request | None:
        """Start the episode ``choice`` names and return its request, if it asks a teacher.
        request() begins the chooser's choices; a tool that compares strategies on the same
        goals begins its own (strategy_precheck.py)."""
        if self.pending is not None or (self.episode is not None and not self.episode.done):
            raise RuntimeError("begin: the learner's current episode has not ended")
        if choice.strategy not in self.strategies:
            raise ValueError(f"begin: {choice.strategy.name} is not one of the learner's "
                             f"strategies")
        closest = self.memory.closest_distance(choice.goal)
        region = choice.region
        log = ChoiceLog(self.n_movements, choice.strategy.name, choice.strategy.teacher,
                        choice.mode, _vec(region.low), _vec(region.high), _vec(choice.goal))
        self.choices.append(log)
        self.cost_spent[choice.strategy.name] += choice.strategy.cost
        self.episode = Episode(choice, start_distance(closest, choice.goal, self.scale.centre),
                               log)
        if choice.strategy.kind == AUTONOMOUS:
            self.episode.process = self._attempt(choice.goal)
            return None
        self.pending = Request(self.n_requests, self.n_movements, choice.strategy,
                               choice.goal.copy())
        log.request = self.n_requests
        self.n_requests += 1
        return self.pending

    def on_answer(self, request: Request, answer: ExpertAnswer | None) -> None:
        """The teacher's answer to ``request`` (None: it has no demonstration near the goal)."""
        if request is not self.pending:
            raise ValueError("on_answer: not the learner's pending request")
        if answer is not None and answer.teacher != request.teacher:
            raise ValueError(f"request {request.index} asked {request.teacher!r}, the answer "
                             f"comes from {answer.teacher!r}")
        kind = request.strategy.kind
        if kind == MIMICRY and answer is not None and answer.action is None:
            raise ValueError(f"request {request.index} asked {request.teacher!r} for its "
                             f"action (mimicry); the answer shows none")
        self.pending = None
        episode = self.episode
        c = self.config
        step = (after_answer(kind, None, None, c.imitation_count) if answer is None else
                after_answer(kind, answer.action, answer.outcome, c.imitation_count))
        episode.log.answered = step.kind in (IMITATE, EMULATE)
        if step.stores:
            self.memory.add(step.action, step.outcome, DEMONSTRATION)
        if step.kind == IMITATE:
            episode.process = Imitation(step.action, step.outcome, step.repetitions,
                                        c.imitation_epsilon, self.rngs.imitation)
        elif step.kind == EMULATE:
            episode.process = self._attempt(step.outcome)
        else:
            self.n_unanswered += 1
        if episode.done:  # none there, or imitation_count 0: nothing to move
            self._end(episode)

    # --- the shared learner API ---
    def next_action(self) -> tuple[np.ndarray, str]:
        if self.request() is not None:
            raise RuntimeError("sgim-acts is waiting for an answer: call request() and "
                               "on_answer() until request() is None before next_action()")
        action, label = self.episode.process.next_action()
        self._last_label = label
        self.movement_strategy = self.episode.choice.strategy.name
        return action, label

    def _after_observe(self, action: np.ndarray, result: ResultLike) -> None:
        episode = self.episode
        if episode is None or episode.done:
            return
        episode.observe(action, result)
        if episode.done:
            self._end(episode)

    def on_demonstration(self, action: np.ndarray | None, outcome: np.ndarray | None) -> None:
        """SGIM-ACTS asks for its demonstrations (request/on_answer); an unsolicited one is
        ignored, as SAGG-RIAC ignores them."""

    # --- internals ---
    def _attempt(self, goal: np.ndarray) -> GoalAttempt:
        return GoalAttempt(goal, self.memory, self.inverse_model, self.config, self.scale,
                           self.rngs.explorer, self.action_dim, self.probe_scale)

    def _end(self, episode: Episode) -> None:
        """The episode's competence at its chosen goal goes to its (strategy, region) pair."""
        comp = self.config.distances(self.scale).competence(
            episode.choice.goal, episode.nearest.outcome, episode.start_distance)
        episode.log.competence = comp
        self.regions.add(episode.choice.strategy.name, episode.choice.goal, comp)
