"""Movements signed with the run's key: only its simulator can make a record every consumer
takes (sgim_ros/record_key.py, bag/record_checks.py)."""

from __future__ import annotations

import dataclasses
import json
import stat

import numpy as np

from sgim_nodes.bag.record_checks import Limits, check
from sgim_nodes.bag.records import MovementRecord
from sgim_ros import record_key


def movement(index: int = 3, attempt: int = 0, outcome=(0.1, -0.2)) -> MovementRecord:
    return MovementRecord(0, 0, index, 0, 0, np.linspace(-0.5, 0.5, 24), np.array(outcome),
                          np.array([0.1, -0.2]), 2, attempt)


def signed(key: str, m: MovementRecord) -> MovementRecord:
    return dataclasses.replace(m, signature=record_key.movement_signature(key, m))


def test_a_signed_movement_passes_and_any_change_or_other_key_fails():
    key = record_key.new_key()
    limits = Limits(record_key=key)
    good = signed(key, movement())
    assert check("movements", good, limits) is None
    for forged in (dataclasses.replace(good, attempt=1),  # a "re-execution" by someone else
                   dataclasses.replace(good, outcome=np.array([0.99, 0.99])),
                   dataclasses.replace(good, action=good.action + 1e-12),
                   dataclasses.replace(good, signature=b""),
                   signed(record_key.new_key(), movement())):
        problem = check("movements", forged, limits)
        assert problem is not None and problem.kind == "unsigned", forged
    # a run made without a key is read as before
    assert check("movements", movement(), Limits(record_key="")) is None


def test_the_key_stays_in_the_run_folder_and_out_of_the_bags_metadata(tmp_path, monkeypatch):
    key = record_key.new_key()
    record_key.write_key(tmp_path, key)
    assert record_key.read_key(tmp_path) == key
    assert stat.S_IMODE((tmp_path / record_key.KEY_FILE).stat().st_mode) == 0o600
    assert record_key.read_key(tmp_path / "elsewhere") == ""
    assert key not in Limits(record_key=key).to_json()
    monkeypatch.setenv(record_key.ENV, key)  # what the launcher gives its nodes
    assert Limits().record_key == key
    assert Limits.from_json(Limits(action_size=7).to_json()).action_size == 7


def test_readers_take_the_key_from_the_run_folder(tmp_path):
    from sgim_nodes.bag.reader import limits_for

    (tmp_path / "bag").mkdir()
    assert limits_for(tmp_path / "bag").record_key == ""
    key = record_key.new_key()
    record_key.write_key(tmp_path, key)
    assert limits_for(tmp_path / "bag").record_key == key
    assert limits_for(tmp_path / "bag.resume1").record_key == key


def _signed_run(tmp_path, keep_key: bool):
    """A run folder whose movements its simulator signed, plus two forgeries after movement
    30 (unsigned re-executions claiming other outcomes); its key kept or lost in a copy."""
    from tests.bag import samples

    key = record_key.new_key()
    messages = []
    for topic, msg in samples.synthetic_run(40, seed=5):
        if topic == "movements":
            msg.signature = np.frombuffer(record_key.movement_signature(key, msg), np.uint8)
        messages.append((topic, msg))
        if topic == "movements" and msg.index in (30, 31):
            forged = samples.movement(int(msg.index), np.random.default_rng(9), attempt=1)
            messages.append(("movements", forged))
    run = tmp_path / "run"
    run.mkdir(parents=True)
    samples.write_bag(run / "bag", messages, chunk_messages=30)
    if keep_key:
        record_key.write_key(run, key)
    return run


def test_a_signed_run_copied_without_its_key_is_refused_in_one_line(tmp_path, monkeypatch):
    """Without the key the readers cannot tell the forgeries from the simulator's records:
    they refuse the folder, naming the missing key, unless told to trust it."""
    import warnings

    import pytest

    from sgim_nodes.bag.reader import BagReadWarning, load_run

    monkeypatch.delenv(record_key.TRUST_ENV, raising=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kept = load_run(_signed_run(tmp_path / "kept", keep_key=True) / "bag")
    assert len(kept.movements) == 40 and {q.index for q in kept.quarantined} == {30, 31}
    lost = _signed_run(tmp_path / "lost", keep_key=False)
    with pytest.raises(record_key.MissingKey) as refused:
        load_run(lost / "bag")
    assert "\n" not in str(refused.value)
    assert f"key ({record_key.KEY_FILE}) is not in its folder" in str(refused.value)
    monkeypatch.setenv(record_key.TRUST_ENV, "1")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trusted = load_run(lost / "bag")
    assert trusted.superseded == [30, 31]  # read unchecked: the forgeries replace movements
    assert any(record_key.UNKEYED in str(w.message) for w in caught
               if issubclass(w.category, BagReadWarning))


def test_an_unsigned_run_without_a_key_is_read_as_before(tmp_path, monkeypatch):
    """A run made before keys (or by nodes started alone) signs nothing: nothing to refuse."""
    from sgim_nodes.bag.reader import load_run
    from tests.bag import samples

    monkeypatch.delenv(record_key.TRUST_ENV, raising=False)
    samples.write_bag(tmp_path / "bag", samples.synthetic_run(20, seed=1))
    assert len(load_run(tmp_path / "bag").movements) == 20


def test_teaching_records_are_signed_under_their_topic_and_checked_when_the_run_signs_them(
        monkeypatch):
    """A teacher's demonstration, the arbiter's taken one and its help request: a forgery, a
    change, or one replayed under another topic is quarantined as unsigned; a bag recorded
    before teaching records were signed is read as it was made."""
    from tests.bag import samples

    key = record_key.new_key()
    rng = np.random.default_rng(2)
    limits = Limits(record_key=key)
    assert limits.signing == record_key.SIGNS_COMPETENCES
    demo = record_key.sign_teaching("demonstrations", samples.demonstration(3, 40, rng), key)
    ask = record_key.sign_teaching("help_requests",
                                   samples.help_request(2, 40, rng, "centre", "goal-only"), key)
    assert check("demonstrations", demo, limits) is None
    assert check("help_requests", ask, limits) is None
    as_taken = check("demonstrations_taken", demo, limits)  # the giver's, not the arbiter's
    assert as_taken is not None and as_taken.kind == "unsigned"
    for forged in (dataclasses.replace(demo, signature=np.zeros(0, dtype=np.uint8)),
                   dataclasses.replace(demo, outcome=np.array([0.9, 0.9])),
                   dataclasses.replace(demo, source="human")):
        problem = check("demonstrations", forged, limits)
        assert problem is not None and problem.kind == "unsigned", forged
    moved = dataclasses.replace(ask, goal=np.array([0.5, 0.5]))
    assert check("help_requests", moved, limits).kind == "unsigned"
    unsigned = dataclasses.replace(demo, signature=np.zeros(0, dtype=np.uint8))
    older = Limits.from_json(json.dumps({"action_size": 24, "outcome_size": 2}))
    assert older.signing == record_key.SIGNS_MOVEMENTS
    older = dataclasses.replace(older, record_key=key)
    assert check("demonstrations", unsigned, older) is None  # recorded before: as made
    assert Limits.from_json(limits.to_json()).signing == record_key.SIGNS_COMPETENCES
    assert check("demonstrations", unsigned, Limits(record_key="")) is None  # keyless run


def test_a_teaching_publisher_signs_what_any_node_publishes(monkeypatch):
    """A node makes its teaching publishers from their declarations, which sign each record
    with the run's key: no publishing site can forget it."""
    from sgim_ros.interfaces import publishes

    sent = []

    class Publisher:
        def publish(self, msg):
            sent.append(msg)

        def get_subscription_count(self):
            return 3

    class FakeNode:
        def create_publisher(self, kind, name, qos, **options):
            return Publisher()

    key = record_key.new_key()
    monkeypatch.setenv(record_key.ENV, key)
    from sgim_msgs.msg import Demonstration, HelpRequest, Movement

    publisher = publishes("/demonstrations").create(FakeNode())
    assert publisher.get_subscription_count() == 3  # the rest is rclpy's publisher
    publisher.publish(Demonstration(index=4, movement_index=9, source="expert:centre"))
    assert record_key.teaching_signed_by(key, "demonstrations", sent[-1])
    publishes("movements").create(FakeNode()).publish(Movement(index=1))
    assert bytes(sent[-1].signature) == b""  # movements are the simulator's to sign
    monkeypatch.delenv(record_key.ENV)
    publishes("help_requests").create(FakeNode()).publish(HelpRequest(index=1))
    assert bytes(sent[-1].signature) == b""  # a node started alone signs nothing


def test_competences_are_signed_by_their_maker_and_checked_when_the_run_signs_them():
    """The interest tree is made of competences: one a rogue publishes (or changes) is
    quarantined; a bag recorded when only teaching records were signed is read as made."""
    from tests.bag import samples

    key = record_key.new_key()
    rng = np.random.default_rng(4)
    limits = Limits(record_key=key)
    made = record_key.sign_teaching("competences", samples.competence(3, 40, rng), key)
    assert check("competences", made, limits) is None
    for forged in (dataclasses.replace(made, signature=np.zeros(0, dtype=np.uint8)),
                   dataclasses.replace(made, competence=-0.01),
                   dataclasses.replace(made, from_demonstration=True)):
        problem = check("competences", forged, limits)
        assert problem is not None and problem.kind == "unsigned", forged
        assert "competences record at movement 40" in problem.detail
    older = dataclasses.replace(limits, signing=record_key.SIGNS_TEACHING)
    unsigned = dataclasses.replace(made, signature=np.zeros(0, dtype=np.uint8))
    assert check("competences", unsigned, older) is None
