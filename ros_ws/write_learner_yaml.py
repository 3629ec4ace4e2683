"""Write the generated sections of the parameter files from the core's declarations.

sgim_nodes/config/learner.yaml, which every node reads: its learner parameters and their
comments come from the field defaults and docstrings of sgim_nodes/core/config.py, and its
teacher's settings from sgim_nodes/core/social_config.py. teacher/config/teacher.yaml: the
teacher's settings, from the same declarations. The files cannot drift from the code
(tests/core/test_learner_yaml.py compares them).

Run: .venv/bin/python ros_ws/write_learner_yaml.py           (rewrites the file)
     .venv/bin/python ros_ws/write_learner_yaml.py --check   (exit 1 if it is out of date)
"""

from __future__ import annotations

import argparse
import ast
import sys
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CONFIG_SOURCE = REPO / "sgim_nodes" / "sgim_nodes" / "core" / "config.py"
YAML_FILE = REPO / "sgim_nodes" / "config" / "learner.yaml"
TEACHER_FILE = REPO / "teacher" / "config" / "teacher.yaml"
MARKER = "    # --- the learner (LearnerConfig"
SOCIAL_MARKER = "    # --- the teacher (SocialConfig"
SECTION = "    # ---"
LEARNER_SOCIAL = ("demonstration_period", "timing", "demonstration_content", "teacher_choice")
"""The teacher's settings the arbiter or the teacher read, in the file every node reads."""
TEACHER_SOCIAL = ("demonstration_period", "reached_rule", "teacher_choice",
                  "demonstration_content", "timing", "tolerance_noise")


def learner_section() -> str:
    sys.path.insert(0, str(REPO / "sgim_nodes"))
    from sgim_nodes.core.config import LearnerConfig

    default = LearnerConfig()
    tree = ast.parse(CONFIG_SOURCE.read_text())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "LearnerConfig")
    lines = [MARKER + "; distances in units of the world's outcome noise (*_noise), of its box"
             " side (*_size) or of action units (*_action)) ---"]
    for i, node in enumerate(cls.body):
        if not isinstance(node, ast.AnnAssign):
            continue
        name = node.target.id
        nxt = cls.body[i + 1] if i + 1 < len(cls.body) else None
        doc = (" ".join(nxt.value.value.split()) if isinstance(nxt, ast.Expr)
               and isinstance(nxt.value, ast.Constant) else "")
        lines += ["    # " + line for line in textwrap.wrap(doc, 94)]
        lines.append(f"    {name}: {getattr(default, name)}")
    return "\n".join(lines) + "\n"


def social_section(names: tuple[str, ...]) -> str:
    """The SOCIAL_MARKER section: each setting's default and its meaning in one line."""
    sys.path.insert(0, str(REPO / "sgim_nodes"))
    from sgim_nodes.core.social_config import declared

    lines = [SOCIAL_MARKER + " in sgim_nodes/core/social_config.py; generated) ---"]
    for name in names:
        d = declared(name)
        lines.append(f"    {name}: {d['default']}  # {d['help']}")
    return "\n".join(lines) + "\n"


def _with_social(text: str, names: tuple[str, ...]) -> str:
    """``text`` with its SOCIAL_MARKER section, up to the next section, made again."""
    start = text.index(SOCIAL_MARKER)
    end = text.index(SECTION, start + len(SOCIAL_MARKER))
    return text[:start] + social_section(names) + text[end:]


def expected_text() -> str:
    text = _with_social(YAML_FILE.read_text(), LEARNER_SOCIAL)
    return text[:text.index(MARKER)] + learner_section()


def expected_teacher_text() -> str:
    return _with_social(TEACHER_FILE.read_text(), TEACHER_SOCIAL)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="only check; exit 1 if out of date")
    args = p.parse_args(argv)
    stale = 0
    for path, new in ((YAML_FILE, expected_text()), (TEACHER_FILE, expected_teacher_text())):
        if new == path.read_text():
            continue
        if args.check:
            print(f"{path} is out of date: run {Path(__file__).name}", file=sys.stderr)
            stale = 1
        else:
            path.write_text(new)
            print(f"wrote {path}")
    return stale


if __name__ == "__main__":
    raise SystemExit(main())
