"""The page's pause and step as pace service calls (teacher/web/pacing.py), against a stand-in
arbiter that counts movements as the real one does: only when a job ends."""

from __future__ import annotations

from teacher.web.pacing import PacePlan, PaceReply, Request

TOTAL = 1000


class Arbiter:
    """PaceControl's answers, in short: its count moves when a job ends; a pause cuts the
    running job at its next movement boundary; a step caps the next job at its movements."""

    def __init__(self, count: int, running: bool = False) -> None:
        self.count = self.shown = count  # the arbiter's count, and the page's
        self.paused = self.held = not running
        self.steps = 0

    def movement(self) -> None:
        """The running job makes one more movement (the page sees it at once), and reaches
        a boundary: a pause cuts it there."""
        self.shown += 1
        if self.paused:
            self.count, self.held = self.shown, True

    def ask(self, request: Request) -> PaceReply:
        message = ""
        if request.command == "pause":
            message = f"pausing at movement {self.count}"  # the arbiter's own, stale, text
            self.paused = True
        elif request.command == "step":
            self.paused, self.held, self.steps = False, False, request.steps
            message = f"stepping {request.steps} movements"
        return PaceReply(True, message, self.paused, self.held, self.count, TOTAL)

    def run_step(self) -> int:
        """The step's job, capped at its movements: where the run pauses again."""
        self.shown = self.count = self.count + self.steps
        self.paused = self.held = True
        return self.count


def carry_out(plan: PacePlan, arbiter: Arbiter) -> dict:
    """Call as the node does; a running job makes a movement between two calls."""
    now, request = 0.0, plan.first()
    for _ in range(100):
        now += 0.05
        step = plan.next(arbiter.ask(request), now)
        if not isinstance(step, Request):
            return step
        if not arbiter.held:
            arbiter.movement()
        request = step
    raise AssertionError("the plan never answered")


def test_a_step_asked_while_a_job_runs_counts_from_where_the_run_stops():
    """The page shows 275 while the arbiter still counts 270 (its job's start): a step of 5
    pauses first, then makes 5 movements from where the run stood still, as its answer says
    (one step call counted 5 from 270, and the job went on to its own end)."""
    arbiter = Arbiter(270, running=True)
    for _ in range(5):
        arbiter.movement()
    assert (arbiter.shown, arbiter.count) == (275, 270)
    answer = carry_out(PacePlan("step", 5, 0.0), arbiter)
    assert answer["ok"] and answer["from"] == arbiter.shown == 277  # a query, then the pause
    assert answer["message"] == ("stepping 5 movements from movement 277: it pauses again at "
                                 "movement 282")
    assert arbiter.run_step() == 282


def test_a_step_at_a_standstill_goes_at_once():
    arbiter = Arbiter(40)
    plan = PacePlan("step", 3, 0.0)
    assert plan.first() == Request("query")
    assert plan.next(arbiter.ask(Request("query")), 0.0) == Request("step", 3)
    answer = plan.next(arbiter.ask(Request("step", 3)), 0.0)
    assert answer["message"] == "stepping 3 movements from movement 40: it pauses again at " \
                                "movement 43"
    end = PacePlan("step", 50, 0.0)
    end.next(Arbiter(980).ask(Request("query")), 0.0)
    assert end.next(PaceReply(True, "", False, False, 980, TOTAL), 0.0)["message"].endswith(
        "the run ends at its budget, movement 1000")


def test_a_pause_says_the_movement_the_run_stands_at_not_the_arbiters_stale_count():
    arbiter = Arbiter(83, running=True)
    for _ in range(37):
        arbiter.movement()
    assert (arbiter.shown, arbiter.count) == (120, 83)
    answer = carry_out(PacePlan("pause", 0, 0.0), arbiter)
    assert answer == {"ok": True, "message": "paused at movement 121"}
    assert arbiter.held and arbiter.shown == 121


def test_refusals_a_resume_meanwhile_and_a_run_that_does_not_stop_in_time():
    refused = PaceReply(False, "the movement budget is spent (1000/1000)", False, True, 1000,
                        TOTAL)
    assert PacePlan("step", 2, 0.0).next(refused, 0.0) == {
        "ok": False, "message": "the movement budget is spent (1000/1000)"}
    moving = PaceReply(True, "", False, False, 10, TOTAL)
    pausing = PaceReply(True, "", True, False, 10, TOTAL)
    step = PacePlan("step", 2, 0.0, settle=1.0)
    assert step.next(moving, 0.0) == Request("pause")
    assert step.next(pausing, 0.1) == Request("query", after=0.05)
    assert "no step made" in step.next(moving, 0.2)["message"]  # someone resumed it
    slow = PacePlan("pause", 0, 0.0, settle=1.0)
    assert slow.next(pausing, 0.5) == Request("query", after=0.05)
    late = slow.next(pausing, 1.5)
    assert late["ok"] and late["message"].startswith("pausing: the run stops at its next")
    stuck = PacePlan("step", 2, 0.0, settle=1.0)
    stuck.next(moving, 0.0)
    assert not stuck.next(pausing, 2.0)["ok"]
    resume = PacePlan("resume", 0, 0.0)
    assert resume.first() == Request("resume")
    assert resume.next(PaceReply(True, "resumed", False, False, 5, TOTAL), 0.0) == {
        "ok": True, "message": "resumed"}
