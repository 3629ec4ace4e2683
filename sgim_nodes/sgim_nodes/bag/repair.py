"""Make a killed recording a complete bag again, so that any viewer opens it.

A recorder killed mid-run (bag.writer) leaves an MCAP file without summary and no
metadata.yaml: this project's readers read it up to its last complete chunk, but Foxglove,
`rosbags` and `ros2 bag` want a complete file. `repair` rewrites the readable messages into a
complete file of the same name (its embedded metadata names it right), writes metadata.yaml,
and keeps the original beside it as `<file>.truncated`: nothing is lost.

CLI: python -m sgim_nodes.bag.repair BAG_OR_RUN_FOLDER   (a run folder: every segment)
"""

from __future__ import annotations

import shutil
import sys
import warnings
from pathlib import Path

from rosbags.rosbag2 import Reader

from sgim_nodes.bag.mcap_recovery import RecoveryError, recover
from sgim_nodes.bag.reader import NotABagError, storage_files
from sgim_nodes.bag.run_folder import is_run_folder, segments
from sgim_nodes.bag.types import typestore
from sgim_nodes.bag.writer import BagWriter
from sgim_ros.command_line import BriefParser

TRUNCATED_SUFFIX = ".truncated"


def _complete(file: Path) -> bool:
    try:
        reader = Reader(file)
        reader.open()
    except Exception:
        return False
    reader.close()
    return True


def repair(bag: str | Path) -> str:
    """Repair one bag directory if it needs it; what was done, in one line."""
    bag = Path(bag)
    files = [f for f in storage_files(bag) if f.suffix == ".mcap" and f.parent == bag]
    broken = [f for f in files if not _complete(f)]
    if not broken and (bag / "metadata.yaml").exists():
        return f"{bag}: complete, nothing to do"
    if len(files) != 1:
        return (f"{bag}: {len(files)} MCAP files ({len(broken)} not closed): only a bag of one "
                "file (this project's recorder) is repaired; the readers still read the rest")
    file = files[0]
    work = bag.parent / f".{bag.name}.repair"
    shutil.rmtree(work, ignore_errors=True)
    out = BagWriter(work / bag.name, chunk_seconds=3600, chunk_messages=10**9)
    store = typestore()
    damage: list[str] = []
    count = 0
    try:
        for m in recover(file, on_gap=damage.append):
            if m.topic not in out._connections:  # the recorded definition, as recorded
                out._connections[m.topic] = out._writer.add_connection(
                    m.topic, m.msgtype, msgdef=m.msgdef, rihs01=store.hash_rihs01(m.msgtype))
            out.write(m.topic, m.timestamp_ns, m.data)
            count += 1
    except (RecoveryError, KeyError) as error:
        out.abort()
        shutil.rmtree(work, ignore_errors=True)
        raise NotABagError(f"{file}: cannot be repaired: {error}") from None
    out.close()
    file.replace(file.with_name(file.name + TRUNCATED_SUFFIX))
    (work / bag.name / file.name).replace(file)
    (work / bag.name / "metadata.yaml").replace(bag / "metadata.yaml")
    shutil.rmtree(work, ignore_errors=True)
    skipped = f", {len(damage)} damaged record(s) skipped" if damage else ""
    return (f"{bag}: rewrote {count} messages into a complete {file.name}{skipped}; the "
            f"original is kept as {file.name}{TRUNCATED_SUFFIX}")


def main(argv: list[str] | None = None) -> int:
    parser = BriefParser(
        prog="repair", description="Rewrite a recording whose recorder was killed as a "
        "complete bag (the original file is kept as .truncated).")
    parser.add_argument("path", type=Path, help="a bag directory, or a run folder (every "
                        "segment: bag/, bag.resume1/, ...)")
    args = parser.parse_args(argv)
    bags = segments(args.path) if is_run_folder(args.path) else [args.path]
    code = 0
    for bag in bags:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                print(repair(bag))
        except NotABagError as error:
            print(f"repair: {error}", file=sys.stderr)
            code = 2
    return code


if __name__ == "__main__":
    raise SystemExit(main())
