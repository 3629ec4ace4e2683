"""`ros_ws/reproduce.sh NAME`: make a pinned experiment's runs, analyse them, write its pages.

One command per page: the experiment file (experiments/NAME.yaml) fixes the runs, the runs are
made or resumed (here, several side by side, or on a Ray cluster with --address), and the
report writes the page's generated blocks and figures, with a provenance block saying what
made them. Hand-written prose around the blocks stays as it is.

`--check` (run by the test suite) says which pages are stale: their runs would not do today
what they did, and the page lacks the banner that says so; `--mark-stale` writes that banner.
What runs do is known by reference runs (experiments/references.py), kept in
experiments/references.yaml; `--references` makes them again after a change of the code and
says which experiments' runs changed.

Exit codes: 0 done, 1 a run or the report failed, or --check found a stale page without its
banner, 2 refused (unknown experiment, a bad experiment file, data files other than pinned).
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from sgim_nodes.experiments import pages
from sgim_nodes.experiments.makers import make_runs, say
from sgim_nodes.experiments.pinned import (
    EXPERIMENTS,
    REPO,
    Experiment,
    ExperimentError,
    all_experiments,
    experiment_files,
    find,
)
from sgim_nodes.experiments.references import (
    ReferencesOutdated,
    aliases_of,
    make_references,
    read_table,
    write_table,
)
from sgim_nodes.provenance.fingerprint import environment
from sgim_nodes.provenance.record import Provenance
from sgim_ros.command_line import BriefParser

FIGURES = REPO / "docs" / "figures"


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    known = ", ".join(p.stem for p in experiment_files(EXPERIMENTS))
    p = BriefParser(
        prog="ros_ws/reproduce.sh", description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=f"experiments: {known}\nexample: ros_ws/reproduce.sh study --parallel 2")
    p.add_argument("names", nargs="*", metavar="NAME", help="experiments to reproduce")
    p.add_argument("--all", action="store_true", help="every experiment of experiments/")
    p.add_argument("--parallel", type=int, default=2,
                   help="runs side by side on this machine (default: %(default)s)")
    p.add_argument("--address", help="make the runs on this Ray cluster (HOST:PORT)")
    p.add_argument("--runs-dir", type=Path,
                   help="where the runs go (one experiment only; default "
                        "runs/experiments/NAME)")
    p.add_argument("--report-only", action="store_true",
                   help="make no run: analyse the runs there and write the pages")
    p.add_argument("--runs-only", action="store_true", help="make the runs, write no page")
    p.add_argument("--ship", action="store_true",
                   help="make no run and no page: write a run table into experiments/shipped/ "
                        "for each finished run of today's code (a full reproduce ships too)")
    p.add_argument("--verify", type=int, metavar="K",
                   help="make K shipped runs again, drawn at random, and check each against "
                        "its run table movement for movement (by the runner; --graph: "
                        "through the graph); a runner or world experiment: K of its jobs, "
                        "against their shipped result files")
    p.add_argument("--verify-movements", type=int, metavar="N",
                   help="--verify checks each run's first N movements only (a cast chunk's "
                        "first N casts), made again at that length: the quick check")
    p.add_argument("--verify-seed", type=int, metavar="S",
                   help="the seed that draws the runs --verify checks (default: one it prints)")
    p.add_argument("--graph", action="store_true",
                   help="--verify makes the runs through the node graph")
    p.add_argument("--ignore-shipped", action="store_true",
                   help="make the runs the repository ships too (experiments/shipped/)")
    p.add_argument("--keep-unlike", action="store_true",
                   help="keep runs made by another learner instead of making them again")
    p.add_argument("--list", action="store_true",
                   help="each experiment: its pages, fingerprint, state and runs")
    p.add_argument("--check", action="store_true",
                   help="fail on a stale page without its banner, or on unpinned data")
    p.add_argument("--mark-stale", action="store_true",
                   help="write the banner into every stale page")
    p.add_argument("--references", action="store_true",
                   help="make the reference runs of the named experiments (or all) that "
                        "today's code lacks, and say whose runs changed")
    p.add_argument("--pin", action="store_true",
                   help="write today's data file hashes into the named experiment files")
    args = p.parse_args(argv)
    if args.parallel < 1:
        p.error("--parallel must be >= 1")
    if args.runs_dir and len(args.names) != 1:
        p.error("--runs-dir needs exactly one experiment")
    if sum((args.report_only, args.runs_only, args.ship, args.verify is not None)) > 1:
        p.error("--report-only, --runs-only, --ship and --verify exclude each other")
    if args.verify is not None and args.verify < 1:
        p.error("--verify must be >= 1")
    if (args.graph or args.verify_seed is not None or args.verify_movements is not None) \
            and args.verify is None:
        p.error("--graph, --verify-seed and --verify-movements go with --verify")
    if args.verify_movements is not None and args.verify_movements < 1:
        p.error("--verify-movements must be >= 1")
    if not (args.names or args.all or args.list or args.check or args.mark_stale
            or args.references):
        p.error("name an experiment (or --all, --list, --check, --mark-stale, --references)")
    return args


def selected(args: argparse.Namespace) -> list[Experiment]:
    if args.all or not args.names:
        return all_experiments()
    return [find(name) for name in args.names]


def check(experiments: list[Experiment], mark: bool) -> int:
    """Every page of every experiment: fresh, or bannered (written with ``mark``)."""
    problems = 0
    for exp in experiments:
        for problem in exp.data_problems():
            print(f"{exp.path.name}: {problem} (ros_ws/reproduce.sh {exp.name} --pin pins "
                  "today's files; the pages then need making again)")
            problems += 1
        table = read_table(exp.references_path)
        try:
            expected = exp.fingerprint(table)
        except ReferencesOutdated as error:
            print(f"{exp.name}: {error}")
            problems += 1
            continue
        for page in exp.pages:
            path = REPO / page
            state = pages.freshness(path, exp.name, expected, aliases_of(table, exp.name))
            text = path.read_text(encoding="utf-8")
            if state.fresh:
                if pages.has_banner(text, exp.name):
                    path.write_text(pages.remove_banner(text, exp.name), encoding="utf-8") \
                        if mark else print(f"{page}: fresh, but it says it is stale "
                                           f"({exp.name}); --mark-stale takes the banner off")
                continue
            if mark:  # a banner says today's fingerprint: written again when that changed
                banner = pages.banner(exp.name, state.made, expected)
                marked = (pages.replace_banner(text, banner, exp.name)
                          if pages.has_banner(text, exp.name)
                          else pages.with_banner(text, banner))
                if marked != text:
                    path.write_text(marked, encoding="utf-8")
                    print(f"{page}: marked stale ({exp.name}: the page {state.why()})")
                continue
            if pages.has_banner(text, exp.name):
                continue
            print(f"{page}: stale and not marked: {exp.name}'s learner fingerprint is "
                  f"{expected} today; the page {state.why()}. Make it again "
                  f"(ros_ws/reproduce.sh {exp.name}) or mark it (ros_ws/reproduce.sh "
                  "--mark-stale)")
            problems += 1
    return 1 if problems else 0


def listing(experiments: list[Experiment]) -> int:
    for exp in experiments:
        table = read_table(exp.references_path)
        try:
            expected = exp.fingerprint(table)
        except ReferencesOutdated:
            expected = "unknown (--references)"
        states = [f"{page} " + ("fresh" if pages.freshness(
            REPO / page, exp.name, expected, aliases_of(table, exp.name)).fresh else "stale")
                  for page in exp.pages]
        runs = exp.run_fingerprints()
        print(f"{exp.name}\t{exp.maker}\t{len(runs)} runs\tfingerprint {expected}\t"
              + "; ".join(states))
    return 0


def references(experiments: list[Experiment], parallel: int) -> int:
    """Make the reference runs today's code lacks; say, experiment by experiment, whether its
    runs do what they did. A page stamped by the sources of code whose runs these are (the
    stamp pages had before reference runs) is kept fresh by an alias."""
    by_folder: dict[Path, list[Experiment]] = {}
    for exp in experiments:
        by_folder.setdefault(exp.references_path, []).append(exp)
    for path, group in by_folder.items():
        table = read_table(path)
        before = {}
        for exp in group:
            try:  # what the table's code did
                before[exp.name] = exp.fingerprint(table, todays=False)
            except ReferencesOutdated:
                before[exp.name] = None
        made = make_references(group, table, parallel, say)
        aliases = {name: dict(found) for name, found in (made.get("aliases") or {}).items()}
        for exp in group:
            today = exp.fingerprint(made)
            was = before[exp.name]
            said = ("its runs do what they did" if was == today else
                    "its runs changed: its pages are stale" if was else "its runs are known")
            say(f"{exp.name}: {said} (fingerprint {today})")
            sources = exp.source_fingerprint()
            for page in exp.pages:
                stamp = pages.provenance_of((REPO / page).read_text(encoding="utf-8"),
                                            exp.name)
                if stamp is not None and stamp.fingerprint == sources:
                    aliases.setdefault(exp.name, {})[stamp.fingerprint] = today
        if aliases:
            made["aliases"] = aliases
        write_table(path, made)
        say(f"wrote {_shown(path)}")
    return 0


def pin(exp: Experiment) -> None:
    """Rewrite the experiment file's data hashes (the lines under 'data:') with today's."""
    from sgim_nodes.experiments.pinned import pin_of
    from sgim_nodes.provenance.fingerprint import data_files

    lines = exp.path.read_text(encoding="utf-8").splitlines(keepends=True)
    found = {name: pin_of(path) for name, path in data_files().items()}
    out, inside = [], False
    for line in lines:
        if line.startswith("data:"):
            inside = True
            out.append("data:\n")
            out += [f"  {name}: {digest}\n" for name, digest in sorted(found.items())]
            continue
        if inside and (line.startswith(" ") or not line.strip()):
            continue
        inside = False
        out.append(line)
    exp.path.write_text("".join(out), encoding="utf-8")
    say(f"{exp.path.name}: data pinned to today's files")


def reproduce(exp: Experiment, args: argparse.Namespace, command: str) -> int:
    from sgim_nodes.experiments.reports import maker
    from sgim_nodes.experiments.reports.graph_study import NotPinned

    problems = exp.data_problems()
    if problems:
        for problem in problems:
            say(f"{exp.path.name}: {problem}")
        say("the world's data files are not the ones the experiment pins: `--pin` pins "
            "today's files (a deliberate change of the experiment)")
        return 2
    runs_dir = args.runs_dir or exp.runs_dir
    began = time.monotonic()
    if args.ship:
        ship_runs(exp, runs_dir)
        return 0
    if args.verify is not None:
        return verify_runs(exp, args)
    if not args.report_only:
        say(f"{exp.name}: making its runs in {runs_dir} ({exp.maker})")
        code = make_runs(exp, runs_dir, args.parallel, args.address, args.keep_unlike,
                         () if args.ignore_shipped else shipped_already(exp))
        if code or args.runs_only:
            ship_runs(exp, runs_dir)  # what finished is kept, even when the rest failed
        if code:
            say(f"{exp.name}: some runs did not finish (exit {code}); run the same command to "
                "resume")
            return 1
    if args.runs_only:
        return 0
    say(f"{exp.name}: analysing {runs_dir}")
    try:
        report = maker(exp.report)(exp, runs_dir, FIGURES)
    except (NotPinned, FileNotFoundError) as missing:
        if not args.report_only:
            raise
        say(f"{exp.name}: nothing to report from: {str(missing).splitlines()[0]}. "
            f"`ros_ws/reproduce.sh {exp.name}` makes its {len(exp.run_fingerprints())} runs "
            "(resumable), then --report-only makes its pages again")
        return 2
    wall = time.monotonic() - began
    notes = [*report.notes, *([f"runs in `{_shown(runs_dir)}`"] if runs_dir.is_dir() else []),
             *shipped_note(exp, runs_dir)]
    outputs = [*exp.pages, _shown(FIGURES)]  # what this command writes is not a change
    made = Provenance.now(command, exp.name, current_fingerprint(exp, args.parallel),
                          environment(), wall, notes,
                          outputs=outputs)
    for page in exp.pages:
        blocks = dict(report.blocks.get(page, {}))
        blocks["provenance"] = made.markdown()
        pages.write_page(REPO / page, blocks, exp.name)
        say(f"{exp.name}: wrote {page}")
    for figure in report.figures:
        say(f"{exp.name}: drew {_shown(figure)}")
    if not args.report_only:
        ship_runs(exp, runs_dir)
    return 0


def verify_runs(exp: Experiment, args: argparse.Namespace) -> int:
    """0 when every run drawn is made again the same, 1 when one is not, 2 when the
    experiment ships no run of today's code."""
    import secrets

    from sgim_nodes.experiments.verify import verify

    if args.graph and exp.maker != "graph":
        say(f"{exp.name}: a {exp.maker} experiment makes no graph run: verify it without "
            "--graph")
        return 2
    seed = args.verify_seed if args.verify_seed is not None else secrets.randbelow(10**6)
    found = verify(exp, args.verify, seed, args.graph, say, movements=args.verify_movements)
    if not found:
        say(f"{exp.name}: no shipped run of today's code to verify: `ros_ws/reproduce.sh "
            f"{exp.name}` makes and ships them")
        return 2
    wrong = [v.name for v in found if not v.same]
    say(f"{exp.name}: {len(found) - len(wrong)} of {len(found)} runs made again the same"
        + (f"; differ: {', '.join(wrong)}" if wrong else ""))
    return 1 if wrong else 0


def shipped_note(exp: Experiment, runs_dir: Path) -> list[str]:
    """Where a runner or world experiment's results came from, when some came from the
    shipped files (a graph experiment's report says so itself)."""
    from sgim_nodes.experiments.shipped import file_jobs, results_folder

    if exp.maker == "graph":
        return []
    jobs, module = file_jobs(exp)
    taken = sum(not module.result_path(runs_dir, job).is_file() for job in jobs)
    return ([f"{taken} of {len(jobs)} results read from "
             f"`{_shown(results_folder(exp))}/`"] if taken else [])


def shipped_already(exp: Experiment) -> set[str]:
    """The runs the repository ships with today's behaviour: not made again."""
    from sgim_nodes.experiments.shipped import shipped_names

    names = shipped_names(exp)
    if names:
        say(f"{len(names)} run(s) shipped in experiments/shipped/ with today's behaviour: "
            "not made again (--ignore-shipped makes them)")
    return names


def ship_runs(exp: Experiment, runs_dir: Path) -> None:
    from sgim_nodes.experiments.shipped import SHIPPED, behaviours, ship_folder, ship_results

    if not behaviours(exp):
        say(f"{exp.name}: no run shipped: its reference runs are not today's code's "
            "(`ros_ws/reproduce.sh --references` makes them)")
        return
    written = (ship_folder if exp.maker == "graph" else ship_results)(exp, runs_dir)
    if written:
        say(f"{exp.name}: shipped {len(written)} run table(s) in {_shown(SHIPPED)} "
            f"({sum(p.stat().st_size for p in written) / 1e6:.1f} MB)")


def current_fingerprint(exp: Experiment, parallel: int) -> str:
    """The experiment's fingerprint, its reference runs made first if today's code lacks
    them (a page is stamped with what its runs do)."""
    try:
        return exp.fingerprint()
    except ReferencesOutdated:
        references([exp], parallel)
        return exp.fingerprint()


def _shown(path: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(REPO))
    except ValueError:
        return str(path)


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    command = "ros_ws/reproduce.sh " + " ".join(shlex.quote(a) for a in (
        argv if argv is not None else sys.argv[1:]))
    try:
        experiments = selected(args)
        if args.list:
            return listing(experiments)
        if args.references:
            return references(experiments, args.parallel)
        if args.check or args.mark_stale:
            return check(experiments, args.mark_stale)
        if args.pin:
            for exp in experiments:
                pin(exp)
            return 0
        code = 0
        for exp in experiments:
            code = max(code, reproduce(exp, args, command))
        return code
    except ExperimentError as error:
        print(f"reproduce: {error}", file=sys.stderr)
        return 2
    except pages.PageError as error:
        print(f"reproduce: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        say("interrupted: the runs made are kept; the same command resumes")
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
