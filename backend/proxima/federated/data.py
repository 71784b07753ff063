"""What a drone trains on, and the held-out set the global model is scored on.

Both come from the centralised code (`proxima.gesture`): clips, the temporal split, the
validation tail of each training part, and 60-frame windows. Only the training parts
(the first 70% of every clip, minus a one-window gap) are ever shared out to drones; the
last 30% is the held-out test set, which no drone trains on. As in centralised training,
moving gestures' training parts start with at most half a window of the clip's opening
rest (`trim-idle`, gesture/idle.py).

Partitions (the run config's `partition`):
- `view`: drone i holds the clips of camera view f, l, r (i mod 3): three drones seeing
  the operator from three sides, strongly non-IID.
- `iid`: every class's windows dealt out evenly at random.
- `dirichlet`: every class's windows split by proportions drawn from Dir(alpha).
Every drone computes the same assignment from the run's seed and keeps its own share.

A drone's console-labelled samples (`proxima.store.samples`, kept ones only) join its
data. A sample that cannot be used (unreadable arrays, non-finite values, an unknown
label, too short for a window) is skipped and reported, never fatal.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from proxima.federated.config import FLConfig, view_of
from proxima.gesture.clip import Clip
from proxima.gesture.idle import trim_idle
from proxima.gesture.windows import (
    WINDOW,
    Windows,
    make_windows,
    split_clips,
    validation_parts,
)
from proxima.types import GESTURES, NUM_LANDMARKS


@dataclass
class DroneData:
    """One drone's local training data."""

    drone: str
    fit: Windows
    val: Windows
    samples_used: int = 0
    notes: list[str] = field(default_factory=list)  # problems worth reporting upstream


def _fingerprint(folders: Sequence[Path]) -> str:
    """Cheap identity of data folders: every data file's name, size and mtime."""
    h = hashlib.sha256()
    for folder in folders:
        h.update(str(folder.resolve()).encode())
        for f in sorted(folder.rglob("*")):
            if f.is_file() and f.suffix in (".csv", ".mat", ".txt", ".json"):
                st = f.stat()
                h.update(f"{f.relative_to(folder)}:{st.st_size}:{st.st_mtime_ns}\n".encode())
    return h.hexdigest()[:24]


def _save_clips(path: Path, clips: Sequence[Clip]) -> None:
    meta = [
        {"name": c.name, "gesture": c.gesture, "view": c.view, "subject": c.subject,
         "source": c.source, "aspect": c.aspect, "has_z": c.has_z, "n": len(c)}
        for c in clips
    ]  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    np.savez(
        tmp,
        meta=np.frombuffer(json.dumps(meta).encode(), np.uint8),
        frames=np.concatenate([c.frames for c in clips]),
        xyz=np.concatenate([c.xyz for c in clips]),
        visibility=np.concatenate([c.visibility for c in clips]),
    )
    tmp.replace(path)


def _read_clips(path: Path) -> list[Clip]:
    with np.load(path) as z:
        meta = json.loads(z["meta"].tobytes())
        frames, xyz, vis = z["frames"], z["xyz"], z["visibility"]
    clips, at = [], 0
    for m in meta:
        n = m.pop("n")
        clips.append(Clip(frames=frames[at : at + n], xyz=xyz[at : at + n],
                          visibility=vis[at : at + n], **m))  # fmt: skip
        at += n
    return clips


@functools.lru_cache(maxsize=4)
def _load(specs: tuple[str, ...]) -> tuple[Clip, ...]:
    """Clips of the data folders, parsed once per machine: every drone process (a
    simulation actor, a deployment ClientApp) would otherwise parse the CSVs again.
    The parsed arrays are cached under the user cache, keyed by the files' names,
    sizes and modification times."""
    from proxima.gesture.data_source import cache_dir, resolve_dataset
    from proxima.gesture.datasets import load_data

    folders = [resolve_dataset(s) for s in specs or (None,)]
    cache = cache_dir().parent / "fl-clips" / f"{_fingerprint(folders)}.npz"
    if cache.is_file():
        try:
            return tuple(_read_clips(cache))
        except (OSError, ValueError, KeyError, TypeError):
            cache.unlink(missing_ok=True)  # unreadable: parse again
    clips = load_data([str(f) for f in folders]).clips
    with contextlib.suppress(OSError):  # a read-only cache only costs time
        _save_clips(cache, clips)
    return tuple(clips)


def load_clips(specs: Sequence[str] | None) -> list[Clip]:
    return list(_load(tuple(specs or ())))


def test_windows(cfg: FLConfig, clips: Sequence[Clip] | None = None) -> Windows:
    """The held-out set: the last 30% of every clip (the temporal split's test part)."""
    clips = load_clips(cfg.data_specs()) if clips is None else clips
    parts = split_clips(clips, "temporal", WINDOW)  # the protocol's gaps
    return make_windows(parts.test, cfg.window, cfg.test_stride, cfg.max_gap)


def _assign(labels: np.ndarray, cfg: FLConfig, salt: int) -> np.ndarray:
    """Drone index for every window: per class, dealt evenly (iid) or by Dirichlet
    proportions. Deterministic in (seed, salt) so every drone computes the same."""
    rng = np.random.default_rng([cfg.seed, salt])
    owner = np.zeros(len(labels), np.int64)
    n = cfg.num_drones
    for c in range(len(GESTURES)):
        idx = np.flatnonzero(labels == c)
        if not len(idx):
            continue
        idx = rng.permutation(idx)
        if cfg.partition == "iid":
            owner[idx] = np.arange(len(idx)) % n
        else:
            p = rng.dirichlet(np.full(n, cfg.dirichlet_alpha))
            cuts = (np.cumsum(p)[:-1] * len(idx)).round().astype(int)
            for drone, part in enumerate(np.split(idx, cuts)):
                owner[part] = drone
    return owner


def partition_windows(
    cfg: FLConfig, partition_id: int, clips: Sequence[Clip]
) -> tuple[Windows, Windows]:
    """(fit, validation) windows of one drone's partition of the training parts."""
    parts = split_clips(clips, "temporal", WINDOW)  # the protocol's gaps
    train = parts.train
    if cfg.partition == "view":
        view = view_of(partition_id)
        train = [c for c in train if c.view == view]
    if cfg.trim_idle:
        train = [trim_idle(c, cfg.window) for c in train]
    fit_parts, val_parts = validation_parts(train, cfg.window)
    names: list[str] = []
    fit = make_windows(fit_parts, cfg.window, cfg.stride, cfg.max_gap, names)
    val = make_windows(val_parts, cfg.window, cfg.stride, cfg.max_gap, names)
    if cfg.partition != "view":
        fit = fit.subset(np.flatnonzero(_assign(fit.labels, cfg, 1) == partition_id))
        val = val.subset(np.flatnonzero(_assign(val.labels, cfg, 2) == partition_id))
    return fit, val


def sample_clips(
    db_path: str | Path, drone: str, window: int = WINDOW
) -> tuple[list[Clip], list[str]]:
    """The drone's kept samples from the console's store as clips, plus one note per
    sample that had to be skipped (the run goes on without it)."""
    from sqlalchemy import inspect
    from sqlalchemy.exc import SQLAlchemyError

    from proxima.store.base import make_engine, make_sessionmaker
    from proxima.store.samples import SampleStatus, list_samples

    clips: list[Clip] = []
    notes: list[str] = []
    engine = make_engine(db_path)
    try:
        if not inspect(engine).has_table("samples"):
            return clips, notes  # a console database without labelled samples yet
        with make_sessionmaker(engine)() as db:
            rows = list_samples(db, drone=drone, status=SampleStatus.KEPT, limit=1_000_000)
            for row in reversed(rows):  # oldest first
                try:
                    arr = row.arrays()
                    xyz, vis = np.asarray(arr.xyz, np.float32), np.asarray(arr.visibility)
                    if xyz.shape[1:] != (NUM_LANDMARKS, 3) or vis.shape != xyz.shape[:2]:
                        raise ValueError(f"landmarks of shape {xyz.shape}")
                    if not (np.isfinite(xyz).all() and np.isfinite(vis).all()):
                        raise ValueError("non-finite landmarks")
                    if row.label not in GESTURES:
                        raise ValueError(f"unknown label {row.label!r}")
                    if len(xyz) < window:
                        raise ValueError(f"{len(xyz)} frames, fewer than one window ({window})")
                except ValueError as exc:
                    notes.append(f"sample {row.id} skipped: {exc}")
                    continue
                clips.append(
                    Clip(
                        name=f"sample-{row.id}",
                        gesture=str(row.label),
                        view="f",
                        subject=f"console:{drone}",
                        source="console",
                        frames=np.arange(len(xyz)),
                        xyz=xyz.copy(),
                        visibility=vis.astype(np.float32),
                    )
                )
    except SQLAlchemyError as exc:
        notes.append(f"sample store {db_path} unreadable: {type(exc).__name__}: {exc}")
    finally:
        engine.dispose()
    return clips, notes


def _concat(a: Windows, b: Windows) -> Windows:
    if not len(b):
        return a
    offset = len(a.clip_names)
    return Windows(
        np.concatenate([a.xyz, b.xyz]),
        np.concatenate([a.vis, b.vis]),
        np.concatenate([a.labels, b.labels]),
        np.concatenate([a.clip, b.clip + offset]),
        np.concatenate([a.aspect, b.aspect]),
        np.concatenate([a.has_z, b.has_z]),
        np.concatenate([a.scene, b.scene]),
        a.clip_names + b.clip_names,
        a.skipped + b.skipped,
    )


def drone_data(
    cfg: FLConfig,
    partition_id: int,
    drone: str,
    data_specs: Sequence[str] | None = None,
    samples_db: str | Path | None = None,
) -> DroneData:
    """A drone's partition of the data set plus its kept console samples."""
    clips = load_clips(data_specs if data_specs is not None else cfg.data_specs())
    fit, val = partition_windows(cfg, partition_id, clips)
    out = DroneData(drone, fit, val)
    if cfg.include_samples and samples_db:
        if not Path(samples_db).is_file():
            out.notes.append(f"sample store {samples_db} not found: no samples used")
        else:
            extra, notes = sample_clips(samples_db, drone, cfg.window)
            out.notes += notes
            if extra:
                # Samples are short: all of each trains (validation stays the data set's).
                out.fit = _concat(fit, make_windows(extra, cfg.window, cfg.stride, cfg.max_gap))
                out.samples_used = len(extra)
                out.notes.append(f"{len(extra)} console sample(s) used")
    return out
