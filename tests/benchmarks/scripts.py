"""The benchmark scripts as modules: they live in benchmarks/, outside any package."""

from __future__ import annotations

import importlib.util
from types import ModuleType

from tests.conftest import REPO


def load_benchmark(name: str) -> ModuleType:
    """benchmarks/NAME.py, imported afresh."""
    spec = importlib.util.spec_from_file_location(name, REPO / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
