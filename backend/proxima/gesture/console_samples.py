"""The console's kept samples as a data source: `--data samples:PATH/TO/console.db` loads
every kept, labelled sample of the console's database as a clip, for `proxima train` and
`proxima evaluate` as for any other data set.

A sample becomes a clip of source `console`: gesture = the label its review gave it,
subject = the drone it was recorded for, view = the stream (camera) it came from. Its
rows are consecutive poses of the stream; their frame numbers come from the stream
times on a 30 fps clock, so a stretch without a person shows as a gap as in the data sets.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.clip import Clip, DataError

SAMPLES_PREFIX = "samples:"
SOURCE = "console"
CONSOLE_FPS = 30.0  # the frame clock sample times are numbered on (windows.SOURCE_FPS)


def frame_numbers(times: np.ndarray, fps: float = CONSOLE_FPS) -> np.ndarray:
    """1-based frame numbers of rows recorded at stream times `times` (seconds): the
    nearest frame of an `fps` clock, strictly increasing (a faster stream's rows get the
    next free number rather than a repeated one)."""
    t = np.asarray(times, np.float64)
    if len(t) == 0:
        return np.zeros(0, np.int64)
    r = np.rint((t - t[0]) * fps).astype(np.int64)
    i = np.arange(len(r))
    return np.maximum.accumulate(r - i) + i + 1


def row_clip(row: Any, label: str) -> Clip:
    """`sample_clip` of a stored `Sample` row (its own copy of the arrays), as `label`."""
    arr = row.arrays()
    return sample_clip(row.id, stream=row.stream, drone=row.drone, label=label,
                       xyz=arr.xyz.copy(), visibility=arr.visibility.copy(),
                       times=arr.times.copy())  # fmt: skip


def sample_clip(
    sample_id: int,
    *,
    stream: str,
    drone: str,
    label: str,
    xyz: np.ndarray,
    visibility: np.ndarray,
    times: np.ndarray,
) -> Clip:
    """One console sample as a clip (see the module's docstring)."""
    return Clip(
        name=f"console-{sample_id}-{stream}-{label}",
        gesture=label,
        view=stream,
        subject=drone,
        source=SOURCE,
        frames=frame_numbers(times),
        xyz=np.asarray(xyz, np.float32),
        visibility=np.asarray(visibility, np.float32),
    )


def resolve_samples_db(spec: str) -> Path:
    """The database file of a `samples:PATH` spec.

    Raises:
        DataError: no such file.
    """
    path = Path(spec.removeprefix(SAMPLES_PREFIX)).expanduser()
    if not path.is_file():
        raise DataError(f"{path}: no console database (samples:PATH names the console's .db file)")
    return path


def load_console_samples(db_path: str | Path, drone: str | None = None) -> list[Clip]:
    """Every kept, labelled sample in the console database at `db_path` (of one drone if
    given), oldest first, as clips. The database is only read (never migrated).

    Raises:
        DataError: not a console database, or one with no kept samples.
    """
    from sqlalchemy import create_engine, select
    from sqlalchemy.exc import SQLAlchemyError
    from sqlalchemy.orm import Session

    from proxima.store.samples import Sample, SampleStatus

    path = Path(db_path)
    engine = create_engine(f"sqlite:///{path.resolve()}")
    q = select(Sample).where(Sample.status == str(SampleStatus.KEPT)).order_by(Sample.id)
    if drone is not None:
        q = q.where(Sample.drone == drone)
    clips: list[Clip] = []
    try:
        with Session(engine) as db:
            for row in db.scalars(q):
                if not row.label:
                    continue
                clips.append(row_clip(row, row.label))
    except SQLAlchemyError as exc:
        raise DataError(f"{path}: not a console database with samples ({exc})") from None
    finally:
        engine.dispose()
    if not clips:
        which = f" of drone {drone!r}" if drone else ""
        raise DataError(f"{path}: no kept samples{which} (keep some on the Labelling page)")
    return clips
