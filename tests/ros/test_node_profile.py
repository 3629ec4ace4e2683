"""SGIM_PROFILE's node profiles count CPU, not waiting (sgim_ros/entry.py, Profile)."""

from __future__ import annotations

import pstats
import time

from sgim_ros.entry import PROFILE_ENV, Profile


def busy(seconds: float) -> None:
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


def test_a_profile_counts_the_cpu_a_node_spends_not_its_waits(tmp_path, monkeypatch):
    monkeypatch.setenv(PROFILE_ENV, str(tmp_path / "profile"))
    with Profile("spinner") as profile:
        time.sleep(0.4)  # a node waiting for its next message
        busy(0.1)
    profile.write()
    stats = pstats.Stats(str(tmp_path / "profile" / "spinner.prof"))
    assert 0.08 < stats.total_tt < 0.3, stats.total_tt
    text = (tmp_path / "profile" / "spinner.prof.txt").read_text()
    first = text.splitlines()[0]
    assert first.startswith("process CPU while spinning: ")
    assert float(first.split(": ")[1].split()[0]) >= 0.08
    assert "busy" in text


def test_no_profile_without_the_variable(tmp_path, monkeypatch):
    monkeypatch.delenv(PROFILE_ENV, raising=False)
    monkeypatch.chdir(tmp_path)
    with Profile("spinner") as profile:
        busy(0.01)
    profile.write()
    assert not list(tmp_path.iterdir())
