"""Read and write landmark streams in the LASER dataset's CSV format.

The format (see ../shared/datasets/laser-uav-gesture/README.md) has one row per landmark:
`,counter_frame,i,x,y,z,visibility`, the first column a running row index, 33 rows
(i = 0..32) per frame, `counter_frame` 1-based and increasing, with gaps where no person
was detected. Stitched streams written by the project use the same columns (extra
columns are allowed and ignored).

Reading is strict because a replayed stream drives the same recognition as a camera: a
malformed file raises `LandmarkCsvError` naming the file, the line and the problem.
"""

from __future__ import annotations

import csv
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from proxima.ingest.base import SourceError
from proxima.types import NUM_LANDMARKS

REQUIRED_COLUMNS: tuple[str, ...] = ("counter_frame", "i", "x", "y", "z", "visibility")
_VIS_TOLERANCE = 1e-6


class LandmarkCsvError(SourceError, ValueError):
    """A landmark CSV is malformed; the message is `FILE:LINE: problem`."""

    def __init__(self, path: Path | str, line: int | None, problem: str) -> None:
        where = f"{path}:{line}" if line is not None else str(path)
        super().__init__(f"{where}: {problem}")
        self.path = str(path)
        self.line = line
        self.problem = problem


@dataclass(frozen=True, eq=False)
class LandmarkTrack:
    """A whole landmark stream: `frames` (F,) the 1-based counter_frame of each frame,
    `xyz` (F, 33, 3) and `visibility` (F, 33), landmarks in MediaPipe index order."""

    path: str
    frames: np.ndarray
    xyz: np.ndarray
    visibility: np.ndarray

    def __len__(self) -> int:
        return int(self.frames.shape[0])


def _header_columns(path: Path, header: list[str]) -> list[int]:
    names = [h.strip() for h in header]
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        raise LandmarkCsvError(
            path,
            1,
            f"header lacks column(s) {', '.join(missing)}; expected the LASER landmark "
            f"format ',counter_frame,i,x,y,z,visibility', got {','.join(names)!r}",
        )
    return [names.index(c) for c in REQUIRED_COLUMNS]


def _locate_parse_error(path: Path, cols: list[int], width: int) -> None:
    """Walk the file row by row and raise at the first row that does not parse."""
    with path.open(newline="") as fh:
        reader = csv.reader(fh)
        next(reader)
        for line_no, row in enumerate(reader, start=2):
            if len(row) != width:
                raise LandmarkCsvError(
                    path, line_no, f"expected {width} fields like the header, got {len(row)}"
                )
            for name, col in zip(REQUIRED_COLUMNS, cols, strict=True):
                text = row[col].strip()
                try:
                    value = float(text)
                except ValueError:
                    raise LandmarkCsvError(
                        path, line_no, f"{name} is not a number: {text!r}"
                    ) from None
                if not math.isfinite(value):
                    raise LandmarkCsvError(path, line_no, f"{name} is not finite: {text!r}")


def _check_structure(path: Path, cf: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Check frame numbering and landmark indices; return each frame's first row."""

    def line(row: int) -> int:
        return int(row) + 2  # header is line 1, first data row line 2

    bad = np.flatnonzero((cf != np.round(cf)) | (cf < 1))
    if bad.size:
        r = bad[0]
        raise LandmarkCsvError(path, line(r), f"counter_frame must be an integer >= 1: {cf[r]}")
    bad = np.flatnonzero((idx != np.round(idx)) | (idx < 0) | (idx >= NUM_LANDMARKS))
    if bad.size:
        r = bad[0]
        raise LandmarkCsvError(path, line(r), f"landmark index i must be 0..32: {idx[r]}")
    back = np.flatnonzero(np.diff(cf) < 0)
    if back.size:
        r = back[0] + 1
        raise LandmarkCsvError(
            path,
            line(r),
            f"counter_frame {int(cf[r])} after {int(cf[r - 1])}: frames must be in "
            "increasing order, each frame's rows together",
        )
    starts = np.concatenate([[0], np.flatnonzero(np.diff(cf) > 0) + 1])
    sizes = np.diff(np.concatenate([starts, [cf.size]]))
    wrong = np.flatnonzero(sizes != NUM_LANDMARKS)
    if wrong.size:
        g = wrong[0]
        rows = idx[starts[g] : starts[g] + sizes[g]].astype(int)
        missing = sorted(set(range(NUM_LANDMARKS)) - set(rows.tolist()))
        raise LandmarkCsvError(
            path,
            line(starts[g]),
            f"frame counter_frame={int(cf[starts[g]])} has {sizes[g]} rows, needs 33"
            + (f" (missing i={missing})" if missing else ""),
        )
    per_frame = np.sort(idx.reshape(-1, NUM_LANDMARKS), axis=1)
    dup = np.flatnonzero((per_frame != np.arange(NUM_LANDMARKS)).any(axis=1))
    if dup.size:
        g = dup[0]
        raise LandmarkCsvError(
            path,
            line(starts[g]),
            f"frame counter_frame={int(cf[starts[g]])} repeats a landmark index "
            "(each of i=0..32 must appear once)",
        )
    return starts


def read_landmark_csv(path: str | Path) -> LandmarkTrack:
    """Load and validate a landmark CSV.

    Raises:
        LandmarkCsvError: the file is missing, empty or not in the landmark format; the
            message names the file, the line and the problem.
    """
    path = Path(path)
    try:
        with path.open(newline="") as fh:
            header = next(csv.reader(fh), None)
    except FileNotFoundError:
        raise LandmarkCsvError(path, None, "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise LandmarkCsvError(path, None, f"cannot read as text: {exc}") from None
    if header is None:
        raise LandmarkCsvError(path, None, "empty file (no header, no landmark rows)")
    cols = _header_columns(path, header)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=cols, ndmin=2, dtype=float)
        if data.shape[0] and not np.isfinite(data).all():
            raise ValueError("non-finite value")
    except ValueError as exc:
        _locate_parse_error(path, cols, len(header))
        raise LandmarkCsvError(path, None, f"cannot parse: {exc}") from None
    if data.shape[0] == 0:
        raise LandmarkCsvError(path, 2, "no landmark rows after the header")
    cf, idx = data[:, 0], data[:, 1]
    _check_structure(path, cf, idx)
    vis = data[:, 5]
    bad = np.flatnonzero((vis < -_VIS_TOLERANCE) | (vis > 1 + _VIS_TOLERANCE))
    if bad.size:
        r = bad[0]
        raise LandmarkCsvError(path, int(r) + 2, f"visibility must be in [0, 1]: {vis[r]}")
    n_frames = cf.size // NUM_LANDMARKS
    order = np.argsort(idx.reshape(n_frames, NUM_LANDMARKS), axis=1, kind="stable")
    rows = (order + np.arange(n_frames)[:, None] * NUM_LANDMARKS).reshape(-1)
    xyz = data[rows, 2:5].reshape(n_frames, NUM_LANDMARKS, 3).astype(np.float32)
    visibility = np.clip(vis[rows], 0.0, 1.0).reshape(n_frames, NUM_LANDMARKS)
    frames = cf[::NUM_LANDMARKS].astype(np.int64)
    return LandmarkTrack(str(path), frames, xyz, visibility.astype(np.float32))


def write_landmark_csv(
    path: str | Path, frames: np.ndarray, xyz: np.ndarray, visibility: np.ndarray
) -> None:
    """Write a landmark stream in the LASER format (e.g. clips stitched into one stream).

    `frames` (F,) are 1-based, strictly increasing counter_frame values; `xyz` is
    (F, 33, 3), `visibility` (F, 33). The file is written whole to a temporary name and
    then renamed, so a reader never sees half of it.

    Raises:
        ValueError: shapes disagree or frames do not strictly increase from 1.
    """
    frames = np.asarray(frames, dtype=np.int64)
    xyz = np.asarray(xyz, dtype=np.float64)
    visibility = np.asarray(visibility, dtype=np.float64)
    n = frames.shape[0]
    if xyz.shape != (n, NUM_LANDMARKS, 3) or visibility.shape != (n, NUM_LANDMARKS):
        raise ValueError(
            f"need frames (F,), xyz (F,33,3), visibility (F,33); got {frames.shape}, "
            f"{xyz.shape}, {visibility.shape}"
        )
    if n and (frames[0] < 1 or (np.diff(frames) <= 0).any()):
        raise ValueError("frames must be >= 1 and strictly increasing")
    path = Path(path)
    tmp = path.with_name(path.name + ".part")
    table = np.empty((n * NUM_LANDMARKS, 7))
    table[:, 0] = np.arange(n * NUM_LANDMARKS)
    table[:, 1] = np.repeat(frames, NUM_LANDMARKS)
    table[:, 2] = np.tile(np.arange(NUM_LANDMARKS), n)
    table[:, 3:6] = xyz.reshape(-1, 3)
    table[:, 6] = visibility.reshape(-1)
    fmt = ["%d", "%d", "%d", "%.9g", "%.9g", "%.9g", "%.9g"]
    np.savetxt(
        tmp, table, delimiter=",", fmt=fmt, header=",counter_frame,i,x,y,z,visibility", comments=""
    )
    tmp.replace(path)
