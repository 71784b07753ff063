"""A performance: a script of gestures (and idle stances) turned into a posture per frame.

Every random choice of one gesture's performance is drawn once into a `GestureDraw`
(tempo, amplitude, pauses at the ends of each swing, repetitions or hold time, the
arms' own variation of the gesture's poses, a hesitation) and kept in the data set's
manifest. Between steps the body moves from where the last one ended to where the next
one starts (an ease-in-out over `entry_s`); those frames belong to the step they lead
into, as a live stream shows a gesture's onset. On top of the script, slow random motion
(the arms' joint angles, trunk lean and twist, head, a weight shift at the pelvis, a
knee bend) keeps repetitions from being identical copies.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from proxima.synth.anthropometry import Hand
from proxima.synth.body import Posture
from proxima.synth.gestures import IDLE, SPECS
from proxima.synth.joints import ELEVATION, PLANE
from proxima.types import GESTURES

IDLE_LABEL = ""  # frames that belong to no gesture
# Per-performance spread of each pose angle (plane, elevation, rotation, elbow,
# pronation, wrist deviation, wrist flexion), degrees.
POSE_JITTER_DEG = np.array([6.0, 6.0, 8.0, 7.0, 10.0, 4.0, 4.0])
REPETITIONS = (3, 8)
HOLD_S = (3.5, 8.0)
AMPLITUDE = (0.85, 1.08)
ENTRY_S = (0.35, 0.7)
HESITATION_P = 0.3
HESITATION_S = (0.3, 1.0)
LOW_ELEVATION = 30.0  # degrees: below it an arm's plane of elevation barely shows


@dataclass(frozen=True)
class GestureDraw:
    """One performance of one gesture (or of an idle stance, `gesture == ""`): every
    random choice, so that the manifest can say what was drawn."""

    gesture: str
    duration_s: float  # the step itself, after its entry transition
    entry_s: float
    right_rest: tuple[float, ...]
    left_rest: tuple[float, ...]
    right_peak: tuple[float, ...] | None = None
    left_peak: tuple[float, ...] | None = None
    period_s: float | None = None
    repetitions: float = 0.0  # cycles, possibly ending part-way through one
    amplitude: float = 1.0
    dwell: float = 1.0
    lag_cycles: float = 0.0  # the left arm's delay behind the right
    hesitation_at_s: float = 0.0  # where a pause starts (within the step)
    hesitation_s: float = 0.0
    variant: bool = False  # the gesture's other form (`GestureSpec.variant`)

    def to_dict(self) -> dict[str, object]:
        def r(v: object) -> object:
            if isinstance(v, float):
                return round(v, 4)
            if isinstance(v, tuple):
                return [round(x, 2) for x in v]
            return v

        return {k: r(v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> GestureDraw:
        d = dict(d)
        for k in ("right_rest", "left_rest", "right_peak", "left_peak"):
            if d.get(k) is not None:
                d[k] = tuple(d[k])
        return cls(**d)


def _jitter(rng: np.random.Generator, pose: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in pose + rng.normal(0.0, POSE_JITTER_DEG))


def draw_gesture(
    gesture: str,
    rng: np.random.Generator,
    handedness: Hand = "right",
    duration_s: float | None = None,
    variant: bool = False,
) -> GestureDraw:
    """Draw one performance of `gesture` ("" for an idle stance); `variant` makes the
    gesture's other form where it has one (`GestureSpec.variant`).

    Raises:
        ValueError: unknown gesture.
    """
    entry = float(rng.uniform(*ENTRY_S))
    if gesture == IDLE_LABEL:
        d = float(duration_s if duration_s is not None else rng.uniform(0.5, 2.0))
        return GestureDraw("", d, entry, _jitter(rng, IDLE), _jitter(rng, IDLE))
    if gesture not in SPECS:
        raise ValueError(f"unknown gesture {gesture!r}; choose from {', '.join(GESTURES)}")
    spec = SPECS[gesture]
    if variant and spec.variant is not None:
        right, left = spec.variant
    else:
        right, left = spec.right, spec.left
        variant = False
    if spec.handed and handedness == "left":
        right, left = left, right
    rest_r, rest_l = _jitter(rng, right.rest), _jitter(rng, left.rest)
    peak_r = _jitter(rng, right.peak) if right.peak is not None else None
    peak_l = _jitter(rng, left.peak) if left.peak is not None else None
    hes_s = float(rng.uniform(*HESITATION_S)) if rng.random() < HESITATION_P else 0.0
    if spec.period_s is None:
        d = float(duration_s if duration_s is not None else rng.uniform(*HOLD_S))
        return GestureDraw(
            gesture,
            d + hes_s,
            entry,
            rest_r,
            rest_l,
            hesitation_at_s=float(rng.uniform(0.2, 0.8) * d),
            hesitation_s=hes_s,
            variant=variant,
        )
    period = float(rng.uniform(*spec.period_s))
    if duration_s is not None:
        reps = duration_s / period
    else:
        reps = float(rng.integers(REPETITIONS[0], REPETITIONS[1] + 1) + rng.uniform(0, 0.5))
    # A hesitation falls at the end of a swing (at rest or at the peak).
    half = int(rng.integers(1, max(int(2 * reps), 2)))
    return GestureDraw(
        gesture,
        reps * period + hes_s,
        entry,
        rest_r,
        rest_l,
        peak_r,
        peak_l,
        period,
        reps,
        amplitude=float(rng.uniform(*AMPLITUDE)),
        dwell=float(rng.uniform(*spec.dwell)),
        lag_cycles=float(rng.normal(0.0, 0.03)),
        hesitation_at_s=half * period / 2,
        hesitation_s=hes_s,
        variant=variant,
    )


def wave(phase: np.ndarray, dwell: float) -> np.ndarray:
    """0 -> 1 -> 0 once per cycle of `phase`; `dwell` > 1 lingers at both ends."""
    base = (1 - np.cos(2 * np.pi * phase)) / 2
    if dwell == 1.0:
        return base
    a, b = base**dwell, (1 - base) ** dwell
    return a / np.maximum(a + b, 1e-12)


def smooth_noise(
    rng: np.random.Generator, n: int, fps: float, hz: float, dims: int = 1
) -> np.ndarray:
    """(n, dims) slow random motion of unit variance: three sinusoids per dimension,
    frequencies 0.5-1.5 x `hz`, random phases."""
    t = np.arange(n)[:, None, None] / fps
    f = rng.uniform(0.5, 1.5, size=(1, dims, 3)) * hz
    ph = rng.uniform(0, 2 * np.pi, size=(1, dims, 3))
    return np.sin(2 * np.pi * f * t + ph).sum(axis=-1) * np.sqrt(2 / 3)


def _step_track(
    draw: GestureDraw, fps: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Both arms' angles (n, 7) during a step (its entry transition excluded)."""
    n = max(round(draw.duration_s * fps), 1)
    t = np.arange(n) / fps
    # Motion time stands still during the hesitation.
    h0, hs = draw.hesitation_at_s, draw.hesitation_s
    tau = np.where(t < h0, t, np.where(t < h0 + hs, h0, t - hs))
    rest_r, rest_l = np.asarray(draw.right_rest), np.asarray(draw.left_rest)
    if draw.period_s is None:
        return np.tile(rest_r, (n, 1)), np.tile(rest_l, (n, 1))
    rate = (1 + 0.06 * smooth_noise(rng, n, fps, 0.15)[:, 0]) / draw.period_s
    phase = np.concatenate([[0.0], np.cumsum(rate[1:] * np.diff(tau))])
    amp = draw.amplitude * (1 + 0.05 * smooth_noise(rng, n, fps, 0.3)[:, 0])
    out = []
    for rest, peak, lag in (
        (rest_r, draw.right_peak, 0.0),
        (rest_l, draw.left_peak, draw.lag_cycles),
    ):
        if peak is None:
            out.append(np.tile(rest, (n, 1)))
            continue
        w = wave(np.maximum(phase - lag, 0.0), draw.dwell)
        weights = np.repeat((w * amp)[:, None], 7, axis=1)
        if rest[ELEVATION] < LOW_ELEVATION:
            # From a hanging arm the plane of elevation means little: the arm turns into
            # its plane early and rises in it (a forward raise goes forward all the way),
            # and the amplitude changes how high it goes, not which way.
            weights[:, PLANE] = w ** (1 / 3)
        out.append(rest + weights * (np.asarray(peak) - rest))
    return out[0], out[1]


def _ease(n: int) -> np.ndarray:
    x = (np.arange(1, n + 1) / (n + 1))[:, None]
    return x * x * (3 - 2 * x)


@dataclass
class Performance:
    """A script performed: the posture per frame, the label of each frame (the gesture
    it belongs to, "" for idle), and each step's frame span `(label, start, onset, end)`:
    the entry transition runs from start to onset, the step itself to end (exclusive)."""

    posture: Posture
    labels: np.ndarray
    fps: float
    draws: list[GestureDraw]
    segments: list[tuple[str, int, int, int]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.labels)


def perform(
    steps: Sequence[GestureDraw],
    rng: np.random.Generator,
    fps: float = 30.0,
    head_turn_deg: float = 0.0,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> Performance:
    """Perform drawn steps one after another, from `start` (both arms' angles; default:
    the first step's own start, without an entry transition). `head_turn_deg` turns the
    head to the left (negative: right), e.g. toward the camera the operator watches."""
    right_parts, left_parts, labels = [], [], []
    segments: list[tuple[str, int, int, int]] = []
    prev = start
    at = 0
    for i, draw in enumerate(steps):
        r, left = _step_track(draw, fps, rng)
        n_e = round(draw.entry_s * fps) if (prev is not None or i > 0) else 0
        if n_e and prev is not None:
            e = _ease(n_e)
            right_parts.append(prev[0] + e * (r[0] - prev[0]))
            left_parts.append(prev[1] + e * (left[0] - prev[1]))
        else:
            n_e = 0
        right_parts.append(r)
        left_parts.append(left)
        labels += [draw.gesture] * (n_e + len(r))
        segments.append((draw.gesture, at, at + n_e, at + n_e + len(r)))
        at += n_e + len(r)
        prev = (r[-1], left[-1])
    right = np.concatenate(right_parts)
    left = np.concatenate(left_parts)
    T = len(right)
    sway = np.array([2.0, 2.0, 2.5, 2.5, 3.0, 1.5, 1.5])  # degrees, per joint angle
    right = right + smooth_noise(rng, T, fps, 0.7, 7) * sway
    left = left + smooth_noise(rng, T, fps, 0.7, 7) * sway
    trunk = np.array([rng.uniform(-2, 4), rng.uniform(-2, 2), rng.uniform(-4, 4)])
    trunk = trunk + smooth_noise(rng, T, fps, 0.25, 3) * [0.8, 0.6, 1.5]
    head = np.array([head_turn_deg, rng.uniform(-5, 10), rng.uniform(-3, 3)])
    head = head + smooth_noise(rng, T, fps, 0.3, 3) * [3.0, 2.0, 1.0]
    pelvis = smooth_noise(rng, T, fps, 0.2, 3) * [0.012, 0.015, 0.002]
    knees = np.clip(rng.uniform(0, 8) + smooth_noise(rng, T, fps, 0.2)[:, 0], 0, None)
    posture = Posture(right, left, pelvis, trunk, head, knees)
    return Performance(posture, np.asarray(labels, dtype=object), fps, list(steps), segments)
