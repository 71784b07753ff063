"""Capture-noised training windows, smoothed as the live engine smooths (issue 21).

Each epoch every training window is redrawn as a drone camera and the live pose path
would deliver it: a capture condition of `CAPTURE_MIX` (`proxima.gesture.capture`) is
applied to the rows that end at the window's last row, and the received poses pass the
live One Euro filter (`proxima.pose.LIVE_ONE_EURO`, the one the tracker and replayed
streams use), run from `WARMUP` poses before the window so its first frames are
filtered as in a running stream. The model therefore trains on what the filter outputs
for noisy input, the input it meets live.

Frame-rate and loss effects need the rows before a window (at 15 fps the engine's last
60 poses span 4 s): `CaptureSource.from_parts` keeps them, each part preceded by copies
of its first row where it has too few. Windows without their clip (the federated
clients' partitions) use `CaptureSource.from_windows`: no history, so those conditions
lose their frame-rate and loss effects (`without_timing`) and the filter starts at the
window's first frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from proxima.gesture.capture import CaptureModel, condition
from proxima.gesture.clip import Clip
from proxima.gesture.timebase import resample_windows
from proxima.gesture.windows import WINDOW, Windows, window_starts
from proxima.pose.one_euro import LIVE_ONE_EURO, one_euro_windows

# (condition, level, share of windows): clean (smoothed only), the field condition at
# the measured live jitter, and at twice that (the two targets).
CAPTURE_MIX: tuple[tuple[str, int, float], ...] = (
    ("clean", 1, 0.2),
    ("field", 1, 0.4),
    ("field", 2, 0.4),
)
WARMUP = 15  # received poses the filter runs over before the window
CHUNK = 1024  # windows drawn at once (bounds memory: ~80 MB of source rows)
AUGMENTS = ("none", "capture")


def without_timing(model: CaptureModel) -> CaptureModel:
    """`model` at 30 fps with no lost frames (for windows without history)."""
    return replace(model, fps=30.0, drop_rate=0.0, gap_rate_hz=0.0)


def mix_models(mix: Sequence[Sequence]) -> tuple[list[CaptureModel], np.ndarray]:
    """The capture models of a mix and their shares (normalised).

    Raises:
        ValueError: an empty mix, a negative share or an unknown condition.
    """
    if not mix:
        raise ValueError("capture mix: need at least one (condition, level, share)")
    models = [condition(str(name), int(level)) for name, level, _ in mix]
    shares = np.asarray([float(s) for *_, s in mix])
    if np.any(shares < 0) or shares.sum() <= 0:
        raise ValueError(f"capture mix: shares must be >= 0 and not all 0, got {shares}")
    return models, shares / shares.sum()


def parse_mix(text: str) -> list[list]:
    """A mix written `CONDITION:LEVEL:SHARE,...` (e.g. `clean:1:0.5,field:1:0.25,field:2:0.25`).

    Raises:
        ValueError: an entry that is not three fields, a level or share that is not a
            number, or what `mix_models` refuses.
    """
    mix: list[list] = []
    for entry in filter(None, (e.strip() for e in text.split(","))):
        fields = entry.split(":")
        if len(fields) != 3:
            raise ValueError(f"capture mix {entry!r}: expected CONDITION:LEVEL:SHARE")
        try:
            mix.append([fields[0], int(fields[1]), float(fields[2])])
        except ValueError:
            msg = f"capture mix {entry!r}: LEVEL is an integer, SHARE a number"
            raise ValueError(msg) from None
    mix_models(mix)
    return mix


def history_rows(mix: Sequence[Sequence], window: int = WINDOW, warmup: int = WARMUP) -> int:
    """Source rows (30 fps) a window needs for every model of `mix`."""
    models, _ = mix_models(mix)
    return max(max(m.source_frames(window + warmup), window + warmup) for m in models)


@dataclass
class CaptureSource:
    """The rows ending at each window's last row: `xyz` (R, 33, 3), `vis` (R, 33) of all
    parts end to end, `end` (N,) the row of window i's last frame; `history` rows are
    available before and including it for every window."""

    xyz: np.ndarray
    vis: np.ndarray
    end: np.ndarray
    history: int

    def __len__(self) -> int:
        return len(self.end)

    @classmethod
    def from_parts(
        cls,
        parts: Sequence[Clip],
        window: int,
        stride: int,
        max_gap: int,
        history: int,
    ) -> CaptureSource:
        """For the windows `make_windows(parts, window, stride, max_gap)` cuts, in its
        order; each part preceded by `history - window` copies of its first row."""
        pad = max(history - window, 0)
        xyz, vis, end = [], [], []
        base = 0
        for part in parts:
            starts, _ = window_starts(part.frames, window, stride, max_gap)
            if not starts:
                continue
            xyz += [np.repeat(part.xyz[:1], pad, axis=0), part.xyz]
            vis += [np.repeat(part.visibility[:1], pad, axis=0), part.visibility]
            end += [base + pad + s + window - 1 for s in starts]
            base += pad + len(part)
        if not end:
            return cls(np.zeros((0, 33, 3), np.float32), np.zeros((0, 33), np.float32),
                       np.zeros(0, np.int64), history)  # fmt: skip
        return cls(
            np.concatenate(xyz).astype(np.float32),
            np.concatenate(vis).astype(np.float32),
            np.asarray(end, np.int64),
            max(history, window),
        )

    @classmethod
    def from_windows(cls, w: Windows) -> CaptureSource:
        """Each window its own rows, no history."""
        n, size = w.xyz.shape[:2]
        return cls(
            w.xyz.reshape(n * size, 33, 3),
            w.vis.reshape(n * size, 33),
            np.arange(n, dtype=np.int64) * size + size - 1,
            size,
        )

    def rows(self, idx: np.ndarray, length: int) -> tuple[np.ndarray, np.ndarray]:
        """The last `length` rows up to each window's end: (n, length, 33, 3), (n, length, 33)."""
        if length > self.history:
            raise ValueError(f"{length} rows asked, {self.history} kept before each window")
        r = self.end[idx][:, None] + np.arange(1 - length, 1)[None, :]
        return self.xyz[r], self.vis[r]


def capture_windows(
    w: Windows,
    source: CaptureSource,
    mix: Sequence[Sequence],
    rng: np.random.Generator,
    window: int = WINDOW,
    warmup: int = WARMUP,
    clock: str = "poses",
) -> np.ndarray:
    """Fresh capture-noised, One-Euro-smoothed versions of windows `w` (N, window, 33, 3):
    each window draws a condition of `mix` by its share (see the module). `clock`: the
    last `window` poses received ("poses"), or under frame-rate and loss effects the last
    (window - 1) / 30 s resampled to `window` poses ("time"; "mixed": half of them).

    Raises:
        ValueError: `source` does not hold one entry per window.
    """
    if len(source) != len(w):
        raise ValueError(f"capture source has {len(source)} windows, the batch {len(w)}")
    models, shares = mix_models(mix)
    pick = rng.choice(len(models), size=len(w), p=shares)
    out = np.full((len(w), window, 33, 3), np.nan, np.float32)  # every window is drawn
    for m, model in enumerate(models):
        idx_all = np.flatnonzero(pick == m)
        warm = min(warmup, source.history - window)
        if model.timing and model.source_frames(window + warm) > source.history:
            model = without_timing(model)
        length = model.source_frames(window + warm) if model.timing else window + warm
        for i in range(0, len(idx_all), CHUNK):
            idx = idx_all[i : i + CHUNK]
            sx, sv = source.rows(idx, length)
            x, _, t = model.apply_windows(
                sx, sv, rng, aspect=w.aspect[idx], has_z=w.has_z[idx],
                window=window + warm, with_times=True,
            )  # fmt: skip
            smoothed = one_euro_windows(x, t, LIVE_ONE_EURO)
            # which windows are resampled ("mixed": half; the sped-up windows of slow
            # cameras as extra variety); the others are the last poses received
            timed = np.zeros(len(idx), bool)
            if model.timing and clock != "poses":
                timed = np.ones(len(idx), bool) if clock == "time" else rng.random(len(idx)) < 0.5
            out[idx[~timed]] = smoothed[~timed, warm:]
            if timed.any():
                out[idx[timed]] = resample_windows(t[timed], smoothed[timed], None, window)[0]
    return out
