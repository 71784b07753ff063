"""The One Euro filter (Casiez, Roussel, Vogel, CHI 2012) for arrays of landmarks.

A low-pass filter whose cutoff rises with speed: still landmarks are smoothed hard
(jitter removed), fast ones lightly (little lag). MediaPipe's Tasks API no longer
smooths landmarks as the legacy `mp.solutions.pose` did, and the gesture data was
recorded with smoothing, so live landmarks are smoothed before classification.
Time comes from the frames (stream time), so gaps and replay speed are handled.

One rule for live and training (docs/recognition.md, "One smoothing rule"): camera
streams (the operator tracker), replayed landmark streams (engine/stream.py) and the
training windows (gesture/augment.py, `one_euro_windows`) all pass the filter with
`LIVE_ONE_EURO`, tuned on the measured live-path jitter by `bench/one_euro_tuning.py`
(least position + velocity error; docs/capture.md), reset after `RESET_AFTER_S` unseen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OneEuroParams:
    """A One Euro setting: `min_cutoff` (Hz), `beta`, `d_cutoff` (Hz)."""

    min_cutoff: float
    beta: float
    d_cutoff: float


# bench/one_euro_tuning.py's recommendation (bench/results/one_euro_tuning.json): at the
# measured jitter 0.0129 torso lengths of position error (unfiltered 0.0134, the old
# tracker setting (1, 30, 1) 0.0229) and 0.0138 of velocity error (0.0188, 0.0148).
LIVE_ONE_EURO = OneEuroParams(min_cutoff=3.0, beta=100.0, d_cutoff=2.0)
RESET_AFTER_S = 0.5  # a pose unseen this long starts the filter afresh (the tracker's rule)


def _alpha(cutoff: np.ndarray | float, dt: float) -> np.ndarray | float:
    tau = 1.0 / (2.0 * math.pi * np.asarray(cutoff))
    return 1.0 / (1.0 + tau / dt)


class OneEuroFilter:
    """Element-wise One Euro filter over arrays of a fixed shape.

    `min_cutoff` (Hz) sets smoothing at rest, `beta` how fast the cutoff rises with
    speed (units/s), `d_cutoff` (Hz) the smoothing of the speed estimate.
    """

    def __init__(self, min_cutoff: float = 1.0, beta: float = 30.0, d_cutoff: float = 1.0) -> None:
        if min_cutoff <= 0 or d_cutoff <= 0 or beta < 0:
            raise ValueError("need min_cutoff > 0, d_cutoff > 0, beta >= 0")
        self.min_cutoff = min_cutoff
        self.beta = beta
        self.d_cutoff = d_cutoff
        self.reset()

    def reset(self) -> None:
        """Forget the history; the next value passes through unchanged."""
        self._x: np.ndarray | None = None
        self._dx: np.ndarray | None = None
        self._t: float | None = None

    def __call__(self, x: np.ndarray, t: float) -> np.ndarray:
        """Filter value `x` observed at time `t` (seconds); returns the smoothed value.
        A `t` not after the previous one returns the previous output unchanged."""
        x = np.asarray(x, dtype=np.float64)
        if self._x is None or self._t is None:
            self._x, self._dx, self._t = x.copy(), np.zeros_like(x), t
            return x.copy()
        if x.shape != self._x.shape:
            raise ValueError(f"shape changed from {self._x.shape} to {x.shape}; reset first")
        dt = t - self._t
        if dt <= 0:
            return self._x.copy()
        dx = (x - self._x) / dt
        self._dx = self._dx + _alpha(self.d_cutoff, dt) * (dx - self._dx)
        cutoff = self.min_cutoff + self.beta * np.abs(self._dx)
        self._x = self._x + _alpha(cutoff, dt) * (x - self._x)
        self._t = t
        return self._x.copy()


def one_euro_windows(
    x: np.ndarray,
    t: np.ndarray,
    params: OneEuroParams = LIVE_ONE_EURO,
    reset_after_s: float = RESET_AFTER_S,
) -> np.ndarray:
    """`OneEuroFilter` run along axis 1 of a batch: `x` (N, T, ...) observed at times `t`
    (N, T) seconds, each row its own filter started at its first frame, restarted after a
    pause over `reset_after_s`. The same equations as the class (tested against it).

    Raises:
        ValueError: `t` is not (N, T) for `x`.
    """
    x = np.asarray(x, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if t.shape != x.shape[:2]:
        raise ValueError(f"times {t.shape} do not match the batch {x.shape[:2]}")
    out = np.empty_like(x)
    extra = (1,) * (x.ndim - 2)
    state = x[:, 0].copy()
    dstate = np.zeros_like(state)
    out[:, 0] = state
    for k in range(1, x.shape[1]):
        dt = (t[:, k] - t[:, k - 1]).reshape(-1, *extra)
        restart = dt > reset_after_s
        ok = dt > 0
        safe = np.where(ok, dt, 1.0)
        dx = (x[:, k] - state) / safe
        a_d = 1.0 / (1.0 + 1.0 / (2.0 * math.pi * params.d_cutoff * safe))
        new_d = dstate + a_d * (dx - dstate)
        cutoff = params.min_cutoff + params.beta * np.abs(new_d)
        a = 1.0 / (1.0 + 1.0 / (2.0 * math.pi * cutoff * safe))
        new = state + a * (x[:, k] - state)
        state = np.where(restart, x[:, k], np.where(ok, new, state))
        dstate = np.where(restart, 0.0, np.where(ok, new_d, dstate))
        out[:, k] = state
    return out


class PoseSmoother:
    """The live rule for one stream of poses: `LIVE_ONE_EURO` (or `params`) on the
    landmarks, restarted after a pause over `reset_after_s` or on `reset()`."""

    def __init__(
        self, params: OneEuroParams = LIVE_ONE_EURO, reset_after_s: float = RESET_AFTER_S
    ) -> None:
        self.filter = OneEuroFilter(params.min_cutoff, params.beta, params.d_cutoff)
        self.reset_after_s = reset_after_s
        self._last_t: float | None = None

    def reset(self) -> None:
        self.filter.reset()
        self._last_t = None

    def __call__(self, xyz: np.ndarray, t: float) -> np.ndarray:
        """The smoothed landmarks (float32) of a pose seen at stream time `t`."""
        if self._last_t is None or t - self._last_t > self.reset_after_s:
            self.filter.reset()
        self._last_t = t
        return self.filter(xyz, t).astype(np.float32)
