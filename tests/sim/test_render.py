"""render_cast draws the world's own cast: same outcome, same landing point, a real GIF."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from sim_bridge.data_files import load_teaching_set
from sim_bridge.fishing_world import FishingWorld, Status
from sim_bridge.render import record_cast, render_cast
from sim_bridge.tools import render_cast as tool


def test_the_recorded_cast_is_the_worlds_cast():
    action = load_teaching_set().actions[10]
    with FishingWorld(seed=3) as world:
        expected = world.execute(action)
    with FishingWorld(seed=3) as world:
        recording = record_cast(world, action)
    assert expected.status == Status.OK
    assert recording.result.status == expected.status
    assert np.array_equal(recording.result.outcome, expected.outcome)
    # The hook's drawn path ends where the world says it came down.
    assert np.allclose(recording.hook[-1, :2], expected.world_point, atol=1e-6)
    assert recording.attached[0] and not recording.attached[-1]
    assert np.all(np.diff(recording.times) > 0)


def test_frames_and_the_tool(tmp_path):
    frames, result = render_cast(load_teaching_set().actions[10], size=(96, 72), fps=10)
    assert result.status == Status.OK and len(frames) > 5
    assert frames[0].shape == (72, 192, 3)
    assert len({f.tobytes() for f in frames}) > 3  # it moves
    out = tmp_path / "cast.gif"
    assert tool.main(["--teaching-index", "10", "--out", str(out), "--size", "96x72",
                      "--fps", "10", "--quiet"]) == 0
    with Image.open(out) as gif:
        assert gif.n_frames > 5 and gif.size == (192, 72)


@pytest.mark.parametrize(("args", "out", "words"), [
    (["--teaching-index", "999"], "x.gif", "no teaching-set entry 999"),
    (["--action", "missing.yaml"], "x.gif", "cannot read missing.yaml"),
    (["--teaching-index", "3"], "cast.mp4", "writes animated GIFs only"),
])
def test_the_tool_refuses_bad_input(tmp_path, capsys, args, out, words):
    assert tool.main([*args, "--out", str(tmp_path / out)]) == 2
    assert words in capsys.readouterr().err
    assert not (tmp_path / out).exists()


def test_the_tool_checks_the_action_file(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("action: [0.1, 2.0]")
    assert tool.main(["--action", str(bad), "--out", str(tmp_path / "x.gif")]) == 2
    assert "24 numbers" in capsys.readouterr().err
