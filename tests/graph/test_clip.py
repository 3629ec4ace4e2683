"""sgim_ros/clip.py: one way to cut a value or a text for a one-line message."""

from __future__ import annotations

from sgim_ros.clip import clipped, value_text


def test_a_long_text_keeps_its_start_and_its_end():
    path = "/tmp/pytest-of-root/pytest-7/popen-gw1/" + "deep/" * 30 + "teaching_set.npz"
    cut = clipped(path, 80)
    assert len(cut) == 80 and "..." in cut
    assert cut.startswith("/tmp/pytest-of-root") and cut.endswith("teaching_set.npz")
    assert clipped("short", 80) == "short"
    assert clipped("x" * 80, 80) == "x" * 80 and len(clipped("x" * 81, 80)) == 80


def test_values_without_a_printable_repr_are_named():
    assert value_text(10**5000) == f"an integer of {(10**5000).bit_length()} bits"
    assert value_text(-(10**50)).startswith("an integer of")
    assert value_text(True) == "True" and value_text(12) == "12"
    deep: list = []
    for _ in range(100_000):
        deep = [deep]
    assert value_text(deep) == "a list nested too deep to show"
    assert value_text("a" * 200, 60).endswith("aaa'") and len(value_text("a" * 200, 60)) == 60
