"""The arbiter's side of SGIM-ACTS (issue 33): the episodes whose strategy asks a teacher.

The goal generator draws each episode's (strategy, goal) (core/strategy_choice.py) when the
explorer asks for its next goal; an autonomous one the explorer attempts at once, a social
one ends its reach_goal job and comes here (ReachGoal.Result.social), with the memory's
distance to the goal when it was chosen. The arbiter then translates the episode's steps, the
core's rules that SgimActsLearner carries out too (core/acts_episode.py):

- it asks the strategy's teacher on `help_requests` (HelpRequest naming the teacher, and
  content means-and-goal for mimicry, goal-only for emulation) and waits for its answer on
  `demonstrations` (source "expert:NAME", `help_request` its index);
- mimicry: the shown action and, when the teacher's cast landed, its outcome are registered
  in the explorer's memory, then the action is imitated `imitation_count` times;
- emulation: the teacher's outcome is reached by the explorer (one goal, its action never
  known);
- the competence goes to the goal generator and the interest computer as a Competence that
  names the strategy, measured at the chosen goal; "none there" (an empty answer, or one
  without what the strategy needs) ends the episode with competence -1 and no movement.

An episode the budget cuts short folds no competence, as the core's does not.
"""

from __future__ import annotations

from sgim_msgs.action import Imitate, ReachGoal
from sgim_msgs.msg import Competence, Demonstration, Goal, HelpRequest
from sgim_msgs.srv import RegisterDemonstration
from sgim_nodes.bag.record_checks import expert_source
from sgim_nodes.core.acts_episode import (
    EMULATE,
    MAX_REQUESTS_IN_A_ROW,
    NONE_THERE,
    after_answer,
    folds,
    request_content,
)
from sgim_nodes.nodes.help_asks import HELP_REQUESTS
from sgim_nodes.nodes.ros_glue import floats, vec


class ActsEpisodes:
    """Requests to the teachers, their answers, and the social episodes they start; driven by
    the arbiter node (social_interaction), whose jobs and counts it uses."""

    def __init__(self, arbiter) -> None:
        self.arbiter = arbiter
        self.requests = 0
        self.in_a_row = 0  # requests since the last movement
        self.answers: dict[int, Demonstration] = {}
        self._asked: dict[int, tuple[str, int]] = {}  # index -> (teacher, movement)
        self._out = HELP_REQUESTS.create(arbiter)

    def resume(self, records) -> None:
        """Requests go on numbering after the recorded ones."""
        self.requests = max((h.index for h in records.help_requests), default=0)

    def receive(self, msg: Demonstration) -> None:
        """A teacher's answer, kept; refused (logged, announced) when it is invalid or not
        one to a request of this run."""
        node = self.arbiter
        problem = node.gate.check("demonstrations", msg)
        why = problem.detail if problem is not None else self._unexpected(msg)
        if why:
            node.say_refusal(f"demonstration {msg.index} refused: {why}")

    def _unexpected(self, msg: Demonstration) -> str:
        """'' or why it is not an answer to a request of this run."""
        index = int(msg.help_request)
        if index not in self._asked:
            return f"it answers help request {index}, which the learner never made"
        teacher, movement = self._asked[index]
        if index in self.answers:
            return f"help request {index} was answered already"
        if msg.source != expert_source(teacher):
            return (f"it answers help request {index} as {msg.source!r}, but the learner "
                    f"asked {expert_source(teacher)!r}")
        if int(msg.movement_index) != movement:
            return (f"it answers help request {index} at movement {int(msg.movement_index)}, "
                    f"but the learner asked at {movement}")
        self.answers[index] = msg
        return ""

    async def after_attempt(self, result: ReachGoal.Result) -> None:
        """After the explorer's job: the social episode it handed back, if any."""
        if result.movements_used:
            self.in_a_row = 0
        if len(result.social.point):
            await self.run(result.social, result.social_start_distance)

    async def run(self, goal: Goal, start: float) -> None:
        """One social episode toward the chosen ``goal`` (memory's distance ``start``)."""
        node = self.arbiter
        kind, _, teacher = goal.strategy.partition(":")
        self.in_a_row += 1
        if self.in_a_row > MAX_REQUESTS_IN_A_ROW:
            raise RuntimeError(f"sgim-acts made {MAX_REQUESTS_IN_A_ROW} requests in a row and "
                               "none gave a movement: its teachers answer none there and it "
                               "has no autonomous strategy")
        answer = await self._ask(goal, teacher, kind)
        step = after_answer(kind, vec(answer.action) if len(answer.action) else None,
                            vec(answer.outcome) if len(answer.outcome) else None,
                            node.config.imitation_count)
        if step.kind == NONE_THERE:  # the request cost, the pair shows no progress
            self._publish(goal, None, 0)
            return
        self.in_a_row = 0
        node.publish_taken(answer)
        if step.kind == EMULATE:  # the explorer reaches the outcome, measured at the goal
            result = await node.run_job(node.reach, emulation_job(
                goal, start, answer.outcome, node.cap(), node.count, node.goals_folded),
                "reach_goal")
            node.goals_folded += result.goals_attempted
            return
        if step.stores:  # its cast landed: the memory holds it, as SGIM-D's does
            reply = await node.call(node.register_client,
                                    RegisterDemonstration.Request(demonstration=answer),
                                    "register_demonstration")
            if not reply.accepted:
                node.get_logger().error(f"the explorer refused demonstration {answer.index}: "
                                        f"{reply.message}")
        repetitions = min(step.repetitions, node.total - node.count)  # never past the budget
        made, best = 0, None
        if repetitions > 0:
            result: Imitate.Result = await node.imitation(answer, repetitions, goal.point)
            made = result.movements_used
            best = vec(result.best_outcome) if len(result.best_outcome) else None
        if folds(step, made):
            self._publish(goal, best, made, start)

    async def _ask(self, goal: Goal, teacher: str, kind: str) -> Demonstration:
        node = self.arbiter
        self.requests += 1
        index = self.requests
        self._asked[index] = (teacher, node.count)
        node.get_logger().info(f"request {index} to {teacher} at movement {node.count} "
                               f"({goal.strategy}, goal {[round(x, 3) for x in goal.point]})")
        self._out.publish(HelpRequest(
            stamp=node.get_clock().now().to_msg(), index=index, movement_index=node.count,
            goal=list(goal.point), teacher=teacher, content=request_content(kind)))
        await node.waits.until(lambda: index in self.answers, node.p["teacher_timeout"],
                               f"the answer of teacher {teacher!r} to request {index} "
                               f"(is its expert node running?)")
        return self.answers.pop(index)

    def _publish(self, goal: Goal, best, used: int, start: float = 0.0) -> None:
        """The episode's competence at its chosen goal (-1 without an outcome)."""
        node = self.arbiter
        comp = node.distances.competence(vec(goal.point), best, start)
        node.publish_competence(Competence(
            stamp=node.get_clock().now().to_msg(), goal_index=goal.index,
            movement_index=node.count, goal=list(goal.point), reached=floats(best),
            competence=comp, movements_used=used, from_demonstration=False,
            strategy=goal.strategy))


def emulation_job(goal: Goal, start: float, outcome, cap: int, count: int,
                  goals_before: int) -> ReachGoal.Goal:
    """The reach_goal job of an emulation: the teacher's outcome to reach, measured at the
    chosen goal."""
    return ReachGoal.Goal(max_movements=cap, max_goals=1, movements_before=count,
                          goals_before=goals_before, demonstrated=list(outcome), chosen=goal,
                          chosen_start_distance=start)
