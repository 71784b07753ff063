"""Loader for the LASER UAV gesture data set (MediaPipe 33 landmarks, three views).

Files are `DJI_<clip>_<gesture>_<view>.MP4.csv` with columns
`,counter_frame,i,x,y,z,visibility`, one row per landmark, 33 rows per frame.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from proxima.gesture.clip import Clip, DataError
from proxima.types import GESTURES, NUM_LANDMARKS

COLUMNS = ("", "counter_frame", "i", "x", "y", "z", "visibility")
_NAME = re.compile(r"^(?P<clip>DJI_\d+)_(?P<gesture>[a-z_]+?)_(?P<view>[frl])\.MP4\.csv$")


def parse_name(path: Path) -> tuple[str, str, str]:
    """(clip id, gesture, view) from a LASER file name.

    Raises:
        DataError: the name does not follow the pattern or names an unknown gesture.
    """
    m = _NAME.match(path.name)
    if not m:
        raise DataError(f"{path}: file name does not match DJI_<n>_<gesture>_<f|l|r>.MP4.csv")
    if m["gesture"] not in GESTURES:
        raise DataError(f"{path}: unknown gesture {m['gesture']!r} in the file name")
    return m["clip"], m["gesture"], m["view"]


def _read_rows(path: Path) -> np.ndarray:
    """All data rows as a float array (N, 7), or a DataError naming the bad line."""
    with path.open(newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise DataError(f"{path}:1: empty file")
        header = [h.strip() for h in header]
        missing = [c for c in COLUMNS[1:] if c not in header]
        if missing:
            raise DataError(f"{path}:1: missing column(s) {', '.join(missing)}")
        cols = [header.index(c) for c in COLUMNS[1:]]
        rows: list[list[float]] = []
        for lineno, row in enumerate(reader, start=2):
            if not row:
                continue
            try:
                rows.append([float(row[c]) for c in cols])
            except IndexError:
                raise DataError(f"{path}:{lineno}: expected {len(header)} fields") from None
            except ValueError:
                for name, c in zip(COLUMNS[1:], cols, strict=True):
                    if not _is_float(row[c]):
                        raise DataError(
                            f"{path}:{lineno}: column {name!r} is not a number: {row[c]!r}"
                        ) from None
                raise
    if not rows:
        raise DataError(f"{path}:2: no data rows")
    return np.asarray(rows, dtype=np.float64)


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def load_laser_csv(path: str | Path) -> Clip:
    """Load one LASER CSV file.

    Raises:
        DataError: bad file name, missing column, non-numeric value, a frame without
            exactly 33 landmarks, a landmark index outside 0..32; the message gives the
            file and line.
    """
    path = Path(path)
    _, gesture, view = parse_name(path)
    rows = _read_rows(path)
    if not np.all(np.isfinite(rows)):
        r = int(np.argwhere(~np.isfinite(rows))[0][0])
        raise DataError(f"{path}:{r + 2}: non-finite value")
    counter = rows[:, 0].astype(np.int64)
    idx = rows[:, 1].astype(np.int64)
    bad_idx = np.flatnonzero((idx < 0) | (idx >= NUM_LANDMARKS))
    if bad_idx.size:
        r = int(bad_idx[0])
        raise DataError(f"{path}:{r + 2}: landmark index {idx[r]} outside 0..32")
    # Rows come grouped by frame; split where counter_frame changes.
    starts = np.flatnonzero(np.r_[True, counter[1:] != counter[:-1]])
    sizes = np.diff(np.r_[starts, len(counter)])
    wrong = np.flatnonzero(sizes != NUM_LANDMARKS)
    if wrong.size:
        s = int(starts[wrong[0]])
        raise DataError(
            f"{path}:{s + 2}: frame {counter[s]} has {sizes[wrong[0]]} landmarks, expected 33"
        )
    frames = counter[starts]
    if np.any(np.diff(frames) <= 0):
        r = int(starts[np.flatnonzero(np.diff(frames) <= 0)[0] + 1])
        raise DataError(f"{path}:{r + 2}: counter_frame {counter[r]} is out of order")
    block = rows.reshape(len(frames), NUM_LANDMARKS, -1)
    order = np.argsort(block[:, :, 1], axis=1)  # landmark index order within each frame
    block = np.take_along_axis(block, order[:, :, None], axis=1)
    dup = np.flatnonzero(np.any(np.diff(block[:, :, 1], axis=1) == 0, axis=1))
    if dup.size:
        s = int(starts[dup[0]])
        raise DataError(f"{path}:{s + 2}: frame {frames[dup[0]]} repeats a landmark index")
    return Clip(
        name=path.name.removesuffix(".MP4.csv"),
        gesture=gesture,
        view=view,
        subject="laser",
        source="laser",
        frames=frames,
        xyz=block[:, :, 2:5].astype(np.float32),
        visibility=block[:, :, 5].astype(np.float32),
    )


def load_laser_dir(path: str | Path) -> list[Clip]:
    """Every `*.MP4.csv` clip in a folder, sorted by name.

    Raises:
        DataError: the folder has no LASER CSV, or one of them is bad.
    """
    path = Path(path)
    files = sorted(path.glob("*.MP4.csv"))
    if not files:
        raise DataError(f"{path}: no LASER CSV files (DJI_*_<gesture>_<view>.MP4.csv)")
    return [load_laser_csv(f) for f in files]
