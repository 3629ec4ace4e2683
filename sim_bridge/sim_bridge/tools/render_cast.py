"""Draw one cast as an animated GIF: the arm and rod close up beside the lake from above.

    render_cast --teaching-index 3 --out cast.gif
    render_cast --action demo.yaml --out cast.gif --seed 2 --size 320x240

The cast is the world's own (sim_bridge.render: FishingWorld.execute, watched), with the
world's motor noise for ``--seed``; the hook's path and where it came down are drawn on a lake
whose water and land are the world's. An action file holds 24 numbers in [-1, 1], as a YAML or
JSON list or under the key ``action`` (the human teacher's ``yaml`` files work as they are).
Prints the cast's outcome; exit code 2 for bad input, 1 when the cast could not be drawn.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import yaml

from sgim_ros.command_line import BriefParser
from sim_bridge.data_files import load_teaching_set
from sim_bridge.fishing_world import Status, validate_action
from sim_bridge.render import FPS, render_cast, save_gif


class BadInput(ValueError):
    """The command line or the action file cannot be used; the message says why."""


def load_action(path: str) -> np.ndarray:
    try:
        data = yaml.safe_load(Path(path).read_text())
    except OSError as error:
        raise BadInput(f"cannot read {path}: {error.strerror or error}") from None
    except yaml.YAMLError:
        raise BadInput(f"{path} is not valid YAML or JSON") from None
    if isinstance(data, dict):
        if "action" not in data:
            raise BadInput(f"{path}: no 'action' key")
        data = data["action"]
    if not isinstance(data, list):
        raise BadInput(f"{path} must hold a list of 24 numbers or a mapping with 'action'")
    try:
        values = [float(v) for v in data]
    except (TypeError, ValueError):
        raise BadInput(f"{path}: the action holds something that is not a number") from None
    action, why = validate_action(values)
    if action is None:
        raise BadInput(f"{path}: {why}")
    return action


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must be WIDTHxHEIGHT, got {text!r}") from None
    if not (32 <= w <= 1920 and 32 <= h <= 1080):
        raise argparse.ArgumentTypeError(f"size {w}x{h} outside 32x32 .. 1920x1080")
    return w, h


def main(argv: list[str] | None = None) -> int:
    p = BriefParser(prog="render_cast", description=__doc__.split("\n\n")[0])
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--action", metavar="FILE", help="YAML/JSON file with 24 numbers")
    source.add_argument("--teaching-index", type=int, metavar="N",
                        help="entry N of the teaching set (see --teaching-set)")
    p.add_argument("--teaching-set", help="teaching-set .npz (default: the packaged one)")
    p.add_argument("--out", required=True, help="the GIF to write (.gif; no MP4 encoder is "
                   "installed, so other formats are refused)")
    p.add_argument("--seed", type=int, default=0, help="the world's noise seed (default 0)")
    p.add_argument("--size", type=parse_size, default=(320, 240),
                   help="WIDTHxHEIGHT of each of the two views (default 320x240)")
    p.add_argument("--fps", type=float, default=FPS, help=f"frames per second (default {FPS})")
    p.add_argument("--slow", type=float, default=2.0,
                   help="slow motion factor of the arm's motion (default 2)")
    p.add_argument("--quiet", action="store_true", help="print nothing")
    args = p.parse_args(argv)
    if not 1 <= args.fps <= 60 or not 0.25 <= args.slow <= 20:
        p.error("--fps must be in [1, 60] and --slow in [0.25, 20]")
    try:
        if Path(args.out).suffix.lower() != ".gif":
            raise BadInput(f"--out {args.out}: render_cast writes animated GIFs only, name the "
                           "file *.gif")
        if args.action is not None:
            action = load_action(args.action)
        else:
            teaching = load_teaching_set(args.teaching_set)
            if not 0 <= args.teaching_index < len(teaching.actions):
                raise BadInput(f"no teaching-set entry {args.teaching_index}: entries are 0 "
                               f"to {len(teaching.actions) - 1}")
            action = teaching.actions[args.teaching_index]
    except (BadInput, OSError, ValueError) as error:
        print(f"render_cast: {error}", file=sys.stderr)
        return 2
    started = time.monotonic()
    try:
        frames, result = render_cast(action, seed=args.seed, size=args.size, fps=args.fps,
                                     slow=args.slow)
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        save_gif(frames, out, fps=args.fps)
    except (OSError, ValueError) as error:
        print(f"render_cast: cannot draw the cast: {error}", file=sys.stderr)
        return 1
    if not args.quiet:
        if result.status == Status.OK:
            what = f"landed at outcome ({result.outcome[0]:+.3f}, {result.outcome[1]:+.3f})"
        else:
            what = f"{Status(result.status).name.lower()}: {result.message}"
        print(f"render_cast: {what}; {len(frames)} frames -> {out} "
              f"({out.stat().st_size / 1e3:.0f} kB, {time.monotonic() - started:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
