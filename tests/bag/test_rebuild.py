"""Rebuilding memory and region tree from a bag equals folding the records into the core."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.bag.reader import BagReadWarning, storage_files
from sgim_nodes.bag.rebuild import main, rebuild
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.memory import Memory
from sgim_nodes.core.region_tree import RegionTree
from tests.bag import samples

CONFIG = LearnerConfig(max_goals_per_region=6, zeta=4, min_goals_per_child=2)


def _direct(messages, n_parts_lost: int = 0):
    """The expected state, from the rosbags messages themselves and the core classes."""
    memory = Memory(24, 2)
    tree = RegionTree(np.full(2, -1.0), np.full(2, 1.0), CONFIG.max_goals_per_region,
                      CONFIG.zeta, CONFIG.min_goals_per_child,
                      CONFIG.min_region_width_size * 2.0, CONFIG.interest_noise_correction)
    for topic, msg in messages:
        if topic == "movements" and msg.status == 0:
            memory.add(msg.action, msg.outcome)
        elif topic == "demonstrations_taken":
            memory.add(msg.action, msg.outcome)  # taken just before movement k + 1
        elif topic == "competences":
            tree.add(msg.goal, msg.competence)
    return memory, tree


def _leaves(tree: RegionTree) -> list[tuple]:
    return sorted((tuple(r.low), tuple(r.high), len(r.goals)) for r in tree.leaves)


@pytest.fixture(scope="module")
def messages():
    return samples.synthetic_run(300, seed=2)


def test_rebuild_matches_folding_the_records_directly(tmp_path, messages):
    bag = samples.write_bag(tmp_path / "run", messages, chunk_messages=64)
    state = rebuild(bag, CONFIG)
    memory, tree = _direct(messages)
    assert len(state.memory) == len(memory) > 250
    assert np.array_equal(state.memory.actions, memory.actions)
    assert np.array_equal(state.memory.outcomes, memory.outcomes)
    assert "demonstration" in state.memory.labels and "imitation" in state.memory.labels
    assert len(tree.leaves) > 3 and _leaves(state.tree) == _leaves(tree)
    assert state.n_movements == state.n_recorded == 300 and state.missing == []
    assert state.last_evaluation.movement_index == 300
    assert state.last_status.state == 1


def test_rebuild_orders_by_movement_count_not_by_arrival(tmp_path, messages):
    # Topics arrive on separate DDS readers: a demonstration may be recorded late.
    shuffled = [m for m in messages if m[0] != "demonstrations"]
    demo = next(m for m in messages if m[0] == "demonstrations")
    shuffled.insert(len(shuffled) - 5, demo)
    bag = samples.write_bag(tmp_path / "late", shuffled)
    memory, _ = _direct(messages)
    assert np.array_equal(rebuild(bag, CONFIG).memory.actions, memory.actions)


def test_a_damaged_bag_gives_a_partial_state_with_a_warning(tmp_path, messages):
    bag = samples.write_bag(tmp_path / "run", messages, chunk_messages=64)
    last = storage_files(bag)[-1]
    last.write_bytes(last.read_bytes()[: last.stat().st_size * 2 // 3])  # a disk cut it
    with pytest.warns(BagReadWarning, match=last.name):
        state = rebuild(bag, CONFIG)
    assert 0 < state.n_movements < 300 and state.missing == []


def test_cli_prints_a_summary_and_refuses_what_is_not_a_bag(tmp_path, messages, capsys):
    bag = samples.write_bag(tmp_path / "run", messages)
    assert main([str(bag), "--set", "max_goals_per_region=6", "--set", "zeta=4",
                 "--set", "min_goals_per_child=2"]) == 0
    out = capsys.readouterr().out
    assert "movements: 300" in out and "last evaluation: at movement 300" in out
    assert "rebuilt tree" in out
    (tmp_path / "junk.mcap").write_bytes(b"junk")
    assert main([str(tmp_path / "junk.mcap")]) == 2
    assert "junk.mcap" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([str(bag), "--set", "no_such=1"])


def test_an_empty_demonstration_is_not_stored(tmp_path, messages):
    empty = samples.demonstration(2, 300, np.random.default_rng(0))
    empty.action, empty.outcome = np.zeros(0), np.zeros(0)  # "nothing left to show"
    bag = samples.write_bag(tmp_path / "run", [*messages, ("demonstrations", empty)])
    state = rebuild(bag, CONFIG)
    memory, _ = _direct(messages)
    assert len(state.memory) == len(memory) and state.n_demonstrations == 1
