"""Movements signed with the run's key: only its simulator can make a record every consumer
takes (sgim_ros/record_key.py, bag/record_checks.py)."""

from __future__ import annotations

import dataclasses
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
