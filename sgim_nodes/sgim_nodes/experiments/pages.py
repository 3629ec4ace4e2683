"""Generated parts of a hand-written page, and the banner of a page the learner has outgrown.

A page holds prose around blocks the tool writes:

    <!-- begin generated final-errors -->
    ... (replaced at every regeneration)
    <!-- end generated final-errors -->

The block named ``provenance`` holds the provenance block (provenance/record.py) of the
experiment that made the page. When today's checkout gives the experiment another fingerprint,
the page is stale: ``mark_stale`` puts a banner under its title, and ``problems`` (run by the
test suite) reports a stale page without one.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from sgim_nodes.provenance.record import Provenance

_BLOCK = re.compile(r"(<!-- begin generated (?P<name>[\w.-]+) -->\n)(?P<body>.*?)"
                    r"(<!-- end generated (?P=name) -->)", re.S)
_STALE = re.compile(r"<!-- stale (?P<name>[\w.-]+): begin -->\n.*?"
                    r"<!-- stale (?P=name): end -->\n", re.S)
_STALE_AND_GAP = re.compile(_STALE.pattern + r"\n?", re.S)


class PageError(ValueError):
    """A page that lacks the blocks an experiment writes into it."""


def blocks_of(text: str) -> dict[str, str]:
    return {m["name"]: m["body"] for m in _BLOCK.finditer(text)}


def fill(text: str, blocks: Mapping[str, str], where: str) -> str:
    """The page with each named block's body replaced; PageError naming the missing ones."""
    missing = sorted(set(blocks) - set(blocks_of(text)))
    if missing:
        raise PageError(f"{where} has no block for {', '.join(missing)}: put "
                        + ", ".join(f"'<!-- begin generated {n} -->' and "
                                    f"'<!-- end generated {n} -->'" for n in missing)
                        + " where each belongs")

    def replace(match: re.Match) -> str:
        name = match["name"]
        if name not in blocks:
            return match[0]
        body = blocks[name].rstrip("\n") + "\n"
        return f"{match[1]}{body}{match[4]}"

    return _BLOCK.sub(replace, text)


def write_page(path: Path, blocks: Mapping[str, str], experiment: str) -> None:
    """Fill the page's blocks and drop the experiment's stale banner (it is fresh now)."""
    text = path.read_text(encoding="utf-8")
    text = remove_banner(fill(text, blocks, str(path)), experiment)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def provenance_of(text: str, experiment: str) -> Provenance | None:
    """The provenance of the experiment's blocks in the page (None if it has none)."""
    for name, body in blocks_of(text).items():
        if name == "provenance" or name.startswith("provenance"):
            found = Provenance.parse(body)
            if found is not None and found.experiment == experiment:
                return found
    return None


def banner(experiment: str, made: Provenance | None, expected: str) -> str:
    """What a stale page says under its title: which code made its figures, or that today's
    code has not made them yet."""
    if made is None:
        said = (f"> **Not made yet.** Today's code (learner fingerprint `{expected}`) has not "
                f"made this page's generated parts. `ros_ws/reproduce.sh {experiment}` makes "
                "them.")
    else:
        said = (f"> **Stale.** The figures of this page come from commit {made.commit} "
                f"(learner fingerprint `{made.fingerprint}`); its runs have changed since, by "
                f"the learner's code or by what the experiment pins (today's fingerprint is "
                f"`{expected}`), so they may differ from what today's code makes. "
                f"`ros_ws/reproduce.sh {experiment}` makes them again.")
    return f"<!-- stale {experiment}: begin -->\n{said}\n\n<!-- stale {experiment}: end -->\n"


def has_banner(text: str, experiment: str) -> bool:
    return any(m["name"] == experiment for m in _STALE.finditer(text))


def remove_banner(text: str, experiment: str) -> str:
    """The page without its banner of ``experiment``, and without the blank line that
    with_banner put after it: the page as it was before it was marked."""
    return _STALE_AND_GAP.sub(lambda m: "" if m["name"] == experiment else m[0], text)


def replace_banner(text: str, block: str, experiment: str) -> str:
    """The page with its banner of ``experiment`` replaced by ``block``, where it stands."""
    return _STALE.sub(lambda m: block if m["name"] == experiment else m[0], text)


def with_banner(text: str, block: str) -> str:
    """The banner right under the page's title (its first line starting with '# ')."""
    lines = text.splitlines(keepends=True)
    at = next((i + 1 for i, line in enumerate(lines) if line.startswith("# ")), 0)
    while at < len(lines) and not lines[at].strip():
        at += 1
    return "".join(lines[:at]) + block + "\n" * (at > 0 and not block.endswith("\n\n")) \
        + "".join(lines[at:])


@dataclass(frozen=True)
class Freshness:
    page: Path
    experiment: str
    made: Provenance | None
    expected: str
    aliases: Mapping[str, str] = field(default_factory=dict)
    """Page fingerprints of code whose runs did what today's do (references.aliases_of)."""

    @property
    def fresh(self) -> bool:
        if self.made is None:
            return False
        made = self.made.fingerprint
        return made == self.expected or self.aliases.get(made) == self.expected

    def why(self) -> str:
        if self.made is None:
            return "holds no provenance of this experiment"
        return f"was made with fingerprint {self.made.fingerprint} at commit {self.made.commit}"


def freshness(page: Path, experiment: str, expected: str,
              aliases: Mapping[str, str] | None = None) -> Freshness:
    return Freshness(page, experiment, provenance_of(page.read_text(encoding="utf-8"),
                                                     experiment), expected, dict(aliases or {}))
