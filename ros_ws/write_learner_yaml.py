"""Write the learner section of sgim_nodes/config/learner.yaml from LearnerConfig itself.

Every node reads that file; its learner parameters and their comments come from the field
defaults and docstrings of sgim_nodes/core/config.py, so the file cannot drift from the code
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
MARKER = "    # --- the learner (LearnerConfig"


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


def expected_text() -> str:
    text = YAML_FILE.read_text()
    return text[:text.index(MARKER)] + learner_section()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="only check; exit 1 if out of date")
    args = p.parse_args(argv)
    new = expected_text()
    if args.check:
        if new != YAML_FILE.read_text():
            print(f"{YAML_FILE} is out of date: run {Path(__file__).name}", file=sys.stderr)
            return 1
        return 0
    YAML_FILE.write_text(new)
    print(f"wrote {YAML_FILE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
