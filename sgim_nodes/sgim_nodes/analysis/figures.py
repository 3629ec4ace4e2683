"""The study's figures as PNG files (matplotlib Agg: no display needed).

  error_curves.png  mean distance to the benchmark goals vs movements, one line per learner,
                    its 95 % band over seeds, the demonstrations as ticks (the paper's main
                    figure)
  landings.png      where the hook landed, rows learners, columns cumulated time frames, pooled
                    over seeds; the isolated region outlined (the paper's exploration figure)
  landings_frames.png  the same for each separate time frame (what was explored when)
  region_tree.png   the leaves of the interest tree at chosen times, coloured by interest, for
                    one seed of each learner that builds a tree (sgim-d, saggriac)
  strategy shares   SGIM-ACTS's choices per window of movements (plot_strategy_shares): the
                    share of each strategy among its episodes, and whom it asked

Why pooled histograms with a shared log scale: a learner's landings pile up in the main basin by
orders of magnitude; a linear scale would hide the few casts in the isolated region, which are
the point of the figure, and a scale per panel would hide the differences between learners.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PatchCollection
from matplotlib.colors import LogNorm, Normalize
from matplotlib.patches import Circle, Rectangle

from sgim_nodes.analysis.statistics import Curve, DemonstrationTimes
from sgim_nodes.analysis.study import STATUS_OK, RunData, Study
from sgim_nodes.core.learner_registry import GOAL_BABBLING, kinds
from sgim_nodes.core.learner_registry import colour as learner_colour
from sim_bridge.lake import ISOLATED_REGION, draw_shoreline

TREE_LEARNERS = tuple(k.name for k in kinds(plugins=False) if k.host == GOAL_BABBLING)
"""The learners whose runs draw a region tree of their own goals."""
BINS = 40
DPI = 110


# For groups that are not a plain learner (a sweep's settings): the tab10 colours no learner
# owns, then tab20's light shades, so that eleven or more curves stay apart.
OTHER_COLOURS = ("tab:orange", "tab:brown", "tab:pink", "tab:olive", "tab:cyan",
                 *(matplotlib.colors.to_hex(matplotlib.colormaps["tab20"](2 * i + 1))
                   for i in range(10)))


def colour(learner: str, k: int) -> str:
    return learner_colour(learner) or OTHER_COLOURS[k % len(OTHER_COLOURS)]


def _outline_isolated(ax: plt.Axes, edge: str = "black") -> None:
    ax.add_patch(Circle(ISOLATED_REGION["centre"], ISOLATED_REGION["radius"], fill=False,
                        edgecolor=edge, linestyle="--", linewidth=1.0))


def _outcome_axes(ax: plt.Axes) -> None:
    ax.set_xlim(-1, 1)
    ax.set_ylim(-1, 1)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)


MANY_CURVES = 5
"""More curves than this (a sweep's settings): a wider figure with the legend beside it."""


def plot_error_curves(curves: dict[str, Curve], path: Path, floor: float | None = None,
                      demonstrations: dict[str, DemonstrationTimes] | None = None) -> Path:
    """``floor``: the benchmark's floor (``analysis.floor``), drawn as a dashed line.
    ``demonstrations``: when each learner's runs were shown one, ticks along the bottom in its
    colour, darker where more of its runs got one at that movement."""
    many = len(curves) > MANY_CURVES  # a sweep: the legend goes beside the axes
    fig, ax = plt.subplots(figsize=(12, 5.5) if many else (8, 5))
    _demonstration_ticks(ax, curves, demonstrations or {})
    if floor is not None:
        ax.axhline(floor, color="black", linestyle="--", linewidth=1,
                   label=f"floor: map lookup cast with noise ({floor:.3f})")
    for k, (learner, c) in enumerate(curves.items()):
        col = colour(learner, k)
        n = f"{int(c.n.min())}" if c.n.min() == c.n.max() else f"{int(c.n.min())}-{int(c.n.max())}"
        ax.plot(c.movements, c.mean, "-o", color=col, markersize=3, linewidth=1.5,
                label=f"{learner} ({n} run{'s' if c.n.max() > 1 else ''})")
        band = np.isfinite(c.low)
        if band.any():
            ax.fill_between(c.movements[band], c.low[band], c.high[band], color=col, alpha=0.2,
                            linewidth=0)
    ax.set_xlabel("movements")
    ax.set_ylabel("mean distance to the benchmark goals (outcome units)")
    ax.set_title("Error on the benchmark goals: mean and 95 % interval over seeds")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    if many:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small",
                  borderaxespad=0.0)
    else:
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _demonstration_ticks(ax: plt.Axes, curves: dict[str, Curve],
                         demonstrations: dict[str, DemonstrationTimes]) -> None:
    rows = [learner for learner in curves if learner in demonstrations]
    bottom = ax.get_xaxis_transform()  # x in movements, y in axes fractions
    height = min(0.035, 0.3 / max(len(rows), 1))  # a sweep's many rows stay in the bottom 30 %
    for row, learner in enumerate(rows):
        times = demonstrations[learner]
        col = colour(learner, list(curves).index(learner))
        y = 0.01 + height * row
        rgb = matplotlib.colors.to_rgb(col)
        ax.vlines(times.movements, y, y + 0.85 * height, transform=bottom, linewidth=0.8,
                  colors=[(*rgb, 0.25 + 0.75 * k / times.runs) for k in times.runs_with_one])
    if rows:  # one legend entry for every row of ticks
        ax.plot([], [], "|", color="grey", markersize=8,
                label="a demonstration, in its learner's colour (darker: in more runs)")


def frame_bounds(frames: Sequence[int], cumulative: bool) -> list[tuple[int, int]]:
    """The movement ranges (start, end], one per panel: 0..end each (cumulated), or between
    consecutive frame ends (the paper's separate time frames)."""
    ends = list(frames)
    starts = [0] * len(ends) if cumulative else [0, *ends[:-1]]
    return list(zip(starts, ends, strict=True))


def _landings(runs: list[RunData], start: int, end: int) -> np.ndarray:
    parts = [r.outcome[(r.movement_index > start) & (r.movement_index <= end)
                       & (r.status == STATUS_OK)] for r in runs]
    points = np.concatenate(parts) if parts else np.zeros((0, 2))
    return points[np.isfinite(points).all(axis=1)]


def plot_landings(study: Study, frames: Sequence[int], path: Path,
                  cumulative: bool = True) -> Path:
    """Rows learners, columns movements 1..frame (``cumulative``) or each separate frame
    (previous frame's end + 1 .. frame); each panel is the share of its landings per bin (so
    frames of different lengths compare), pooled over the seeds."""
    learners = study.learners
    edges = np.linspace(-1, 1, BINS + 1)
    bounds = frame_bounds(frames, cumulative)
    shares: dict[tuple[str, int], tuple[np.ndarray, int]] = {}
    for learner in learners:
        for start, end in bounds:
            points = _landings(study.runs_of(learner), start, end)
            counts, _, _ = np.histogram2d(points[:, 0], points[:, 1], bins=[edges, edges])
            shares[learner, end] = (counts / max(len(points), 1), len(points))
    positive = [s[s > 0] for s, _ in shares.values() if (s > 0).any()]
    low = min((float(p.min()) for p in positive), default=1e-4)
    high = max((float(p.max()) for p in positive), default=1.0)
    norm = LogNorm(vmin=low, vmax=max(high, low * 10))
    rows, cols = len(learners), len(frames)
    fig, axes = plt.subplots(rows, cols, figsize=(2.8 * cols + 1.2, 2.7 * rows + 0.6),
                             squeeze=False)
    mesh = None
    for i, learner in enumerate(learners):
        n_runs = len(study.runs_of(learner))
        for j, (start, end) in enumerate(bounds):
            ax = axes[i][j]
            share, count = shares[learner, end]
            masked = np.ma.masked_where(share.T <= 0, share.T)
            mesh = ax.pcolormesh(edges, edges, masked, norm=norm, cmap="viridis")
            draw_shoreline(ax, resolution=160, colors="0.6", linewidths=0.5)
            _outline_isolated(ax)
            _outcome_axes(ax)
            ax.text(0.02, 0.02, f"{count} landings", transform=ax.transAxes, fontsize=7)
            if i == 0:
                ax.set_title(f"movements {start + 1}-{end}", fontsize=9)
            if j == 0:
                ax.set_ylabel(f"{learner}\n({n_runs} run{'s' if n_runs > 1 else ''})",
                              fontsize=9)
    fig.suptitle("Where the hook landed (share of the frame's landings per bin, pooled over "
                 f"seeds; {'cumulated' if cumulative else 'separate'} time frames; dashed: "
                 "isolated region)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.86, 0.96))
    if mesh is not None:
        fig.colorbar(mesh, cax=fig.add_axes((0.88, 0.15, 0.02, 0.7)), label="share of landings")
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def tree_runs(study: Study, seed: int | None = None) -> list[RunData]:
    """One run per tree-building learner: the requested seed, else the lowest with maps."""
    chosen = []
    for learner in TREE_LEARNERS:
        runs = [r for r in study.runs_of(learner) if len(r.map_index)]
        preferred = [r for r in runs if r.seed == seed]
        if preferred or runs:
            chosen.append((preferred or runs)[0])
    return chosen


def plot_region_trees(study: Study, times: Sequence[int], path: Path, seed: int | None = None
                      ) -> Path | None:
    """Leaves of the recorded RegionMap closest to each time; None when no run has a tree."""
    runs = tree_runs(study, seed)
    if not runs:
        return None
    snapshots = {(r.name, t): r.region_map_at(t) for r in runs for t in times}
    interests = np.concatenate([s[3] for s in snapshots.values()] + [np.zeros(1)])
    norm = Normalize(vmin=min(0.0, float(interests.min())),
                     vmax=max(float(interests.max()), 1e-9))
    cols = len(times)
    fig, axes = plt.subplots(len(runs), cols, figsize=(2.9 * cols + 1.2, 2.9 * len(runs) + 0.6),
                             squeeze=False)
    for i, run in enumerate(runs):
        for j, t in enumerate(times):
            ax = axes[i][j]
            at, lower, upper, interest = snapshots[run.name, t]
            boxes = [Rectangle(lo, *(hi - lo)) for lo, hi in zip(lower, upper, strict=True)]
            patches = PatchCollection(boxes, cmap="magma", norm=norm, edgecolor="white",
                                      linewidth=0.4)
            patches.set_array(interest)
            ax.add_collection(patches)
            _outline_isolated(ax, edge="tab:cyan")  # visible on dark and light leaves
            _outcome_axes(ax)
            leaves = f"{len(boxes)} lea{'f' if len(boxes) == 1 else 'ves'}"
            ax.set_title(f"movement {t}\n(map at {at}, {leaves})", fontsize=8)
            if j == 0:
                ax.set_ylabel(f"{run.learner} seed {run.seed}", fontsize=9)
    fig.suptitle("Interest tree: leaf regions coloured by interest (competence progress)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.9, 0.95))
    mappable = plt.cm.ScalarMappable(norm=norm, cmap="magma")
    fig.colorbar(mappable, cax=fig.add_axes((0.92, 0.15, 0.02, 0.7)), label="interest")
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _strategy_colour(name: str, teachers: list[str]) -> tuple[tuple[float, ...], str]:
    """A strategy's colour and hatch: grey alone; a teacher's colour, solid for mimicry and
    hatched for emulation, so that one teacher's two strategies read as one hue."""
    kind, _, teacher = name.partition(":")
    if not teacher:
        return matplotlib.colors.to_rgba("lightgrey"), ""
    rgb = matplotlib.colormaps["tab10"](teachers.index(teacher) % 10)
    return rgb, "" if kind == "mimicry" else "///"


def plot_strategy_shares(shares: dict[int, dict[str, float]],
                         asks: dict[int, dict[str, float]], window: int, runs: int,
                         path: Path) -> Path:
    """Two panels over windows of ``window`` movements (keys: a window's first movement):
    the mean over ``runs`` runs of each strategy's share of the episodes chosen in the window,
    and the mean number of requests per run sent to each teacher; strategies and teachers
    stacked in the order the mappings name them."""
    starts = sorted(set(shares) | set(asks))
    strategies = list(dict.fromkeys(s for v in shares.values() for s in v))
    teachers = list(dict.fromkeys([*(s.partition(":")[2] for s in strategies if ":" in s),
                                   *(t for v in asks.values() for t in v)]))
    x = np.array(starts, dtype=float) + window / 2
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    base = np.zeros(len(starts))
    for name in strategies:
        values = np.array([shares.get(s, {}).get(name, 0.0) for s in starts])
        rgba, hatch = _strategy_colour(name, teachers)
        top.bar(x, values, width=0.9 * window, bottom=base, color=rgba, hatch=hatch,
                edgecolor="white" if not hatch else "black", linewidth=0.3, label=name)
        base += values
    top.set_ylim(0, 1)
    top.set_ylabel("share of the episodes chosen")
    top.set_title(f"SGIM-ACTS's strategies per window of {window} movements "
                  f"(mean over {runs} runs)")
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    base = np.zeros(len(starts))
    for teacher in teachers:
        values = np.array([asks.get(s, {}).get(teacher, 0.0) for s in starts])
        rgba, _ = _strategy_colour(f"mimicry:{teacher}", teachers)
        bottom.bar(x, values, width=0.9 * window, bottom=base, color=rgba, edgecolor="white",
                   linewidth=0.3, label=teacher)
        base += values
    bottom.set_ylabel("requests per run")
    bottom.set_xlabel("movements")
    bottom.set_title("Whom it asked: requests per teacher (mimicry and emulation)")
    bottom.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    for ax in (top, bottom):
        ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_share_curves(curves: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]],
                      goals: dict[str, float], window: int, path: Path) -> Path:
    """One panel per share (``goals``: its title and goal line), one line per arm: ``curves``
    maps an arm to (window middles, first share, second share), shares in [0, 1]."""
    fig, axes = plt.subplots(1, len(goals), figsize=(5.2 * len(goals) + 1.6, 3.8),
                             sharey=True, squeeze=False)
    for k, (ax, (title, goal)) in enumerate(zip(axes[0], goals.items(), strict=True)):
        for j, (arm, series) in enumerate(curves.items()):
            ax.plot(series[0], 100 * series[1 + k], marker="o", markersize=3,
                    color=plt.get_cmap("tab10")(j), label=arm)
        ax.axhline(100 * goal, color="black", linestyle="--", linewidth=1,
                   label=f"goal ({100 * goal:.0f} %)")
        ax.set_title(f"{title}, per window of {window} movements", fontsize=10)
        ax.set_xlabel("movements")
        ax.set_ylim(0, 100)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("share of the requests (%)")
    axes[0][-1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path
