"""The arbiter's side of SGIM-ACTS (nodes/acts_episodes.py): a request names its teacher and
what the strategy needs, only that teacher's answer at that count is taken, a "none there"
episode costs no movement and folds competence -1 at the chosen goal, and a resumed run
numbers its requests after the recorded ones."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace

import pytest

pytestmark = pytest.mark.ros


class _Arbiter:
    """What ActsEpisodes needs of the arbiter node; `deliver` answers while it waits."""

    def __init__(self) -> None:
        from sgim_nodes.core.config import LearnerConfig
        from sgim_nodes.core.scale import WorldScale

        self.requests: list = []
        self.competences: list = []
        self.refusals: list[str] = []
        self.deliver: list = []
        self.count = 40
        self.total = 100
        self.p = {"teacher_timeout": 5.0}
        self.config = LearnerConfig()
        self.distances = self.config.distances(WorldScale((-1.0, -1.0), (1.0, 1.0), 0.01))
        self.gate = SimpleNamespace(check=lambda _topic, _msg: None)
        self.waits = SimpleNamespace(until=self._until)
        self.episodes = None

    def create_publisher(self, _type, _topic, _qos):
        return SimpleNamespace(publish=self.requests.append)

    def get_clock(self):
        from builtin_interfaces.msg import Time

        return SimpleNamespace(now=lambda: SimpleNamespace(to_msg=Time))

    def get_logger(self):
        return SimpleNamespace(info=lambda _line: None, error=self.refusals.append)

    def say_refusal(self, line: str) -> None:
        self.refusals.append(line)

    def publish_competence(self, msg) -> None:
        self.competences.append(msg)

    async def _until(self, ready, _timeout, what: str) -> None:
        for msg in self.deliver:
            self.episodes.receive(msg)
        assert ready(), f"no answer for {what}"


def _episodes():
    from sgim_nodes.nodes.acts_episodes import ActsEpisodes

    arbiter = _Arbiter()
    arbiter.episodes = ActsEpisodes(arbiter)
    return arbiter.episodes, arbiter


def _answer(index: int, source: str, movement: int, outcome=()):
    from sgim_msgs.msg import Demonstration

    return Demonstration(index=index, help_request=index, source=source,
                         movement_index=movement, outcome=list(outcome))


def _goal(strategy: str):
    from sgim_msgs.msg import Goal

    return Goal(index=7, point=[0.25, -0.5], strategy=strategy)


def test_only_the_named_teachers_answer_at_the_asked_count_ends_the_episode():
    from sgim_nodes.core.teaching import GOAL_ONLY

    episodes, arbiter = _episodes()
    arbiter.deliver = [
        _answer(2, "expert:west", 40),    # to a request never made
        _answer(1, "expert:rough", 40),   # another teacher
        _answer(1, "expert:west", 39),    # another count
        _answer(1, "expert:west", 40),    # the answer: none there (no outcome)
        _answer(1, "expert:west", 40),    # a second answer to the same request
    ]
    asyncio.run(episodes.run(_goal("emulation:west"), 0.3))

    (request,) = arbiter.requests
    assert (request.index, request.teacher, request.movement_index) == (1, "west", 40)
    assert request.content == GOAL_ONLY and list(request.goal) == [0.25, -0.5]
    reasons = "\n".join(arbiter.refusals)
    assert len(arbiter.refusals) == 4, reasons
    for why in ("request 2, which the learner never made", "as 'expert:rough'",
                "at movement 39", "answered already"):
        assert why in reasons, reasons
    (folded,) = arbiter.competences
    assert folded.competence == -1.0 and folded.movements_used == 0
    assert (folded.goal_index, folded.strategy, list(folded.goal)) == (
        7, "emulation:west", [0.25, -0.5])
    assert arbiter.count == 40  # a request costs no movement of the budget


def test_mimicry_needs_an_action_and_a_resumed_run_numbers_after_the_recorded_requests():
    from sgim_nodes.core.teaching import MEANS_AND_GOAL

    episodes, arbiter = _episodes()
    episodes.resume(SimpleNamespace(help_requests=[SimpleNamespace(index=3),
                                                   SimpleNamespace(index=9)]))
    # An outcome without an action is "none there" for mimicry.
    arbiter.deliver = [_answer(10, "expert:centre", 40, outcome=[0.2, -0.4])]
    asyncio.run(episodes.run(_goal("mimicry:centre"), 0.3))
    (request,) = arbiter.requests
    assert (request.index, request.content) == (10, MEANS_AND_GOAL)
    assert arbiter.refusals == []
    (folded,) = arbiter.competences
    assert (folded.competence, folded.movements_used, folded.strategy) == (
        -1.0, 0, "mimicry:centre")


def test_a_forged_answer_first_is_refused_and_the_experts_own_is_taken(monkeypatch):
    """A process answering each request at once as the asked expert, unsigned: its answer is
    refused as unsigned, and the expert's own (signed with the run's key) is the one taken,
    not refused as 'answered already'."""
    from sgim_nodes.bag.record_checks import Limits
    from sgim_nodes.bag.validation import LiveGate
    from sgim_nodes.core.teaching import GOAL_ONLY
    from sgim_ros import record_key

    key = record_key.new_key()
    episodes, arbiter = _episodes()
    quarantined: list[str] = []
    arbiter.gate = LiveGate(quarantined.append, Limits(record_key=key))
    forged = _answer(1, "expert:west", 40, outcome=[0.9, 0.9])
    real = _answer(1, "expert:west", 40, outcome=[0.2, -0.4])
    for answer in (forged, real):  # what an expert shows for emulation: the outcome alone
        answer.content, answer.teaching_set_index = GOAL_ONLY, -1
    record_key.sign_teaching("demonstrations", real, key)
    arbiter.deliver = [forged, real]
    taken, jobs = [], []

    async def run_job(_client, goal, _name):
        jobs.append(goal)
        return SimpleNamespace(goals_attempted=1)

    arbiter.publish_taken, arbiter.run_job = taken.append, run_job
    arbiter.reach, arbiter.goals_folded, arbiter.cap = None, 0, lambda: 10
    asyncio.run(episodes.run(_goal("emulation:west"), 0.3))

    (request,) = arbiter.requests
    assert request.content == GOAL_ONLY
    assert len(arbiter.refusals) == 1 and "not signed" in arbiter.refusals[0], arbiter.refusals
    assert "answered already" not in "\n".join(arbiter.refusals)
    assert len(quarantined) == 1 and "quarantined" in quarantined[0]
    assert taken == [real]  # the expert's answer, not the forgery's
    (job,) = jobs
    assert list(job.demonstrated) == [0.2, -0.4]  # the explorer reaches the expert's outcome
