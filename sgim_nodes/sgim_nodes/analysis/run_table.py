"""One run as one compressed file of columns: what the pages need, without its bag.

Why: a run's bag is large and costs a run's compute to make again, but the pages only
read a few columns of it (study.RunData). A run table holds exactly those columns, its
metadata and a stamp saying which behaviour made it (experiments/shipped.py), so that a
page can be made again, byte for byte, from the tables the repository ships.

Of the region maps (one per change of the tree), a table keeps the tree at each evaluation
(the map ``RunData.region_map_at`` gives for it) and the last: the region-tree figures show
the tree at evaluation counts, and the other maps are a large share of a run's bytes.

The file is a NumPy ``.npz`` (a zip of ``.npy`` arrays, read by ``numpy.load``): every column
under its RunData name, plus ``metadata`` and ``stamp`` as JSON text and ``notes`` (what the
bag's reader warned about). It is written byte for byte the same for the same run (fixed zip
dates, sorted names), so shipping a run again changes no file.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from sgim_nodes.analysis.study import RunData

FORMAT = 1
"""The layout's version: a table of another version is refused, never misread."""
_IDENTITY = ("name", "learner", "seed")
_SCALARS = ("budget", "final_state")
_NOT_COLUMNS = {"path", "metadata", "warnings", "group", *_IDENTITY, *_SCALARS}
COLUMNS = tuple(f.name for f in dataclasses.fields(RunData) if f.name not in _NOT_COLUMNS)
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


class RunTableError(ValueError):
    """A run table that is not one this code writes (another format, a missing column)."""


def _text(value: Any) -> np.ndarray:
    return np.array(json.dumps(value, sort_keys=True, ensure_ascii=False))


def maps_at_evaluations(run: RunData) -> dict[str, np.ndarray]:
    """The run's region-map columns, cut to the maps region_map_at picks for each evaluation
    count, and the last map. For those counts it then picks the same map: the one picked is
    the closest of all maps, so it is the closest of the kept ones, and a kept map as close
    and later would have been picked instead."""
    if not len(run.map_index):
        return {}
    last = len(run.map_index) - 1
    kept = sorted({last, *(int(np.searchsorted(run.map_index, run.region_map_at(int(t))[0]))
                           for t in run.eval_index)})
    offsets = run.map_offsets
    rows = np.concatenate([np.arange(offsets[k], offsets[k + 1]) for k in kept]).astype(np.int64)
    sizes = np.array([offsets[k + 1] - offsets[k] for k in kept], dtype=np.int64)
    return {"map_index": run.map_index[kept],
            "map_offsets": np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
            "leaf_lower": run.leaf_lower[rows], "leaf_upper": run.leaf_upper[rows],
            "leaf_interest": run.leaf_interest[rows]}


def save_run(run: RunData, path: Path, stamp: Mapping[str, Any]) -> Path:
    """Write `run` to `path` (atomically), with `stamp` (what made it) beside its columns."""
    arrays = {name: np.asarray(getattr(run, name)) for name in COLUMNS}
    arrays.update(maps_at_evaluations(run))
    arrays.update({name: np.array(getattr(run, name)) for name in _SCALARS})
    arrays.update(format=np.array(FORMAT), name=np.array(run.name),
                  learner=np.array(run.learner), seed=np.array(run.seed),
                  metadata=_text(run.metadata), stamp=_text(dict(stamp)),
                  notes=np.array(run.warnings, dtype=str))
    return write_arrays(path, arrays)


def write_arrays(path: Path, arrays: Mapping[str, np.ndarray]) -> Path:
    """An ``.npz`` of `arrays`, written atomically and byte for byte the same for the same
    arrays (sorted names, fixed zip dates): shipping the same data again changes no file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            for name in sorted(arrays):
                buffer = io.BytesIO()
                np.lib.format.write_array(buffer, np.asarray(arrays[name]), allow_pickle=False)
                info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_DATE)
                info.compress_type = zipfile.ZIP_DEFLATED
                archive.writestr(info, buffer.getvalue(), compresslevel=9)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def read_stamp(path: Path) -> dict[str, Any]:
    """What made the run of this table, without reading its columns."""
    with np.load(path, allow_pickle=False) as data:
        _check_format(path, data)
        return json.loads(str(data["stamp"]))


def load_run(path: Path) -> RunData:
    """The run of a table, as the analysis reads a run folder; its path is the table's."""
    path = Path(path)
    with np.load(path, allow_pickle=False) as data:
        _check_format(path, data)
        missing = [name for name in (*COLUMNS, *_SCALARS, *_IDENTITY) if name not in data.files]
        if missing:
            raise RunTableError(f"{path}: no column {', '.join(missing)}")
        return RunData(name=str(data["name"]), path=path, learner=str(data["learner"]),
                       seed=int(data["seed"]), metadata=json.loads(str(data["metadata"])),
                       warnings=[str(n) for n in data["notes"]],
                       **{name: data[name] for name in COLUMNS},
                       **{name: int(data[name]) for name in _SCALARS})


def _check_format(path: Path, data: Any) -> None:
    found = int(data["format"]) if "format" in data.files else None
    if found != FORMAT:
        raise RunTableError(f"{path}: a run table of format {found}, this code reads "
                            f"format {FORMAT}")
