"""Every relative link and image of the repository's Markdown points at something that exists.

A link into a Markdown file with `#anchor` must name one of its headings, slugged as GitHub
slugs them (lowercase; punctuation dropped but '-' and '_'; spaces to '-'; a repeated heading
gets -1, -2...). External links are not fetched: the suite runs offline. Pure Python, no
site generator: the whole check reads a few hundred kB of text (well under a second).
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from urllib.parse import unquote

from tests.conftest import REPO

# Not the project's pages: tools' caches and environments, builds, runs' outputs.
SKIPPED = {"node_modules", "runs", "ros_ws/build", "ros_ws/install", "ros_ws/log"}
FENCE = re.compile(r"^ {0,3}(```|~~~)")
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1")
INLINE = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]"  # [text], one level of [] inside
                    r"\(\s*(<[^>]*>|[^\s()]*(?:\([^\s()]*\)[^\s()]*)*)"  # (target
                    r"(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^)]*\)))?\s*\)")  # "title")
REFERENCE = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
HTML = re.compile(r"<(?:a|img|source)\b[^>]*?\b(?:href|src)\s*=\s*[\"']([^\"']*)[\"']", re.I)
HTML_ANCHOR = re.compile(r"<a\b[^>]*?\b(?:name|id)\s*=\s*[\"']([^\"']*)[\"']", re.I)
ATX = re.compile(r"^ {0,3}(#{1,6})(?:[ \t]+(.*?))?(?:[ \t]+#+)?[ \t]*$")
SETEXT = re.compile(r"^ {0,3}(=+|-+)[ \t]*$")
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def markdown_files(root: Path = REPO) -> list[Path]:
    """Every *.md of the repository but those in hidden or SKIPPED directories."""
    found = []
    for path in root.rglob("*.md"):
        parts = path.relative_to(root).parts
        if not any(p.startswith(".") for p in parts[:-1]) and not any(
                "/".join(parts[:i]) in SKIPPED for i in range(1, len(parts))):
            found.append(path)
    return sorted(found)


def prose_lines(text: str) -> Iterator[tuple[int, str]]:
    """(line number, line) outside fenced code blocks, code spans blanked."""
    fence = ""
    for number, line in enumerate(text.splitlines(), 1):
        opened = FENCE.match(line)
        if fence:
            if opened and line.strip().startswith(fence):
                fence = ""
            continue
        if opened:
            fence = opened.group(1)
            continue
        yield number, CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line)


def slug(heading: str) -> str:
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link: its text
    text = re.sub(r"<[^>]+>", "", text).replace("`", "")
    text = re.sub(r"(\*+|_+)(\S(?:.*?\S)?)\1", r"\2", text)  # emphasis
    kept = (c for c in text.strip().lower()
            if c in " -_" or unicodedata.category(c)[0] in "LMN")
    return "".join(kept).replace(" ", "-")


@cache
def anchors(path: Path) -> frozenset[str]:
    """The anchors a Markdown file offers: its headings' slugs and its HTML anchors."""
    seen: dict[str, int] = {}
    found: set[str] = set()
    previous = ""
    for _, line in prose_lines(path.read_text(encoding="utf-8")):
        heading = ATX.match(line)
        text = (heading.group(2) or "") if heading else None
        if text is None and previous.strip() and SETEXT.match(line):
            text = previous.strip()
        if text is not None:
            base = slug(text)
            count = seen.get(base, 0)
            seen[base] = count + 1
            found.add(f"{base}-{count}" if count else base)
        found.update(HTML_ANCHOR.findall(line))
        previous = "" if heading else line
    return frozenset(found)


def targets(path: Path) -> Iterator[tuple[int, str]]:
    """(line, target) of every link, image and reference definition of a Markdown file."""
    for number, line in prose_lines(path.read_text(encoding="utf-8")):
        for pattern in (INLINE, REFERENCE, HTML):
            for match in pattern.finditer(line):
                yield number, match.group(1).strip("<>")


def problem(source: Path, target: str) -> str | None:
    """Why a link does not resolve, or None when it does (or is external)."""
    if not target or SCHEME.match(target) or target.startswith("//"):
        return None
    where, _, anchor = target.partition("#")
    where = unquote(where.split("?")[0])
    if where.startswith("/"):
        resolved = REPO / where.lstrip("/")
    else:
        resolved = (source.parent / where) if where else source
    if not resolved.exists():
        return "no such file"
    if anchor and resolved.suffix == ".md" and unquote(anchor).lower() not in anchors(
            resolved.resolve()):
        return f"no heading with anchor #{anchor} in {resolved.name}"
    return None


def broken_links(files: list[Path]) -> list[str]:
    return [f"{path.relative_to(REPO)}:{number}: {target} ({why})"
            for path in files for number, target in targets(path)
            if (why := problem(path, target))]


def test_every_relative_link_and_anchor_resolves():
    files = markdown_files()
    assert REPO / "README.md" in files and REPO / "docs" / "reference.md" in files
    broken = broken_links(files)
    assert not broken, f"{len(broken)} broken links:\n" + "\n".join(broken)


def test_slugs_follow_githubs_rules():
    assert slug("How close the learners get") == "how-close-the-learners-get"
    assert slug("4e. The error oracle (by error²)") == "4e-the-error-oracle-by-error²"
    assert slug("`reach_goal` jobs: *why*") == "reach_goal-jobs-why"
    assert slug("Two  spaces -- and [a link](x.md)") == "two--spaces----and-a-link"


def test_the_checker_finds_what_is_broken(tmp_path, monkeypatch):
    monkeypatch.setitem(globals(), "REPO", tmp_path)
    (tmp_path / "img.png").write_bytes(b"")
    page = tmp_path / "a.md"
    page.write_text(
        "# Title\n\n## Part\n\n## Part\n\nA [fine](a.md#part-1) ![img](img.png) [web](https://x.y)"
        " [self](#title) [dir](.) [root](/img.png)\n[gone](b.md) ![gone](no.png) [bad](#nope)\n"
        "`[in code](c.md)`\n```\n[in a fence](d.md)\n```\n[ref]: e.md\n<img src=\"f.png\">\n")
    assert broken_links([page]) == [
        "a.md:8: b.md (no such file)", "a.md:8: no.png (no such file)",
        "a.md:8: #nope (no heading with anchor #nope in a.md)",
        "a.md:13: e.md (no such file)", "a.md:14: f.png (no such file)"]
