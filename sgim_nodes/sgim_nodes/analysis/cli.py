"""`analyze STUDY_DIR`: a study's figures, results.md and results.json, from its bags alone.

Why one command: reproducing the paper's comparison must be a single step after the study,
and its numbers must exist both for people (markdown tables beside the figures) and for
scripts (the same numbers as JSON).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from dataclasses import asdict
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from sgim_nodes.analysis import figures
from sgim_nodes.analysis.export import write_csv
from sgim_nodes.analysis.floor import benchmark_floor
from sgim_nodes.analysis.pooling import Unlike, mixed_note, refusal, unlike_runs
from sgim_nodes.analysis.report import (
    PCT,
    StudyNumbers,
    num,
    render,
    study_numbers,
    table,
)
from sgim_nodes.analysis.statistics import (
    ALPHA,
    CONFIDENCE,
    Coverage,
    CoverageTest,
    Curve,
    FinalErrors,
    PairTest,
    demonstration_times,
)
from sgim_nodes.analysis.study import CACHE_NAME, Study, discover_runs, load_study
from sgim_ros.command_line import BriefParser
from sgim_ros.record_key import TRUST_ENV, UNKEYED
from sim_bridge.lake import ISOLATED_REGION

FRAME_FRACTIONS = (0.2, 0.5, 1.0)  # the paper's 1000, 2500 and 5000 of 5000 movements

DESCRIPTION = f"""\
Analyse a study (one folder per run: <learner>-seed<N>/ with bag/ and metadata.yaml) from its
bags alone, and write:
  error_curves.png  mean error on the benchmark goals per learner, 95 % band over seeds,
                    the floor dashed, the demonstrations as ticks along the bottom
  landings.png      where the hook landed: rows learners, columns movements 1..T
  landings_frames.png  the same per separate time frame: movements T(k-1)+1..T(k)
  region_tree.png   interest-coloured leaf regions of sgim-d and saggriac at the same times
  results.md        final errors (mean and 95 % interval, and how far above the benchmark's
                    floor: what a lookup on a dense map of the world achieves), pairwise
                    error along the way, pairwise tests (Welch's t and Mann-Whitney U),
                    isolated-region coverage with its pairwise tests (Fisher's exact test on
                    the runs reaching it, Mann-Whitney U on the share of own landings in it),
                    runs and durations: the blocks that the pages show (analysis/report.py)
  results.json      the same numbers
  evaluations.csv   with --csv: one row per run and evaluation, every setting a column
Each run is read once, every segment of it (bag/, bag.resume1/, ...), its records validated
as every reader validates them; its columns are cached as <run>/{CACHE_NAME} (rebuilt when a
segment changes). Damaged bags are reported and used as far as readable; unreadable runs are
skipped. Runs are pooled only with like runs: a learner's runs that differ in teacher, budget
or parameters are analysed as separate groups (a warning names what differs), and runs of
one group that share a seed stop the analysis unless --allow-repeated-seeds. Runs whose
learner fingerprints differ (code, world, data or library versions across the study, or
parameters within a group), runs resumed by another learner and runs made before
fingerprints stop it too (exit 2, naming what differs and which runs hold what) unless
--allow-mixed. Every table of tests is Holm-corrected over its p-values, with effect sizes
and 95 % intervals beside them and the smallest p each test can reach at its n."""


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = BriefParser(
        prog="analyze", description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example: analyze runs/study --times 1000 2500 5000")
    parser.add_argument("study_dir", type=Path, metavar="STUDY_DIR",
                        help="the study folder (run_study.sh --runs-dir), or one run folder")
    parser.add_argument("--out", type=Path, default=None,
                        help="where to write the figures and tables (default STUDY_DIR/analysis)")
    parser.add_argument("--times", type=int, nargs="+", default=None, metavar="N",
                        help="movement counts for the landing frames and the region-tree "
                             "snapshots (default 20%%, 50%% and 100%% of the run length)")
    parser.add_argument("--tree-seed", type=int, default=None, metavar="SEED",
                        help="seed whose region trees are drawn (default: the lowest)")
    parser.add_argument("--no-cache", action="store_true",
                        help="re-read every bag, ignoring and rewriting the caches")
    parser.add_argument("--allow-repeated-seeds", action="store_true",
                        help="pool runs of one group that share a seed (by default the "
                             "analysis refuses: they are not independent samples)")
    parser.add_argument("--allow-mixed", action="store_true",
                        help="pool runs whose learner fingerprints differ (another commit, "
                             "world or library version; resumed by another learner; made "
                             "before fingerprints): by default the analysis refuses, naming "
                             "what differs; with it, results.md says so at its top")
    parser.add_argument("--trust-unkeyed", action="store_true",
                        help="read runs whose movements are signed but whose record.key is "
                        "missing, without checking the signatures (results.md says so at its "
                        "top); without it such a run is skipped, naming the missing key")
    parser.add_argument("--csv", action="store_true",
                        help="also write evaluations.csv: one row per run and evaluation, "
                             "every setting of the run a column (for pandas and the like)")
    args = parser.parse_args(argv)
    if args.times is not None and any(t < 1 for t in args.times):
        parser.error("--times must be positive movement counts")
    return args


def default_times(study: Study) -> list[int]:
    length = max((r.total_movements for r in study.runs), default=0)
    return sorted({max(1, round(f * length)) for f in FRAME_FRACTIONS})


def _clean(value: object) -> object:
    """JSON-safe: numpy to Python, NaN and inf to None."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, np.generic):
        return _clean(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Path):
        return str(value)
    return value


def _curve_json(c: Curve) -> dict:
    return {"movements": c.movements, "mean": c.mean, "low": c.low, "high": c.high, "n": c.n}


def _final_json(f: FinalErrors) -> dict:
    return asdict(f) | {"mean": f.interval.mean, "low": f.interval.low, "high": f.interval.high,
                        "n": f.interval.n}


def _coverage_json(c: Coverage) -> dict:
    share = c.share
    return {"runs": len(c.runs), "runs_reached": c.runs_reached, "share_mean": share.mean,
            "share_low": share.low, "share_high": share.high,
            "first_movement_median": c.first_movement_median,
            "per_run": [asdict(r) | {"share": r.share} for r in c.runs]}


def _test_json(t: PairTest | CoverageTest) -> dict:
    return asdict(t) | {"applicable": t.applicable, "significant": t.significant}


def results_dict(study: Study, numbers: StudyNumbers, written: dict[str, str],
                 mixed: list[Unlike] | None = None) -> dict:
    n = numbers
    return _clean({
        "mixed": [{"what": u.what, "holders": dict(u.holders)} for u in mixed or []],
        "floor": asdict(n.floor) if n.floor else None,
        "study": shown_path(study.path), "generated": datetime.now(UTC).isoformat(),
        "confidence": CONFIDENCE, "alpha": ALPHA, "correction": "holm (per table)",
        "isolated_region": ISOLATED_REGION,
        "runs": {k: asdict(v) for k, v in n.summaries.items()}, "skipped": study.skipped,
        "warnings": study.warnings,
        "curves": {k: _curve_json(v) for k, v in n.curves.items()},
        "final_errors": {k: _final_json(v) for k, v in n.finals.items()},
        "tests": [_test_json(t) for t in n.tests],
        "isolated_coverage": {k: _coverage_json(v) for k, v in n.coverage.items()},
        "isolated_coverage_tests": [_test_json(t) for t in n.region_tests],
        "figures": written,
    })


def shown_path(path: Path) -> str:
    """The study's folder as the reports name it: relative to the working directory when it
    lies inside (reports committed to a repository then name no one's machine), else absolute."""
    full = path.resolve()
    try:
        return str(full.relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(full)


def results_markdown(study: Study, numbers: StudyNumbers, written: dict[str, str],
                     mixed: list[Unlike] | None = None, points: list[int] | None = None) -> str:
    """results.md: its tables are report.render's blocks, those the pages show."""
    blocks = render(numbers, points)
    out = [mixed_note(mixed), ""] if mixed else []
    unkeyed = [r.name for r in study.runs if any(UNKEYED in w for w in r.warnings)]
    if unkeyed:
        out += [f"**Runs {UNKEYED} (--trust-unkeyed): {', '.join(unkeyed)}. Their movements' "
                "signatures were not checked: a forged record would count as the "
                "simulator's.**", ""]
    out += [f"# Study results: {shown_path(study.path)}", "",
            "Generated by `analyze` from the bags alone. Intervals are two-sided "
            f"t intervals at {PCT} % over seeds (n/a with one run).", ""]
    out += ["## Runs", "", *table(
        ["learner", "runs", "finished", "seeds", "movements", "demonstrations per run",
         "total duration (s)", "mean duration (s)"],
        [[s.learner, str(s.runs), str(s.finished), ", ".join(map(str, s.seeds)),
          ", ".join(sorted(set(map(str, s.movements)), key=int)),
          ", ".join(map(str, s.demonstrations)),
          num(s.total_duration_s, 1), num(s.mean_duration_s, 1)]
         for s in numbers.summaries.values()])]
    if study.skipped:
        out += ["Skipped runs:", ""] + [f"- {k}: {v}" for k, v in study.skipped.items()] + [""]
    out += ["## Final error", "",
            "Mean distance to the benchmark goals at each run's last evaluation "
            "(outcome units; lower is better; the lowest mean in bold).", ""]
    if numbers.floor:
        out += ["Beside each learner, how far it is from what is possible: the "
                f"{numbers.floor.describe()}.", ""]
    out += [blocks["final-errors"], "", "Along the way (mean over seeds; the lowest of each "
            "column in bold):", "", blocks["error-curve"], ""]
    out += ["## Pairwise tests of final errors", "", blocks["pairwise"], ""]
    centre = ", ".join(f"{v:.3g}" for v in ISOLATED_REGION["centre"])
    out += ["## Isolated region coverage", "",
            f"Isolated region: centre ({centre}), radius {ISOLATED_REGION['radius']:.3g} "
            "(normalised outcome units). Share: the run's valid landings that fall in it "
            "(mean over runs, in %); 'own' excludes imitations and demonstrated actions.", "",
            blocks["isolated-coverage"], ""]
    if numbers.region_tests:
        out += ["Does one learner meet the isolated region more than another?", "",
                blocks["isolated-tests"], ""]
    out += ["## Figures", ""] + [f"- [{name}]({name})" for name in written.values()] + [""]
    if study.warnings:
        out += ["## Warnings", ""] + [f"- {w}" for w in study.warnings] + [""]
    return "\n".join(out)


def _progress_bar(total: int):
    try:
        from tqdm import tqdm
    except ImportError:  # progress is a comfort, not a requirement
        return None
    return tqdm(total=total, desc="[analyze] runs", unit="run", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    study_dir: Path = args.study_dir
    if args.trust_unkeyed:  # the readers take it from the environment (sgim_ros/record_key.py)
        os.environ[TRUST_ENV] = "1"
    if not study_dir.is_dir():
        print(f"analyze: {study_dir} is not a folder", file=sys.stderr)
        return 2
    found = discover_runs(study_dir)
    if not found:
        print(f"analyze: no run folders (<learner>-seed<N>/bag) in {study_dir}", file=sys.stderr)
        return 2
    print(f"[analyze] {len(found)} run folders in {study_dir}", file=sys.stderr)
    bar = _progress_bar(len(found))

    def warn(message: str) -> None:
        (bar.write if bar else print)(f"[analyze] warning: {message}", file=sys.stderr)

    def step(name: str) -> None:
        if bar:
            bar.set_postfix_str(name)
            bar.update()
        else:
            print(f"[analyze] loaded {name}", file=sys.stderr)

    study = load_study(study_dir, use_cache=not args.no_cache, warn=warn, progress=step)
    if bar:
        bar.close()
    if not study.runs:
        print(f"analyze: no usable run in {study_dir}", file=sys.stderr)
        return 1
    refused = False
    mixed = unlike_runs(study)
    if mixed and not args.allow_mixed:
        for line in refusal(study, mixed).splitlines():
            print(f"analyze: {line}", file=sys.stderr)
        refused = True
    if study.repeated_seeds and not args.allow_repeated_seeds:
        for group, names in study.repeated_seeds.items():
            print(f"analyze: '{group}' has runs with the same seed ({', '.join(names)}): "
                  "pooling them would count one sample twice. Remove the extra runs, or pass "
                  "--allow-repeated-seeds", file=sys.stderr)
        refused = True
    if refused:
        return 2
    for unlike in mixed:
        warn(f"pooled anyway (--allow-mixed): {unlike.describe()}")
    out: Path = args.out or study_dir / "analysis"
    out.mkdir(parents=True, exist_ok=True)
    times = sorted(set(args.times)) if args.times else default_times(study)
    print(f"[analyze] statistics over {len(study.runs)} runs of "
          f"{', '.join(study.learners)}; frames at movements {times}", file=sys.stderr)
    numbers = study_numbers(study, benchmark_floor())
    written: dict[str, str] = {}
    print("[analyze] drawing figures", file=sys.stderr)
    if numbers.curves:
        written["error_curves"] = figures.plot_error_curves(
            numbers.curves, out / "error_curves.png",
            numbers.floor.mean if numbers.floor else None, demonstration_times(study)).name
    written["landings"] = figures.plot_landings(study, times, out / "landings.png").name
    written["landings_frames"] = figures.plot_landings(
        study, times, out / "landings_frames.png", cumulative=False).name
    tree = figures.plot_region_trees(study, times, out / "region_tree.png", args.tree_seed)
    if tree is not None:
        written["region_tree"] = tree.name
    (out / "results.md").write_text(results_markdown(study, numbers, written, mixed),
                                    encoding="utf-8")
    (out / "results.json").write_text(json.dumps(
        results_dict(study, numbers, written, mixed), indent=1), encoding="utf-8")
    tables = ["results.md", "results.json"]
    if args.csv:
        tables.append(write_csv(study, out / "evaluations.csv").name)
    print(f"Wrote {', '.join([*written.values(), *tables])} to {out}")
    if study.skipped:
        print(f"Skipped {len(study.skipped)} run(s): {', '.join(study.skipped)} "
              "(see results.md, Warnings)")
    return 0


def main(argv: list[str] | None = None) -> int:
    return run(parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
