"""The test suite's time as CI sees it (issue 32: a clean clone's `./test.sh` in 10 minutes on
2 quiet cores, `./test.sh --quick` in 2): clone the repository's HEAD into a scratch folder,
run `./bootstrap.sh` there (the venv, the workspace), then `./test.sh`, and print the wall and
CPU time of each step, the tests' count and the longest tests.

    python benchmarks/bench_suite.py             # the whole suite
    python benchmarks/bench_suite.py --quick     # the developer's loop
    python benchmarks/bench_suite.py --keep      # keep the clone, to look at what it made

Run it on a quiet machine: the suite is bound by the CPU, so anything else running lengthens
it. The clone shares nothing with this checkout (its own .venv and workspace); pip's download
cache is the user's, as on a machine that has installed once.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
LONGEST = 15
_SUMMARY = re.compile(r"^=*\s*(?P<counts>\d+ [a-z]+(?:, \d+ [a-z]+)*) in (?P<seconds>[\d.]+)s")
_DURATION = re.compile(r"^(?P<seconds>[\d.]+)s (?P<phase>call|setup|teardown) +(?P<test>\S+)")


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(argv: list[str], cwd: Path, log: Path) -> tuple[int, float, float]:
    """(exit code, wall seconds, CPU seconds of it and its children), its output in `log`."""
    began, cpu = time.perf_counter(), children_cpu()
    with log.open("w") as out:
        code = subprocess.call(argv, cwd=cwd, stdout=out, stderr=subprocess.STDOUT)
    return code, time.perf_counter() - began, children_cpu() - cpu


def summary(output: str) -> tuple[str, float] | None:
    """pytest's summary: ('1 failed, 1103 passed, 2 warnings', 798.2), or None without one."""
    found = None
    for line in output.splitlines():
        match = _SUMMARY.search(line)
        if match:
            found = (match["counts"], float(match["seconds"]))
    return found


def longest(output: str, count: int = LONGEST) -> list[tuple[float, str]]:
    """The longest tests of pytest's --durations table, setup, call and teardown added."""
    totals: dict[str, float] = {}
    for line in output.splitlines():
        match = _DURATION.match(line.strip())
        if match:
            totals[match["test"]] = totals.get(match["test"], 0.0) + float(match["seconds"])
    return sorted(((s, t) for t, s in totals.items()), reverse=True)[:count]


def failures(output: str, limit: int = 12_000) -> str:
    """pytest's FAILURES section (each failure's traceback and node logs), at most `limit`
    characters of it: what a failed timing run must show, since its clone is removed."""
    start = output.find("= FAILURES =")
    if start < 0:
        return ""
    start = output.rfind("\n", 0, start) + 1
    ends = [i for i in (output.find(" warnings summary ", start),
                        output.find(" short test summary info ", start)) if i >= 0]
    end = output.rfind("\n", 0, min(ends)) + 1 if ends else len(output)
    text = output[start:end]
    return text if len(text) <= limit else text[:limit] + "\n[... cut]\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="time ./test.sh --quick")
    p.add_argument("--keep", action="store_true", help="keep the clone and its logs")
    args = p.parse_args(argv)
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True, check=True).stdout.strip()
    scratch = Path(tempfile.mkdtemp(prefix="bench-suite-"))
    clone = scratch / "repo"
    try:
        subprocess.run(["git", "clone", "-q", str(REPO), str(clone)], check=True)
        env_note = f"PYTHONDONTWRITEBYTECODE={os.environ.get('PYTHONDONTWRITEBYTECODE', '')}"
        print(f"a clean clone of {head} in {clone} ({os.cpu_count()} cores, {env_note})",
              flush=True)
        code, boot_wall, boot_cpu = timed(["./bootstrap.sh"], clone, scratch / "bootstrap.log")
        print(f"bootstrap:  {boot_wall:6.0f} s wall, {boot_cpu:6.0f} s CPU (exit {code})",
              flush=True)
        if code != 0:
            print((scratch / "bootstrap.log").read_text()[-3000:], file=sys.stderr)
            return 1
        tests = ["./test.sh", *(["--quick"] if args.quick else []), "--durations", "40"]
        code, wall, cpu = timed(tests, clone, scratch / "test.log")
        output = (scratch / "test.log").read_text(errors="replace")
        found = summary(output)
        print(f"{' '.join(tests[:2] if args.quick else tests[:1])}: {wall:6.0f} s wall, "
              f"{cpu:6.0f} s CPU (exit {code}); pytest: "
              + (f"{found[0]} in {found[1]:.0f} s" if found else "no summary line"))
        print(f"in all:     {boot_wall + wall:6.0f} s wall, {boot_cpu + cpu:6.0f} s CPU "
              f"({(boot_wall + wall) / 60:.1f} min)")
        print(f"the {LONGEST} longest tests (setup, call and teardown):")
        for seconds, test in longest(output):
            print(f"  {seconds:6.1f} s  {test}")
        if code != 0:
            kept = Path(tempfile.gettempdir()) / f"bench-suite-{head}-test.log"
            shutil.copyfile(scratch / "test.log", kept)
            print(failures(output) or output[-3000:], file=sys.stderr)
            print(f"the whole output: {kept}", file=sys.stderr)
        return 0 if code == 0 else 1
    finally:
        if args.keep:
            print(f"kept: {scratch}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
