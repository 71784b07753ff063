"""Recorded gesture samples: landmark sequences labelled in the console.

A sample is N consecutive poses of one stream, recorded for the drone that camera
belongs to. It starts `pending` (recorded, not yet reviewed), and the supervisor keeps it
(with a gesture label) or deletes it. Deleted samples stay in the table, marked, so a
mistaken delete can be undone and counts stay honest; only kept ones join that drone's
local data for the next federated run (`kept_samples`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from sqlalchemy import Float, Integer, LargeBinary, String, select
from sqlalchemy.orm import Mapped, Session, mapped_column

from proxima.store.base import Base
from proxima.types import GESTURES, NUM_LANDMARKS


class SampleStatus(StrEnum):
    PENDING = "pending"
    KEPT = "kept"
    DELETED = "deleted"


class Sample(Base):
    __tablename__ = "samples"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    created_at: Mapped[float] = mapped_column(Float, nullable=False)
    stream: Mapped[str] = mapped_column(String(64), nullable=False)
    drone: Mapped[str] = mapped_column(String(64), nullable=False, index=True)
    label: Mapped[str | None] = mapped_column(String(32), nullable=True)
    status: Mapped[str] = mapped_column(String(16), nullable=False, index=True)
    n_frames: Mapped[int] = mapped_column(Integer, nullable=False)
    t_start: Mapped[float] = mapped_column(Float, nullable=False)  # stream time
    t_end: Mapped[float] = mapped_column(Float, nullable=False)
    xyz: Mapped[bytes] = mapped_column(LargeBinary, nullable=False)  # float32 (N, 33, 3)
    visibility: Mapped[bytes] = mapped_column(LargeBinary, nullable=False)  # float32 (N, 33)
    times: Mapped[bytes] = mapped_column(LargeBinary, nullable=False)  # float64 (N,)
    created_by: Mapped[str] = mapped_column(String(64), nullable=False, default="")
    reviewed_by: Mapped[str | None] = mapped_column(String(64), nullable=True)
    reviewed_at: Mapped[float | None] = mapped_column(Float, nullable=True)

    def arrays(self) -> SampleArrays:
        """The landmark arrays of this sample."""
        n = self.n_frames
        return SampleArrays(
            xyz=np.frombuffer(self.xyz, dtype=np.float32).reshape(n, NUM_LANDMARKS, 3),
            visibility=np.frombuffer(self.visibility, dtype=np.float32).reshape(n, NUM_LANDMARKS),
            times=np.frombuffer(self.times, dtype=np.float64).reshape(n),
        )


@dataclass(frozen=True)
class SampleArrays:
    xyz: np.ndarray  # (N, 33, 3) float32, the dataset's normalised coordinates
    visibility: np.ndarray  # (N, 33) float32
    times: np.ndarray  # (N,) float64 stream time


@dataclass(frozen=True)
class KeptSample:
    """What federated training reads: one labelled sequence for one drone."""

    id: int
    drone: str
    label: str
    xyz: np.ndarray
    visibility: np.ndarray


def add_sample(
    db: Session,
    *,
    stream: str,
    drone: str,
    xyz: np.ndarray,
    visibility: np.ndarray,
    times: np.ndarray,
    created_by: str = "",
    label: str | None = None,
) -> Sample:
    """Store a recorded sequence as a pending sample (committed).

    Raises:
        ValueError: arrays of the wrong shape, non-finite values, or an unknown label.
    """
    xyz = np.asarray(xyz, dtype=np.float32)
    visibility = np.asarray(visibility, dtype=np.float32)
    times = np.asarray(times, dtype=np.float64)
    n = xyz.shape[0]
    if n == 0 or xyz.shape != (n, NUM_LANDMARKS, 3):
        raise ValueError(f"sample xyz must be (N>0, 33, 3), got {xyz.shape}")
    if visibility.shape != (n, NUM_LANDMARKS):
        raise ValueError(f"sample visibility must be ({n}, 33), got {visibility.shape}")
    if times.shape != (n,):
        raise ValueError(f"sample times must be ({n},), got {times.shape}")
    if not (np.isfinite(xyz).all() and np.isfinite(visibility).all()):
        raise ValueError("sample has non-finite landmarks")
    if label is not None and label not in GESTURES:
        raise ValueError(f"unknown gesture {label!r}; expected one of {', '.join(GESTURES)}")
    row = Sample(
        created_at=time.time(),
        stream=stream,
        drone=drone,
        label=label,
        status=str(SampleStatus.PENDING),
        n_frames=n,
        t_start=float(times[0]),
        t_end=float(times[-1]),
        xyz=xyz.tobytes(),
        visibility=visibility.tobytes(),
        times=times.tobytes(),
        created_by=created_by,
    )
    db.add(row)
    db.commit()
    return row


def review_sample(
    db: Session, sample: Sample, *, status: SampleStatus | str, label: str | None, by: str
) -> Sample:
    """Keep (with a gesture label) or delete a sample; a deleted one can be kept again.

    Raises:
        ValueError: keeping without a known label, or an unknown status.
    """
    status = SampleStatus(status)
    if label is not None and label not in GESTURES:
        raise ValueError(f"unknown gesture {label!r}; expected one of {', '.join(GESTURES)}")
    new_label = label if label is not None else sample.label
    if status is SampleStatus.KEPT and new_label is None:
        raise ValueError("a kept sample needs a gesture label")
    sample.label = new_label
    sample.status = str(status)
    sample.reviewed_by = by
    sample.reviewed_at = time.time()
    db.commit()
    return sample


def list_samples(
    db: Session,
    *,
    drone: str | None = None,
    stream: str | None = None,
    status: SampleStatus | str | None = None,
    limit: int = 200,
) -> list[Sample]:
    """Samples, newest first, filtered by drone, stream and status."""
    q = select(Sample).order_by(Sample.id.desc()).limit(limit)
    if drone is not None:
        q = q.where(Sample.drone == drone)
    if stream is not None:
        q = q.where(Sample.stream == stream)
    if status is not None:
        q = q.where(Sample.status == str(SampleStatus(status)))
    return list(db.scalars(q))


def kept_samples(db: Session, drone: str) -> list[KeptSample]:
    """Every kept, labelled sample of one drone, oldest first: that drone's additions to
    its local training data."""
    q = (
        select(Sample)
        .where(Sample.drone == drone, Sample.status == str(SampleStatus.KEPT))
        .order_by(Sample.id)
    )
    out = []
    for row in db.scalars(q):
        arr = row.arrays()
        out.append(
            KeptSample(
                id=row.id,
                drone=row.drone,
                label=row.label or "",
                xyz=arr.xyz.copy(),
                visibility=arr.visibility.copy(),
            )
        )
    return out
