"""Values and texts cut to a size fit for a one-line message (a refusal, a log line, a web
page's reply), the same way everywhere: cut in the middle, so that a long path keeps its file
name and a long message its end as well as its start."""

from __future__ import annotations

from typing import Any

HUGE_INT = 10**40


def clipped(text: str, limit: int = 80) -> str:
    """``text`` itself if it fits in ``limit`` characters, else its start and end around
    "..."."""
    if len(text) <= limit:
        return text
    head = (limit - 3) // 2
    return text[:head] + "..." + text[len(text) - (limit - 3 - head):]


def value_text(value: Any, limit: int = 80) -> str:
    """A value in a message: its repr, clipped. An integer of thousands of digits has no repr
    (Python refuses to print it), and a structure nested as deep as the interpreter allows
    none either: each is named instead."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > HUGE_INT:
        return f"an integer of {value.bit_length()} bits"
    try:
        return clipped(repr(value), limit)
    except RecursionError:
        return f"a {type(value).__name__} nested too deep to show"
