"""The runner's worlds come from a registry (core/worlds.py): the arms register in the core,
other packages' worlds through entry points, and a missing one says what to install."""

from __future__ import annotations

import sys
from importlib.metadata import EntryPoint, EntryPoints

import pytest

from sgim_nodes.core import runner, worlds


def test_every_world_is_named_even_when_not_loaded():
    assert worlds.world_names()[:4] == ("fishing", "planar-arm", "arm-7", "arm-20")


def test_a_world_takes_only_its_own_options():
    assert worlds.build_world("planar-arm", 0, arm_joints=3).env.action_dim == 3
    with pytest.raises(ValueError, match="takes no arm_joints"):
        worlds.build_world("arm-7", 0, arm_joints=3)
    with pytest.raises(ValueError, match="unknown env 'moon'"):
        worlds.build_world("moon", 0)


def test_an_installed_entry_point_is_a_world(monkeypatch):
    """What pip or colcon install for sim_bridge, here for another world."""
    point = EntryPoint("moon", "sgim_nodes.core.worlds:planar_arm_world",
                       worlds.ENTRY_POINT_GROUP)
    monkeypatch.setattr(worlds, "entry_points", lambda **select: EntryPoints([point]).select(
        **select))
    monkeypatch.setattr(worlds, "_FACTORIES", dict(worlds._FACTORIES))  # loading registers
    assert "moon" in worlds.world_names()
    assert worlds.build_world("moon", 0, arm_joints=4).env.action_dim == 4


def test_a_missing_world_says_what_to_install_in_one_line(monkeypatch, capsys, tmp_path):
    for name in ("sim_bridge", "sim_bridge.core_world"):  # as if it were not installed
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setattr(worlds, "_FACTORIES", {k: v for k, v in worlds._FACTORIES.items()
                                               if k != "fishing"})
    with pytest.raises(worlds.WorldMissing):
        worlds.build_world("fishing", 0)
    assert runner.main(["--env", "fishing", "--output", str(tmp_path / "run.jsonl")]) == 2
    assert capsys.readouterr().err == ("error: the fishing world needs sim_bridge "
                                       "(pip install ./sim_bridge)\n")
