"""Evaluation splits and 60-frame windows.

A split decides, per clip, which rows train and which test. Windows are then cut inside
each part, never across it: a random split of overlapping windows from one clip puts
near-identical windows on both sides and scores 0.99-1.00 for any model, so it is not
offered here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from proxima.gesture.clip import Clip, DataError
from proxima.types import GESTURES

WINDOW = 60
MIN_WINDOW = 15  # the shortest window `proxima train --window` takes (0.5 s at 30 fps)
TEMPORAL_TRAIN_FRACTION = 0.7
# Sources that only ever train: synthetic clips are not recordings of anyone, so no
# split scores on them; every test part holds real clips only.
TRAIN_ONLY_SOURCES = frozenset({"synth"})
# Frames a second of each source's recordings, for splits that count in seconds. LASER:
# 30 fps. UAV-Gesture: 25 fps, the frame rate of its 1920x1080 videos in the data set's
# paper (Perera et al. 2018); the joint files themselves carry no rate. Synthetic: 30.
# Console samples: numbered on a 30 fps clock from their stream times (console_samples.py).
SOURCE_FPS = {"laser": 30.0, "uav-gesture": 25.0, "synth": 30.0, "console": 30.0}
CALIBRATE = "calibrate"
# Inner splits a calibration can follow: those that hold out whole clips of a new view
# or new people (the temporal split's test parts are tails of seen clips).
CALIBRATABLE = ("cross-view", "uav-gesture")


@dataclass
class Windows:
    """A batch of windows. xyz (N, W, 33, 3) normalised; vis (N, W, 33); labels (N,);
    clip (N,) index into `clip_names`; aspect (N,), has_z (N,) and scene (N,) per window.
    `scene` is the window's `Clip.scene` (one person before one camera): windows of one
    scene may be joined into transitions (augment.py)."""

    xyz: np.ndarray
    vis: np.ndarray
    labels: np.ndarray
    clip: np.ndarray
    aspect: np.ndarray
    has_z: np.ndarray
    scene: np.ndarray
    clip_names: list[str] = field(default_factory=list)
    skipped: int = 0  # windows not cut because they would span a long gap

    def __len__(self) -> int:
        return len(self.labels)

    def subset(self, idx: np.ndarray) -> Windows:
        return Windows(
            self.xyz[idx],
            self.vis[idx],
            self.labels[idx],
            self.clip[idx],
            self.aspect[idx],
            self.has_z[idx],
            self.scene[idx],
            self.clip_names,
            0,
        )


def window_starts(frames: np.ndarray, window: int, stride: int, max_gap: int) -> tuple[list, int]:
    """Start rows of the windows of one clip part, and how many were skipped because
    they would bridge a gap of more than `max_gap` missing frames."""
    n = len(frames)
    if n < window:
        return [], 0
    missing = np.diff(frames) - 1  # frames lost between row i and i+1
    bad = np.r_[0, np.cumsum(missing > max_gap)]  # count of long gaps up to each row
    starts, skipped = [], 0
    for s in range(0, n - window + 1, stride):
        if bad[s + window - 1] - bad[s] > 0:
            skipped += 1
        else:
            starts.append(s)
    return starts, skipped


def make_windows(
    parts: Sequence[Clip],
    window: int = WINDOW,
    stride: int = 5,
    max_gap: int = 5,
    clip_names: list[str] | None = None,
) -> Windows:
    """Cut windows from clip parts (each part's rows are contiguous in its clip)."""
    names = clip_names if clip_names is not None else []
    xyz, vis, labels, clip_ix, aspect, has_z, scene = [], [], [], [], [], [], []
    skipped = 0
    for part in parts:
        if part.name not in names:
            names.append(part.name)
        ci = names.index(part.name)
        starts, sk = window_starts(part.frames, window, stride, max_gap)
        skipped += sk
        for s in starts:
            xyz.append(part.xyz[s : s + window])
            vis.append(part.visibility[s : s + window])
        n = len(starts)
        labels += [GESTURES.index(part.gesture)] * n
        clip_ix += [ci] * n
        aspect += [part.aspect] * n
        has_z += [part.has_z] * n
        scene += [part.scene] * n
    if not xyz:
        empty = np.zeros((0, window, 33), np.float32)
        return Windows(
            np.zeros((0, window, 33, 3), np.float32),
            empty,
            np.zeros(0, np.int64),
            np.zeros(0, np.int64),
            np.zeros(0, np.float32),
            np.zeros(0, bool),
            np.zeros(0, str),
            names,
            skipped,
        )
    return Windows(
        np.stack(xyz).astype(np.float32),
        np.stack(vis).astype(np.float32),
        np.asarray(labels, np.int64),
        np.asarray(clip_ix, np.int64),
        np.asarray(aspect, np.float32),
        np.asarray(has_z, bool),
        np.asarray(scene),
        names,
        skipped,
    )


@dataclass
class SplitParts:
    """Clip parts for training and testing. `test` is empty for `--split all`."""

    name: str
    train: list[Clip]
    test: list[Clip]
    # `calibrate:` splits only: the first seconds of each held-out clip (also in `train`)
    calibration: list[Clip] = field(default_factory=list)


def temporal_parts(clip: Clip, window: int) -> tuple[Clip, Clip]:
    """First 70% of rows minus one window (the gap) to train, last 30% to test."""
    cut = round(len(clip) * TEMPORAL_TRAIN_FRACTION)
    return clip.slice(0, max(cut - window, 0)), clip.slice(cut, len(clip))


def clip_fps(clip: Clip) -> float:
    """The frame rate of a clip's recording (`SOURCE_FPS`)."""
    try:
        return SOURCE_FPS[clip.source]
    except KeyError:
        raise DataError(f"{clip.name}: no known frame rate for source {clip.source!r}") from None


def parse_calibration(split: str) -> tuple[str, float] | None:
    """(inner split, seconds) of `calibrate:<split>:<seconds>`, or None for other splits.
    The seconds are the last field: the inner split has colons of its own.

    Raises:
        DataError: a malformed calibration split; the message names the bad field.
    """
    kind, _, rest = split.partition(":")
    if kind != CALIBRATE:
        return None
    inner, sep, seconds = rest.rpartition(":")
    usage = "use calibrate:<split>:<seconds>, e.g. calibrate:cross-view:l:5"
    if not sep or not inner:
        raise DataError(f"split {split!r}: {usage}")
    try:
        value = float(seconds)
    except ValueError:
        raise DataError(
            f"split {split!r}: the seconds field {seconds!r} is not a number ({usage})"
        ) from None
    if not math.isfinite(value) or value < 0:
        raise DataError(f"split {split!r}: the seconds field must be a number >= 0, not {seconds}")
    if inner.partition(":")[0] not in CALIBRATABLE:
        raise DataError(
            f"split {split!r}: the inner split {inner!r} must hold out whole clips: "
            "cross-view:f|l|r or uav-gesture:1|2|3"
        )
    return inner, value


def calibration_parts(clip: Clip, seconds: float, window: int) -> tuple[Clip, Clip]:
    """(the first `seconds` of a clip, the rest after a one-window gap). Seconds count in
    the clip's own frame rate from its first frame with a person, by frame number, so a
    gap of missing frames counts as time. With 0 s the rest is the whole clip."""
    n = round(seconds * clip_fps(clip))
    if n == 0:
        return clip.slice(0, 0), clip
    start = int(clip.frames[0])
    end = int(np.searchsorted(clip.frames, start + n))  # rows of frames < start + n
    rest = int(np.searchsorted(clip.frames, start + n + window))  # window frames skipped
    return clip.slice(0, end), clip.slice(rest, len(clip))


def calibration_split(
    clips: Sequence[Clip],
    split: str,
    inner_split: str,
    seconds: float,
    window: int = WINDOW,
    uav_dir: Path | None = None,
) -> SplitParts:
    """`calibrate:<inner_split>:<seconds>` (see `split_clips`)."""
    inner = split_clips(clips, inner_split, window, uav_dir)
    calib: list[Clip] = []
    test: list[Clip] = []
    for c in inner.test:
        a, b = calibration_parts(c, seconds, window)
        if len(a):
            calib.append(a)
        if len(b):
            test.append(b)
    if not test:
        raise DataError(f"split {split!r}: {seconds:g} s leaves no test frames in any clip")
    return SplitParts(split, inner.train + calib, test, calib)


def split_clips(
    clips: Sequence[Clip], split: str, window: int = WINDOW, uav_dir: Path | None = None
) -> SplitParts:
    """Apply a named split: `temporal`, `cross-view:f|l|r`, `all`, `uav-gesture:1|2|3`,
    or `calibrate:<cross-view or uav-gesture split>:<seconds>`: the inner split's
    training part plus the first seconds of each of its test clips train, the rest of
    each test clip after a one-window gap tests (`calibration_parts`).
    Clips of `TRAIN_ONLY_SOURCES` (synthetic) go whole to the training part of every
    split; the test parts hold real clips only.

    Raises:
        DataError: unknown split, or one that leaves no training or no test data.
    """
    calibration = parse_calibration(split)
    if calibration is not None:
        return calibration_split(clips, split, *calibration, window, uav_dir)
    kind, _, arg = split.partition(":")
    train: list[Clip] = []
    test: list[Clip] = []
    if kind == "temporal":
        for c in clips:
            if c.source in TRAIN_ONLY_SOURCES:
                train.append(c)  # the whole clip: it never shares a scene with a test part
                continue
            a, b = temporal_parts(c, window)
            train.append(a)
            test.append(b)
    elif kind == "all":
        train = list(clips)
    elif kind == "cross-view":
        if arg not in ("f", "l", "r"):
            raise DataError(f"split {split!r}: the view must be f, l or r")
        # LASER clips of the held-out view test; everything else (other views, any
        # UAV-Gesture clips, which are other people, and synthetic clips) trains.
        for c in clips:
            (test if c.source == "laser" and c.view == arg else train).append(c)
    elif kind == "uav-gesture":
        from proxima.gesture.uavgesture import load_split

        if uav_dir is None:
            raise DataError(f"split {split!r} needs UAV-Gesture data (--data uav-gesture)")
        try:
            number = int(arg)
        except ValueError:
            raise DataError(f"split {split!r}: the split number must be 1, 2 or 3") from None
        tr_names, te_names = load_split(uav_dir, number)
        for c in clips:
            if c.source != "uav-gesture" or c.name in tr_names:
                train.append(c)
            elif c.name in te_names:
                test.append(c)
    else:
        raise DataError(
            f"unknown split {split!r}: use temporal, cross-view:f|l|r, all, uav-gesture:1|2|3 "
            "or calibrate:<split>:<seconds>"
        )
    if not train:
        raise DataError(f"split {split!r} leaves no training data")
    if kind != "all" and not test:
        only = (
            " (synthetic clips never test: add real data)"
            if all(c.source in TRAIN_ONLY_SOURCES for c in clips)
            else ""
        )
        raise DataError(f"split {split!r} leaves no test data for the given --data{only}")
    return SplitParts(split, train, test)


def validation_parts(train: Sequence[Clip], window: int, fraction: float = 0.15) -> tuple:
    """Hold out the last `fraction` of each training part (after a one-window gap) for
    early stopping, so validation windows never overlap training windows."""
    fit, val = [], []
    for c in train:
        cut = round(len(c) * (1 - fraction))
        if cut - window < window or len(c) - cut < window:
            fit.append(c)  # too short to split: all of it trains
            continue
        fit.append(c.slice(0, cut - window))
        val.append(c.slice(cut, len(c)))
    return fit, val
