"""The fuzz tests' summary: how many cases each target was tried with, and what happened."""

from __future__ import annotations

import pytest

from tests.fuzz.tally import COUNTS, summary


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if COUNTS:
        terminalreporter.section("fuzz cases")
        for line in summary():
            terminalreporter.write_line(line)
