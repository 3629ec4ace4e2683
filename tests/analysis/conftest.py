"""Fixtures: a synthetic study of real bags (see synthetic_study.py)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from synthetic_study import write_study


@pytest.fixture
def study(tmp_path: Path) -> Path:
    return write_study(tmp_path / "study")


@pytest.fixture
def make_study(tmp_path: Path) -> Callable[..., Path]:
    def make(name: str = "study", **kwargs) -> Path:
        return write_study(tmp_path / name, **kwargs)

    return make
