"""The learners as compositions of the core parts, driven movement by movement.

API shared by all learners (what a ROS node calls):
  ``next_action() -> (action, process_label)``  the next movement to execute;
  ``observe(action, result)``                   its result (``.outcome``, ``.status``);
  ``on_demonstration(action, outcome)``         a teacher's demonstration (social part);
  ``inverse(goal)``                             the inverse model, for the evaluator.
Successful movements are stored in memory; failed ones count as movements but are not stored.

Each is declared, with its traits, in learner_registry.py: SGIM-D (goal babbling that stores,
imitates and learns the interest of each demonstration: it interrupts the goal attempt under
way at the next movement boundary, imitates the demonstration ``imitation_count`` times, and
its outcome becomes an attempted goal whose competence, the best imitation's, feeds the region
tree), SAGG-RIAC (goal babbling; demonstrations ignored), random goals (goals uniform in the
outcome box, the same lower level: "SAGG-Random", Baranes & Oudeyer 2013, the yardstick that
tells what the interest adds), demonstrations only (a small variation of the latest
demonstration, random actions before the first), random actions, and SGIM-ACTS
(acts_learner.py).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import numpy as np

from .competence import start_distance
from .config import LearnerConfig
from .environment import ResultLike
from .goal_reaching import GoalAttempt, probe_scale_for
from .goal_selection import GoalSelector
from .imitation import IMITATION, Imitation, perturb

# The aliased ones are re-exported: the nodes, the evaluator and tests build with them.
from .learner_base import DEMONSTRATION, Learner, region_tree_for
from .learner_base import build_memory as build_memory
from .learner_base import inverse_model_for as inverse_model_for
from .learner_base import inverse_or_centre as inverse_or_centre
from .scale import WorldScale

RANDOM_LABEL = "random"
"""The process label of a random movement (environment.PROCESS_CODES)."""


class RandomLearner(Learner):
    def next_action(self) -> tuple[np.ndarray, str]:
        self._last_label = RANDOM_LABEL
        return self.rngs.random.uniform(-1.0, 1.0, self.action_dim), RANDOM_LABEL


class DemoOnlyLearner(Learner):
    social = True

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.latest_demo: np.ndarray | None = None
        self.latest_outcome: np.ndarray | None = None

    def on_demonstration(self, action: np.ndarray | None, outcome: np.ndarray | None) -> None:
        """Only an action can be varied: a goal-only demonstration (teaching.py) is refused."""
        if action is None:
            raise ValueError(f"{self.name} varies demonstrated actions: it cannot learn from a "
                             "goal-only demonstration")
        self.latest_demo = np.asarray(action, dtype=float).copy()
        self.latest_outcome = None if outcome is None else np.asarray(outcome, dtype=float).copy()
        if outcome is not None:  # a means-only demonstration: the outcome was not shown
            self.memory.add(self.latest_demo, self.latest_outcome, DEMONSTRATION)

    def aim(self) -> np.ndarray | None:
        """The demonstrated outcome its variations aim at (None before the first, or after a
        means-only one)."""
        return self.latest_outcome

    def next_action(self) -> tuple[np.ndarray, str]:
        if self.latest_demo is None:
            self._last_label = RANDOM_LABEL
            return self.rngs.random.uniform(-1.0, 1.0, self.action_dim), RANDOM_LABEL
        self._last_label = IMITATION
        return perturb(self.latest_demo, self.config.imitation_epsilon, self.rngs.imitation), (
            IMITATION)


class GoalBabblingLearner(Learner):
    """SAGG-RIAC; with ``social=True`` it is SGIM-D; a learner declared with goal modes of its
    own (random goals) draws its goals by them (the region tree still records them, for the
    plots)."""

    def __init__(self, action_dim: int, outcome_dim: int, seed: int,
                 config: LearnerConfig | None = None, scale: WorldScale | None = None,
                 social: bool = False,
                 goal_modes: tuple[float, float, float] | None = None) -> None:
        super().__init__(action_dim, outcome_dim, seed, config, scale)
        c = self.config
        self.social = social
        self.tree = region_tree_for(c, self.scale)
        self.probe_scale = probe_scale_for(c, self.scale, action_dim)
        self.selector = GoalSelector(self.tree, goal_modes or (c.p_mode1, c.p_mode2, c.p_mode3),
                                     c.distances(self.scale).mode3_radius)
        self.process: GoalAttempt | Imitation | None = None
        # (action, outcome, memory's distance to the outcome before it was stored); the action
        # is None for a goal-only demonstration, the outcome None for a means-only one
        self.pending_demos: deque[tuple[np.ndarray | None, np.ndarray | None, float]] = deque()
        self.last_goal_mode = 0
        self.n_goals = 0
        # Called with (goal, competence) when one of its own goal attempts ends (not an
        # imitation): what a learner that asks for help watches (help_request.py).
        self.attempt_listeners: list[Callable[[np.ndarray, float], None]] = []

    def on_demonstration(self, action: np.ndarray | None, outcome: np.ndarray | None) -> None:
        """Store what was shown and queue its follow-up (teaching.py's contents): with both, the
        pair enters memory and is imitated (the paper's SGIM-D); with the outcome only, the
        learner adopts it as its next goal (emulation); with the action only, it imitates the
        action and learns where it lands from its own movements."""
        if not self.social:
            return
        a = None if action is None else np.asarray(action, dtype=float).copy()
        y = None if outcome is None else np.asarray(outcome, dtype=float).copy()
        if a is None and y is None:
            raise ValueError("a demonstration shows an action, an outcome or both")
        before = (float("inf") if y is None else
                  start_distance(self.memory.closest_distance(y), y, self.scale.centre))
        if a is not None and y is not None:
            self.memory.add(a, y, DEMONSTRATION)
        self.pending_demos.append((a, y, before))

    def _new_process(self) -> GoalAttempt | Imitation:
        c = self.config
        if self.pending_demos:
            a, y, before = self.pending_demos.popleft()
            if a is None:  # goal-only: an attempt at the demonstrated outcome, as a goal
                return GoalAttempt(y, self.memory, self.inverse_model, c, self.scale,
                                   self.rngs.explorer, self.action_dim, self.probe_scale)
            if c.imitation_count > 0:
                return Imitation(a, y, c.imitation_count, c.imitation_epsilon,
                                 self.rngs.imitation, start_distance=before)
        choice = self.selector.sample(self.rngs.goals)
        self.last_goal_mode = choice.mode
        return GoalAttempt(choice.goal, self.memory, self.inverse_model, c, self.scale,
                           self.rngs.explorer, self.action_dim, self.probe_scale)

    def next_action(self) -> tuple[np.ndarray, str]:
        if self.pending_demos and isinstance(self.process, GoalAttempt) and not self.process.done:
            self._interrupt()
        if self.process is None or self.process.done:
            self.process = self._new_process()
        action, label = self.process.next_action()
        self._last_label = label
        return action, label

    def on_teacher_turn(self) -> None:
        """The teacher interrupts the intrinsic loop at every one of its turns, even when it
        has nothing left to show (the learner then simply chooses a new goal): the graph's
        arbiter must stop the running job at the teacher's boundary before it knows what the
        teacher will say, and the single-process learner behaves the same."""
        if self.social and isinstance(self.process, GoalAttempt) and not self.process.done:
            self._interrupt()

    def _interrupt(self) -> None:
        """A demonstration preempts the goal attempt at this movement boundary (as the graph's
        arbiter cancels the explorer's job): the goal's competence is what it reached so far."""
        attempt = self.process
        if attempt.movements > 0:
            self._record_competence(attempt)
        self.process = None

    def _after_observe(self, action: np.ndarray, result: ResultLike) -> None:
        p = self.process
        if p is None:
            return
        p.observe(action, result)
        if p.done:
            self._record_competence(p)

    def _record_competence(self, process: GoalAttempt | Imitation) -> float | None:
        """Competence of the attempt (or imitation) against memory before it (competence.py);
        None for a means-only imitation, which has no goal."""
        if process.goal is None:
            return None
        comp = self.config.distances(self.scale).competence(
            process.goal, process.best_outcome, process.start_distance)
        self.tree.add(process.goal, comp)
        self.n_goals += 1
        if isinstance(process, GoalAttempt):
            for listener in self.attempt_listeners:
                listener(process.goal, comp)
        return comp

