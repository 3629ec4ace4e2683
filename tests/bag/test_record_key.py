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
