"""The reports of the pinned experiments: each turns its runs into a page's generated blocks.

A report module has ``make(experiment, runs_dir, figures_dir) -> Report``; REPORTS names them
by the experiment file's ``report`` key, imported only when used.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

REPORTS = {"study": "study", "social_modes": "social_modes", "learners": "learners",
           "isolated_region": "isolated_region", "active_strategies": "active_strategies",
           "world": "world"}


@dataclass
class Report:
    """Blocks by page, then by block name; figures written; notes for the provenance."""

    blocks: dict[str, dict[str, str]] = field(default_factory=dict)
    figures: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def add(self, page: str, name: str, text: str) -> None:
        self.blocks.setdefault(page, {})[name] = text


def maker(name: str) -> Callable:
    if name not in REPORTS:
        raise KeyError(f"no report {name!r} (reports: {', '.join(REPORTS)})")
    return importlib.import_module(f"sgim_nodes.experiments.reports.{REPORTS[name]}").make
