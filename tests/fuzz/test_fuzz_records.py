"""Fuzz the one validation of records (bag/validation.py, record_checks.py).

Every record the graph accepts (movements, goals, competences, demonstrations, help requests,
evaluations, run status, region maps) goes through `RunValidator.admit` in the recorder and
every reader, and through `LiveGate` in the live nodes. Whatever a record holds, even fields
of the wrong type or missing ones (a rogue publisher, a damaged bag, a bag of another
version), it is accepted or quarantined with a reason: never an exception. An accepted record
is one a consumer can fold: finite vectors of the run's sizes inside [-1, 1], indices within
the budget, and a movement index that is the run's next one or a re-execution of the latest.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sgim_nodes.bag.record_checks import Limits, check
from sgim_nodes.bag.validation import LiveGate, RunValidator
from tests.fuzz.tally import fuzz, tally

LIMITS = Limits(action_size=24, outcome_size=2, budget=50, teaching_set_size=26,
                record_key="") if "record_key" in Limits.__dataclass_fields__ else Limits(
    action_size=24, outcome_size=2, budget=50, teaching_set_size=26)

odd = st.sampled_from([None, "x", [], [[1.0]], {"a": 1}, math.nan, math.inf, -1, 2**64, b"\x00"])


def strategies(valid: bool) -> dict[str, st.SearchStrategy]:
    """One strategy per topic: records as a correct node would publish them (`valid`), or as
    anything might: wrong types, missing fields, NaN, sizes off by one, codes out of range."""

    def field(good: st.SearchStrategy, anything: st.SearchStrategy | None = None):
        return good if valid else st.one_of(good, good if anything is None else anything, odd)

    def vectors(size: int, bound: float = 1.0) -> st.SearchStrategy:
        good = st.lists(st.floats(-bound, bound), min_size=size, max_size=size)
        sizes = st.sampled_from(sorted({0, max(size - 1, 0), size, size + 1}))
        return field(good, sizes.flatmap(lambda n: st.lists(st.floats(), min_size=n,
                                                            max_size=n)))

    def index(low: int = 1, high: int = 60) -> st.SearchStrategy:
        return field(st.integers(low, high), st.one_of(st.integers(-3, 3),
                                                       st.integers(0, 2**64 - 1)))

    def record(**fields: st.SearchStrategy) -> st.SearchStrategy:
        """A message-like object (the checks read fields by name), now and then missing a
        field when not `valid`."""
        def build(values: dict, drop: str | None) -> SimpleNamespace:
            values.pop(drop, None)
            return SimpleNamespace(**values)
        drops = st.none() if valid else st.one_of(st.none(), st.none(),
                                                  st.sampled_from(sorted(fields)))
        return st.builds(build, st.fixed_dictionaries(fields), drops)

    region = record(id=field(st.just(0), st.integers(0, 8)),
                    parent_id=field(st.just(-1), st.integers(-1, 8)),
                    lower=field(st.just([-1.0, -1.0]), vectors(2)),
                    upper=field(st.just([1.0, 1.0]), vectors(2)),
                    interest=field(st.floats(-1, 1), st.floats()), goal_count=index(0),
                    is_leaf=st.booleans(), least_competent_goal=vectors(2))
    found = {
        "movements": record(index=index(1, 3), process=field(st.integers(0, 3),
                                                             st.integers(0, 9)),
                            status=field(st.just(0), st.integers(0, 5)), action=vectors(24),
                            outcome=vectors(2), goal=vectors(2), goal_index=index(0),
                            attempt=field(st.integers(0, 2), st.integers(0, 300)),
                            signature=st.just([])),
        "goals": record(index=index(1, 3), movement_index=index(0), point=vectors(2),
                        region_id=field(st.integers(-1, 10), st.integers(-3, 10)),
                        mode=field(st.integers(1, 4), st.integers(0, 6))),
        "competences": record(goal_index=index(), movement_index=index(0), goal=vectors(2),
                              reached=vectors(2),
                              competence=field(st.floats(-1, 0), st.floats()),
                              movements_used=index(), from_demonstration=st.booleans(),
                              strategy=st.sampled_from(["", "autonomous", "mimicry:rough"]),
                              signature=st.just([])),
        "demonstrations": record(
            index=index(), movement_index=index(0), action=vectors(24), outcome=vectors(2),
            teaching_set_index=field(st.integers(-1, 25), st.integers(-3, 30)),
            source=field(st.sampled_from(["automatic", "human", "web"]),
                         st.sampled_from(["robot", ""])),
            content=field(st.just("means-and-goal"), st.sampled_from(
                ["goal-only", "means-only", "both"])),
            help_request=index(0)),
        "help_requests": record(index=index(), movement_index=index(0, 49), goal=vectors(2)),
        "evaluations": st.integers(1, 4).flatmap(lambda n: st.lists(
            st.floats(0, 5), min_size=n, max_size=n).flatmap(lambda distances: record(
                movement_index=index(0), outcome_size=field(st.just(2), st.sampled_from([1, 3])),
                goals=vectors(2 * n), reached=vectors(2 * n, bound=3.0),
                distances=field(st.just(distances)),
                mean_distance=field(st.just(float(np.mean(distances))), st.floats(0, 5))))),
        "run_status": record(learner=field(st.sampled_from(["sgim-d", "random"]),
                                           st.sampled_from(["sgimd", ""])),
                             seed=index(0, 2**32 - 1), movement_index=index(0, 50),
                             total_movements=field(st.just(50), st.sampled_from([0, 49, 51])),
                             state=field(st.integers(0, 2), st.integers(0, 4)),
                             message=st.text(max_size=10)),
        "region_map": record(movement_index=index(0, 50), split_count=index(0),
                             goal_count=index(0), regions=field(st.lists(region, min_size=1,
                                                                         max_size=1),
                                                                st.lists(region, max_size=4))),
    }
    found["demonstrations_taken"] = found["demonstrations"]
    return found


GOOD, ANY = strategies(valid=True), strategies(valid=False)
RECORDS = {topic: st.one_of(GOOD[topic], ANY[topic]) for topic in GOOD}


def _fine(values, size: int) -> bool:
    v = np.asarray(values, dtype=float).ravel()
    return v.size == size and bool(np.all(np.isfinite(v))) and bool(np.all(np.abs(v) <= 1))


def _accepted_is_usable(topic: str, r) -> None:
    """What a consumer relies on when it folds an accepted record."""
    if topic == "movements":
        assert _fine(r.action, 24) and 1 <= int(r.index) <= LIMITS.budget
        assert int(r.status) != 0 or _fine(r.outcome, 2)
    elif topic == "goals":
        assert _fine(r.point, 2) and int(r.index) >= 1
    elif topic == "competences":
        assert _fine(r.goal, 2) and -1 <= float(r.competence) <= 0
    elif topic in ("demonstrations", "demonstrations_taken"):
        assert len(r.action) in (0, 24) and len(r.outcome) in (0, 2)
        assert all(math.isfinite(x) and abs(x) <= 1 for x in [*r.action, *r.outcome])
    elif topic == "help_requests":
        assert _fine(r.goal, 2) and int(r.movement_index) < LIMITS.budget
    elif topic == "evaluations":
        assert math.isfinite(float(r.mean_distance))
    elif topic == "region_map":
        assert len(r.regions) >= 1
        for region in r.regions:
            assert _fine(region.lower, 2) and _fine(region.upper, 2)
            assert math.isfinite(float(region.interest))


@pytest.mark.slow
@fuzz(400)
@given(stream=st.lists(st.sampled_from(sorted(RECORDS)).flatmap(
    lambda topic: st.tuples(st.just(topic), RECORDS[topic])), min_size=1, max_size=8))
def test_every_record_is_accepted_or_quarantined_never_an_exception(stream):
    """A run's records in arrival order through the readers' and the recorder's validator,
    and each through a live node's gate: the same verdicts, no exception."""
    validator = RunValidator(LIMITS)
    logged: list[str] = []
    gate = LiveGate(logged.append, LIMITS)
    last_movement = refused = 0
    for topic, r in stream:
        verdict = validator.admit(topic, r)
        live = gate.admit_movement(r) if topic == "movements" else None
        if topic != "movements":
            gate.check(topic, r)
        if verdict.ok:
            _accepted_is_usable(topic, r)
            if topic == "movements":
                index = int(r.index)
                assert index == last_movement + 1 or (verdict.supersedes and
                                                      index == last_movement)
                last_movement = index
                assert live is not None and live.ok
            tally(f"records: {topic}", "accepted")
        else:
            assert verdict.problem.kind and verdict.problem.detail
            assert "\n" not in verdict.problem.detail
            refused += 1
            tally(f"records: {topic}", f"quarantined ({verdict.problem.kind})")
    assert len(validator.quarantined) == refused  # every refusal is in the report


SIGNED_FIELDS = {"movements": ("index", "attempt", "process", "status", "goal_index", "action",
                               "outcome", "goal"),
                 "demonstrations": ("index", "movement_index", "teaching_set_index",
                                    "help_request", "action", "outcome", "source", "content"),
                 "help_requests": ("index", "movement_index", "goal", "teacher", "content"),
                 "competences": ("goal_index", "movement_index", "competence", "movements_used",
                                 "from_demonstration", "goal", "reached", "strategy")}
SIGNED_FIELDS["demonstrations_taken"] = SIGNED_FIELDS["demonstrations"]


def _changed(value):
    """Another value of the same kind: what a forger changes in a signed record."""
    if isinstance(value, str):
        return value + "x"
    if isinstance(value, bool):
        return not value
    if isinstance(value, float):
        return value + 0.125 if value < -0.5 else value - 0.125
    if isinstance(value, int | np.integer):
        return int(value) + 1
    values = [float(v) for v in value]
    if not values:
        return [0.5]
    last = values[-1]
    return [*values[:-1], last + 0.125 if not last > 0.5 else last - 0.125]


@pytest.mark.slow
@fuzz(300)
@given(topic=st.sampled_from(sorted(SIGNED_FIELDS)), data=st.data())
def test_a_signed_record_changed_in_any_field_is_never_accepted(topic, data):
    """In a run with a key, a record its maker signed passes the signature check; the same
    record with any signed field changed, or with random signature bytes, is quarantined."""
    from sgim_ros import record_key

    key = record_key.new_key()
    limits = Limits(action_size=24, outcome_size=2, budget=50, teaching_set_size=26,
                    record_key=key)
    r = data.draw(GOOD[topic])
    if topic == "help_requests":  # the fields a graph of today fills
        r.teacher, r.content = data.draw(st.sampled_from([("", ""), ("centre", "goal-only")]))
    if topic == "movements":
        r.signature = list(record_key.movement_signature(key, r))
    else:
        record_key.sign_teaching(topic, r, key)
    first = check(topic, r, limits)
    assert first is None or first.kind != "unsigned"
    name = data.draw(st.sampled_from(SIGNED_FIELDS[topic]))
    forged = SimpleNamespace(**vars(r))
    setattr(forged, name, _changed(getattr(r, name)))
    problem = check(topic, forged, limits)
    assert problem is not None
    tally(f"signed records: {topic}", f"one field changed: quarantined ({problem.kind})")
    noise = SimpleNamespace(**vars(r))
    noise.signature = data.draw(st.lists(st.integers(0, 255), max_size=20))
    if bytes(noise.signature) != bytes(bytearray(r.signature)):
        assert check(topic, noise, limits) is not None
        tally(f"signed records: {topic}", "random signature: quarantined")
