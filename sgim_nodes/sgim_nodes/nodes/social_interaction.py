"""social_interaction: the arbiter that drives a run, movement budget to final evaluation.

It owns the movement count and runs one job at a time: goal attempts (the explorer's
`reach_goal` action, which asks the goal generator for each goal itself and goes on from goal
to goal up to the arbiter's next boundary), an imitation (`imitate`), or a movement of the
core learner it hosts, according to how the learner's declaration says the graph hosts it
(core/learner_registry.py):
  goal babbling  the explorer's goal attempts; a social learner's demonstrations are
                 registered in the explorer's memory, imitated `imitation_count` times, and
                 their outcomes enter the interest computation with the competence of the best
                 imitation (SGIM-D);
  episodes       goal babbling whose goals each come with a strategy: an autonomous one is
                 attempted by the explorer, a social one asks its teacher (SGIM-ACTS,
                 acts_episodes.py);
  in the arbiter the core learner itself, built here as the runner builds it: its next action
                 is executed through the simulator and its result told back, movement by
                 movement, and the demonstrations it takes are given to it (random actions,
                 demonstrations only, and a learner of another package).
A demonstration preempts the intrinsic loop at the next movement boundary: with the automatic
teacher (`teacher: automatic`) the arbiter knows the teacher's period and stops every job at
the teacher's boundaries, then waits for its word (a demonstration, or an empty one when it has
nothing left to show), which makes a run reproducible; with a human teacher demonstrations come
at any time and the running job is cancelled, honoured at its next movement boundary; a human
teacher can also pause, resume and step the run and be given a turn every P movements
(`wait_for_teacher`; see pace.py). With `timing: on-request` (issue 14) the automatic teacher
has no boundaries: the learner asks for help on `help_requests` when its progress stalls
(help_asks.py, the core's rule) and waits for the teacher's answer.

What a demonstration shows (its `content`, core/teaching.py) decides what the learner does
with it, as the single-process learner does: both parts (the paper's) are registered in the
explorer's memory and imitated; a goal-only one is adopted as the next goal (a reach_goal job of
that one goal, whose choose_goal names it, Goal.MODE_DEMONSTRATION) and reached like any goal,
its action never known; a means-only
one is imitated without a goal, nothing stored, no competence.

The budget is exact: an imitation is cut to the movements left, and a demonstration that is
invalid (bag/validation.py: sizes, bounds, a known teaching-set index) or comes once the
budget is spent is refused, logged and announced on run_status (it stays in the bag). Each
demonstration the learner takes is republished on `demonstrations_taken` with the count at
which it entered the learner's memory: the evaluator and the bag readers use those only.

Its topics, services and actions: INTERFACES below (and docs/reference.md).
Parameters: the common ones, every LearnerConfig field, movements, teacher,
demonstration_period, timing, wait_for_teacher, wait_for_evaluation, wait_for_recorder,
goals_per_job, timeouts.
"""

from __future__ import annotations

import time
from typing import Any

from rclpy.action import ActionClient
from rclpy.duration import Duration

from sgim_msgs.action import Imitate, ReachGoal
from sgim_msgs.msg import Competence, Demonstration, Evaluation, RunStatus
from sgim_msgs.srv import ExecuteAction, RegisterDemonstration
from sgim_nodes.bag.record_checks import Limits, teaching_set_size
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.bag.validation import LiveGate
from sgim_nodes.core.environment import PROCESS_CODES, MovementResult
from sgim_nodes.core.help_request import ON_REQUEST
from sgim_nodes.core.learner_registry import IN_ARBITER, learner_kind, make_learner
from sgim_nodes.core.schedule import Schedule
from sgim_nodes.core.teaching import GOAL_ONLY, MEANS_ONLY
from sgim_nodes.nodes.acts_episodes import ActsEpisodes
from sgim_nodes.nodes.arbiter_jobs import JobSlot, Waits
from sgim_nodes.nodes.arbiter_params import PARAMS
from sgim_nodes.nodes.demonstration_inbox import DemonstrationInbox, shown
from sgim_nodes.nodes.graph_startup import (
    READY_CALLS,
    ExpectedGraph,
    RunAborted,
    arbiter_graph,
    call_bounded,
    wait_for_graph,
)
from sgim_nodes.nodes.help_asks import HELP_REQUESTS, HelpAsks, resume_schedule
from sgim_nodes.nodes.imitation_turn import as_message, imitation_competence, resumed_cut
from sgim_nodes.nodes.pace import PACE_INTERFACES, PaceControl
from sgim_nodes.nodes.ros_glue import (
    AsyncNode,
    declare_learner,
    floats,
    teacher_names,
    vec,
    world_scale,
)
from sgim_nodes.nodes.run_progress import RUN_STATUS, RunProgress
from sgim_nodes.nodes.sim_client import EXECUTE, SimClient, SimulatorError
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import action_client, calls, declared, publishes, subscribes
from sgim_ros.params import ParameterError

REGISTER, TAKEN = calls("register_demonstration"), publishes("demonstrations_taken")
REACH, IMITATE = action_client("reach_goal"), action_client("imitate")
COMPETENCES = publishes("competences")  # of demonstrated goals, and of hosted learners'
DEMONSTRATIONS, EVALUATIONS = subscribes("demonstrations"), subscribes("evaluations")
INTERFACES = declared(REGISTER, TAKEN, REACH, IMITATE, COMPETENCES, DEMONSTRATIONS, EVALUATIONS,
                      EXECUTE, RUN_STATUS, HELP_REQUESTS, PACE_INTERFACES, READY_CALLS)


class SocialInteraction(AsyncNode):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("social_interaction", **node_options)
        values, self.config = declare_learner(self, PARAMS)
        self.p = values
        self.learner = values["learner"]
        self.kind = learner_kind(self.learner)
        self.acts = self.kind.chooses_teachers
        self.total = values["movements"]
        social = self.kind.social and values["teacher"] != "none"
        self.automatic = social and values["teacher"] == "automatic"
        on_request = social and values["timing"] == ON_REQUEST
        if on_request and not self.automatic:
            raise ParameterError("timing 'on-request' needs the automatic teacher (teacher: "
                                 "automatic): it answers the learner's help requests")
        refusal = self.kind.refusal(timing=ON_REQUEST) if on_request else ""
        if refusal:
            raise ParameterError(refusal)
        # When the teacher takes its turn and the learner asks: the core's schedule, as the
        # runner's (core/schedule.py); the arbiter caps its jobs where it says.
        self.schedule = Schedule(self.total, values["demonstration_period"], values["timing"],
                                 teacher=self.automatic)
        self.social = social
        scale = world_scale(values)
        self.distances = self.config.distances(scale)
        self.centre = scale.centre
        self.cut, self.cut_start = None, float("inf")  # an imitation a kill cut (resume.py)
        # The core learner itself, when the arbiter hosts it (module docstring).
        self.hosted = (make_learner(self.learner, values["action_size"],
                                    values["outcome_size"], values["seed"], self.config, scale)
                       if self.kind.host == IN_ARBITER else None)
        self.count = 0
        self.goals_folded = 0  # competences published so far (by the explorer and by us)
        # Goals per reach_goal job: with timing on-request, each attempt ends at the arbiter,
        # which tells the help rule (help_asks.py) before it decides the next cap.
        self.goals_per_job = 1 if on_request else values["goals_per_job"]
        self.evaluated: set[int] = set()
        self.finished, self.exit_code = False, 0
        self.job = JobSlot(self)  # the running action, to cut on a demonstration
        self.waits = Waits(self)
        self.progress = RunProgress(self, self.learner, values["seed"], self.total,
                                    lambda: self.count)

        self.asks = HelpAsks(self, self.schedule) if on_request else None
        self.pace = None  # pause, step and teacher turns: for a human teacher only
        if social and values["teacher"] == "human":
            self.pace = PaceControl(self, self.total, values["demonstration_period"],
                                    values["wait_for_teacher"], self._preempt_goal)
        self.episodes = ActsEpisodes(self) if self.acts else None
        self.sim = SimClient(self, values)
        self.register_client = REGISTER.create(self)
        self.reach, self.imitate = REACH.create(self), IMITATE.create(self)
        self._taken = TAKEN.create(self)
        self.gate = LiveGate(self.get_logger().error, Limits(
            values["action_size"], values["outcome_size"], budget=self.total,
            teaching_set_size=teaching_set_size(values["teaching_set"] or None)))
        self.inbox = DemonstrationInbox(self.gate, self.total, self.automatic, self.asks,
                                        self.say_refusal)
        self._competences = COMPETENCES.create(self)
        DEMONSTRATIONS.create(self, self._on_demo)
        EVALUATIONS.create(self, self._on_evaluation)
        if values["resume_from"]:
            self._resume(resume_point(values["resume_from"], self.config,
                                 values["resume_segments"]))
        self._start_timer = self.create_timer(0.05, self._start)

    def _resume(self, point) -> None:
        self.count = point.count
        self.goals_folded = point.state.n_competences
        if self.episodes is not None:
            self.episodes.resume(point.records)
        resume_schedule(self.schedule, point.records, point.count, point.demonstration_turns)
        self.evaluated = set(point.evaluated)
        if self.social and not self.acts and self.hosted is None:
            self.cut, self.cut_start = resumed_cut(point, self.config, self.total,
                                                   self.centre)
        demo = point.latest_demonstration
        if demo is not None and self.hosted is not None and self.social:
            self.hosted.on_demonstration(*shown_parts(demo))
        self.get_logger().info(f"resuming at movement {self.count}/{self.total}")

    # --- events -------------------------------------------------------------------------
    def _on_demo(self, msg: Demonstration) -> None:
        if self.acts:  # a teacher's answer to one of its requests
            self.episodes.receive(msg)
        elif self.social and self.inbox.receive(msg, self.count):
            self.job.cancel()  # preempt: honoured at the job's next movement boundary
        self._wake()

    def _on_evaluation(self, msg: Evaluation) -> None:
        if self.gate.check("evaluations", msg):
            return
        self.evaluated.add(msg.movement_index)
        self._wake()

    def _preempt_goal(self) -> None:
        """Cut a goal attempt at its next movement boundary (an imitation is never cut)."""
        self.job.cancel(only="reach_goal")

    def _wake(self) -> None:
        if self.pace is not None:
            self.pace.notify()
        self.waits.check()

    # --- the run ----------------------------------------------------------------------------
    async def _start(self) -> None:
        self._start_timer.cancel()
        try:
            await wait_for_graph(self, self._expected_graph(), self.p["startup_timeout"],
                                 self.p["settle_time"])
            self.progress.say(RunStatus.STATE_RUNNING,
                              f"resumed at {self.count}" if self.count else "started")
            await self._run()
            self.inbox.refuse_waiting()
            self.progress.say(RunStatus.STATE_RUNNING, "movement budget spent")
            if self.p["wait_for_evaluation"]:
                await self.waits.until(lambda: self.total in self.evaluated,
                                       self.p["evaluation_timeout"],
                                       f"the evaluation at movement {self.total} (evaluator)")
            if self.inbox.refused:
                self.progress.say(RunStatus.STATE_RUNNING, f"{self.inbox.refused} "
                                  "demonstrations refused in all (see the arbiter's log)")
            self.progress.say(RunStatus.STATE_FINISHED, "finished")
            self.get_logger().info(f"run finished: {self.count} movements in "
                                   f"{time.monotonic() - self.progress.started:.1f} s")
        except (RunAborted, SimulatorError) as error:
            self.get_logger().error(f"run aborted: {error}")
            self.progress.say(RunStatus.STATE_ABORTED, str(error))
            self.exit_code = 1
        # The last status must reach the recorder and the launcher before this process ends.
        self.progress.publisher.wait_for_all_acked(Duration(seconds=5.0))
        self.finished = True

    def _expected_graph(self) -> ExpectedGraph:
        """The servers, publishers and listeners this run needs (graph_startup.py)."""
        return arbiter_graph(self.learner, self.social, self.automatic,
                             self.p["wait_for_recorder"], self.p["wait_for_evaluation"],
                             execute=self.sim.client, reach=self.reach,
                             register=self.register_client, imitate=self.imitate,
                             teachers=teacher_names(self.p["teachers"]) if self.acts else ())

    async def call(self, client, request, name: str):
        """A service call that gives up after call_timeout (RunAborted naming the service)."""
        return await call_bounded(self, client, request, name, self.p["call_timeout"])

    async def _run(self) -> None:
        if self.cut is not None:
            await self._finish_cut_imitation(self.cut)
            self.cut = None
        while self.count < self.total:
            if self.pace is not None:
                await self.pace.hold(self.count)
                if (self.pace.turn_due(self.count)
                        and self.count not in self.schedule.turns_taken):
                    self.schedule.take_turn(self.count)
                    how = await self.pace.teacher_turn(self.count, lambda: bool(self.inbox.pending))
                    self.get_logger().info(f"teacher's turn at movement {self.count}: {how}")
                    continue
            if self.schedule.turn_due(self.count):
                self.schedule.take_turn(self.count)
                await self.waits.until(lambda b=self.count: b in self.inbox.boundary_word,
                                       self.p["teacher_timeout"],
                                       f"the teacher's word at movement {self.count}")
                word = self.inbox.boundary_word.pop(self.count)
                if shown(word):
                    await self._take_demonstration(word)
                continue
            if self.asks is not None and self.schedule.ask_due(self.count):
                await self._ask_for_help()
                continue
            if self.inbox.pending:
                await self._take_demonstration(self.inbox.pending.popleft())
                self._paced()
                continue
            cap = self.cap()
            if self.acts:  # a social goal comes back from the explorer: its episode
                await self.episodes.after_attempt(await self.goal_attempt(cap))
            elif self.hosted is not None:
                await self._hosted_movement()
            else:
                await self.goal_attempt(cap)
            self._paced()
            self.progress.moved()

    def cap(self) -> int:
        """Movements the next job may make: to the budget, the teacher's next boundary, a
        human's step, or where a stalled learner earns its next ask."""
        cap = self.schedule.cap(self.count)
        if self.pace is not None:
            cap = min(cap, self.pace.cap(cap))
        return cap

    async def _ask_for_help(self) -> None:
        """Ask the teacher (help_requests) and wait for its answer, as at a boundary."""
        ask = self.asks.ask(self.count)
        self.get_logger().info(f"help request {ask.index} at movement {self.count} (goal "
                               f"{[round(x, 3) for x in ask.goal]})")
        await self.waits.until(lambda i=ask.index: i in self.asks.answers,
                               self.p["teacher_timeout"],
                               f"the teacher's answer to help request {ask.index} at movement "
                               f"{self.count}")
        word = self.asks.answers.pop(ask.index)
        if shown(word):
            await self._take_demonstration(word)

    def _paced(self) -> None:
        if self.pace is not None:
            self.pace.moved(self.count)

    async def _take_demonstration(self, demo: Demonstration) -> None:
        if self.count >= self.total:
            self.inbox.refuse(demo, f"the movement budget of {self.total} is spent")
            return
        self.get_logger().info(f"demonstration {demo.index} at movement {self.count} "
                               f"({demo.content}, outcome {floats(demo.outcome)})")
        if self.hosted is not None:  # the core learner says what it can take
            try:
                self.hosted.on_demonstration(*shown_parts(demo))
            except ValueError as refusal:
                self.inbox.refuse(demo, str(refusal), always=True)
                return
            self.publish_taken(demo)
            return
        if demo.content == GOAL_ONLY:  # emulation: the outcome becomes the next goal
            self.publish_taken(demo)
            await self.goal_attempt(self.cap(), demonstrated=demo.outcome)
            return
        if demo.content == MEANS_ONLY:  # the action, imitated; where it lands, seen by itself
            self.publish_taken(demo)
            await self.imitation(demo, min(self.config.imitation_count,
                                            self.total - self.count))
            return
        reply = await self.call(self.register_client,
                                 RegisterDemonstration.Request(demonstration=demo),
                                 "register_demonstration")
        if not reply.accepted:
            self.inbox.refuse(demo, f"the explorer refused it: {reply.message}")
            return
        self.publish_taken(demo)
        # The imitation never runs past the budget (the single-process runner stops there).
        result = await self.imitation(demo, min(self.config.imitation_count,
                                                 self.total - self.count))
        self._imitation_competence(demo, result, reply.closest_distance)

    def _imitation_competence(self, demo: Demonstration, result: Imitate.Result | None,
                              start: float, earlier=None, earlier_used: int = 0) -> None:
        made = imitation_competence(self.distances, demo, result, start, self.count,
                                    self.get_clock().now().to_msg(), earlier, earlier_used)
        if made is not None:
            self.publish_competence(made)

    async def _finish_cut_imitation(self, cut) -> None:
        """A resumed run first makes the imitations its kill cut, then records the whole
        imitation's competence, as the uninterrupted run would have (imitation_turn.py)."""
        self.get_logger().info(f"resume: {cut.describe()}")
        demo = as_message(cut)
        result = await self.imitation(demo, cut.remaining) if cut.remaining else None
        if cut.measured and not cut.competence_recorded:
            self._imitation_competence(demo, result, self.cut_start, cut.best_outcome(),
                                       len(cut.made))

    async def goal_attempt(self, cap: int, demonstrated=()) -> ReachGoal.Result:
        """Goals drawn by the goal generator and reached by the explorer, up to `cap`
        movements and goals_per_job goals; or the `demonstrated` outcome adopted, alone."""
        result = await self.run_job(self.reach, ReachGoal.Goal(
            max_movements=cap, max_goals=self.goals_per_job, movements_before=self.count,
            goals_before=self.goals_folded, demonstrated=list(demonstrated)), "reach_goal")
        self.goals_folded += result.goals_attempted
        if self.asks is not None and result.goal_movements > 0:  # one goal per job: the last
            self.schedule.attempt_ended(vec(result.goal), result.competence,
                                        None if result.finished else self.count)
        return result

    def publish_competence(self, msg: Competence) -> None:
        """A competence folded by the arbiter (an imitated demonstration, a social episode)."""
        self._competences.publish(msg)
        self.goals_folded += 1

    async def imitation(self, demo: Demonstration, repetitions: int,
                        measure_at=()) -> Imitate.Result:
        return await self.run_job(self.imitate, Imitate.Goal(
            action=demo.action, outcome=demo.outcome, repetitions=repetitions,
            movements_before=self.count, measure_at=list(measure_at)), "imitate")

    async def run_job(self, client: ActionClient, goal, name: str):
        held = self.inbox.pending or (self.pace is not None and self.pace.paused)
        # Feedback counts from the job's start: one that arrives after the result (a topic
        # and a service answer keep no order between them) is then behind, never ahead.
        start = self.count
        if name == "reach_goal":  # feedback only where it can be said (run_progress.py)
            goal.report_after = max(1, self.progress.due(start))
            goal.report_every = self.progress.step
        result = await self.job.run(client, goal, name, self.count, self.p["call_timeout"],
                                    cut_at_once=bool(held) and name == "reach_goal",
                                    feedback=lambda f: self.progress.moved(
                                        start + f.movements_done))
        self.count += result.movements_used
        return result

    async def _hosted_movement(self) -> None:
        """One movement of the hosted core learner: its action executed, its result told."""
        action, label = self.hosted.next_action()
        aim = self.hosted.aim()
        index = self.count + 1
        response = await self.sim.execute(ExecuteAction.Request(
            action=floats(action), process=PROCESS_CODES[label], movement_index=index,
            goal=[] if aim is None else floats(aim), record=True))
        outcome = vec(response.outcome) if len(response.outcome) else None
        self.hosted.observe(action, MovementResult(outcome, response.status))
        self.count = index

    def publish_taken(self, demo: Demonstration) -> None:
        """The learner's memory holds it from now on (after movement `count`)."""
        self._taken.publish(Demonstration(
            stamp=self.get_clock().now().to_msg(), index=demo.index, movement_index=self.count,
            action=demo.action, outcome=demo.outcome,
            teaching_set_index=demo.teaching_set_index, source=demo.source,
            content=demo.content, help_request=demo.help_request))

    def say_refusal(self, line: str) -> None:
        self.get_logger().warning(line)
        self.progress.say(RunStatus.STATE_RUNNING, line)


def shown_parts(demo) -> tuple:
    """(action, outcome) of a validated demonstration as a core learner takes them: None for
    the part its content does not show, which validation leaves empty (bag/record_checks.py)."""
    return (vec(demo.action) if len(demo.action) else None,
            vec(demo.outcome) if len(demo.outcome) else None)


ENTRY = NodeEntry(SocialInteraction)
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
