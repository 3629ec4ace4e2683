"""A throw-away repository for the experiments' tests: experiments/ (its shipped run tables
too), docs/ and runs/ of its own, which `reproduce.sh` (experiments/cli.py) reads and writes
instead of the project's."""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

from sgim_nodes.experiments import cli, pinned, shipped
from sgim_nodes.experiments.pinned import pin_of
from sgim_nodes.provenance.fingerprint import data_files


@dataclass(frozen=True)
class ScratchRepo:
    root: Path

    def experiment(self, name: str, body: str) -> Path:
        """experiments/NAME.yaml: `body` (dedented), then today's data files pinned."""
        pins = {n: pin_of(p) for n, p in data_files().items()}
        path = self.root / "experiments" / f"{name}.yaml"
        path.write_text(textwrap.dedent(body) + "data: "
                        + yaml.safe_dump(pins, default_flow_style=True, width=10**4))
        return path

    def page(self, relative: str, text: str) -> Path:
        path = self.root / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        return path


@pytest.fixture
def scratch_repo(tmp_path, monkeypatch) -> ScratchRepo:
    (tmp_path / "experiments").mkdir()
    (tmp_path / "docs").mkdir()
    for module in (pinned, cli):
        monkeypatch.setattr(module, "REPO", tmp_path)
        monkeypatch.setattr(module, "EXPERIMENTS", tmp_path / "experiments")
    monkeypatch.setattr(cli, "FIGURES", tmp_path / "docs" / "figures")
    monkeypatch.setattr(shipped, "SHIPPED", tmp_path / "experiments" / "shipped")
    monkeypatch.setenv("SGIM_EXPERIMENT_RUNS", str(tmp_path / "runs"))
    return ScratchRepo(tmp_path)
