"""A run folder's recordings, read as one history, whatever tool asks.

run_experiment.sh leaves `runs/<run>/` with the first recording in `bag/` and one more per
resumption (`bag.resume1/`, `bag.resume2/`, ...), beside params.yaml and metadata.yaml. A tool
given the folder must read every segment, in order, with one validator carrying the run's
count from one segment to the next (bag/validation.py), and a tool given something that is
neither a bag nor a run folder must say what it found instead.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

from sgim_nodes.bag.reader import NotABagError, limits_for, load_run
from sgim_nodes.bag.record_checks import Limits
from sgim_nodes.bag.records import RunRecords
from sgim_nodes.bag.validation import RunValidator

FIRST_SEGMENT = "bag"
_RESUMED = re.compile(r"^bag\.resume(\d+)$")


def segments(run_dir: str | Path) -> list[Path]:
    """The run's recordings in the order they were made."""
    run_dir = Path(run_dir)
    later = sorted(((int(m.group(1)), p) for p in run_dir.iterdir()
                    if (m := _RESUMED.match(p.name)) and p.is_dir()), key=lambda t: t[0])
    first = run_dir / FIRST_SEGMENT
    return ([first] if first.is_dir() else []) + [p for _, p in later]


def next_segment(run_dir: str | Path) -> Path:
    run_dir = Path(run_dir)
    if not (run_dir / FIRST_SEGMENT).exists():
        return run_dir / FIRST_SEGMENT
    return run_dir / f"bag.resume{len(segments(run_dir))}"


def is_run_folder(path: str | Path) -> bool:
    """A folder holding bag/ (or bag.resumeN/), as run_experiment.sh makes them."""
    path = Path(path)
    return path.is_dir() and bool(segments(path))


def load_run_folder(run_dir: str | Path, limit: int = 0, limits: Limits | None = None,
                    topics: Iterable[str] | None = None) -> RunRecords:
    """Every valid record of a run across its recordings (the first `limit` ones if > 0: a
    resumed graph reads only those made before its own), as one RunRecords."""
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise NotABagError(f"{run_dir} is not a folder")
    parts = segments(run_dir)
    if limit > 0:
        parts = parts[:limit]
    if not parts:
        raise NotABagError(f"{run_dir}: no recording ('{FIRST_SEGMENT}/') in this folder")
    validator = RunValidator(limits or limits_for(parts[0]))
    merged = RunRecords()
    for part in parts:
        load_run(part, topics, validator=validator, into=merged)
    return merged


def load_records(path: str | Path) -> tuple[RunRecords, list[Path]]:
    """The records of a bag, a storage file or a whole run folder, and the recordings read.

    NotABagError says what the path is when it is none of those."""
    path = Path(path)
    if is_run_folder(path):
        return load_run_folder(path), segments(path)
    return load_run(path), [path]


QUARANTINE_SUFFIX = ".quarantine.yaml"  # what the recorder writes beside each segment


def quarantine_summary(run_dir: str | Path) -> dict:
    """The recorders' reports of a run, summed over its segments, for metadata.yaml:
    {"total": n, "by_topic": {topic: {kind: n}}, "write_errors": {segment: why}}, plus
    "unreported": the segments whose recorder left no report (killed before its first)."""
    import yaml

    total, by_topic, errors, unreported = 0, {}, {}, []
    for segment in segments(run_dir):
        report_file = segment.with_name(segment.name + QUARANTINE_SUFFIX)
        try:
            report = yaml.safe_load(report_file.read_text(encoding="utf-8")) or {}
        except (OSError, yaml.YAMLError):
            unreported.append(segment.name)
            continue
        total += int(report.get("total_quarantined", 0) or 0)
        for topic, kinds in (report.get("quarantined") or {}).items():
            for kind, n in kinds.items():
                by_topic.setdefault(topic, {})
                by_topic[topic][kind] = by_topic[topic].get(kind, 0) + int(n)
        if report.get("write_error"):
            errors[segment.name] = report["write_error"]
    summary: dict = {"total": total, "by_topic": by_topic, "write_errors": errors}
    if unreported:
        summary["unreported"] = unreported
    return summary
