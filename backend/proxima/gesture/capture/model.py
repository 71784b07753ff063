"""`CaptureModel`: what a drone camera and the live pose path do to landmark sequences.

Input is MediaPipe's 33 landmarks in normalised image coordinates (x by the width, y by
the height, z in x's scale) with visibility, as recorded (the LASER clips: near eye
level, 30 fps, smoothed). Output is what the live engine's window would hold for the
same motion seen by a drone camera. The effects, in the order applied:

1. Frame rate, dropped frames and gaps (`fps`, `drop_rate`, `gap_rate_hz`, `gap_s`):
   camera frames at `fps`, sampled from the 30 fps source by linear interpolation; the
   lost ones removed. The engine's `PoseWindow` holds the last 60 poses received,
   whatever their times, and restarts after a pause over `max_gap_s`; so the output is
   the received poses in order (at 10 fps a 60-pose window spans 6 s). Training windows
   hold pauses up to `TRAIN_MAX_GAP_S` only, the live window bridges up to `MAX_GAP_S`.
2. Distance (`person_height`): the person scaled about the image centre (where a
   camera's optical axis meets the image) to that height, a fraction of the frame.
3. Camera elevation and yaw (`elevation_deg`, `yaw_deg`): the body turned about its
   hips in the metric frame (x * aspect, y, z * aspect * Z_SCALE, geometry.to_metric),
   first about the vertical axis (yaw, random sign; only where the data has depth), then
   about the camera's horizontal axis (a camera above the eye line looking down: the
   head comes nearer, the torso looks shorter by cos(elevation)), and projected back
   (weak perspective: no size change with depth).
4. Roll (`roll_deg`, random sign): the image turned about its centre in the metric frame.
5. Landmarks lost (`loss_rate`, `loss_parts`, `loss_modes`, `loss_s`, `loss_cut`): for
   `loss_s` seconds, the legs or one arm leave the frame (`frame`: the camera drifts, the
   person moves in the image, with 0.3 s ramps, until the edge cuts the part at
   `loss_cut` of its length) or are hidden in place (`hidden`: visibility set to what
   MediaPipe reports for absent parts).
6. Visibility as MediaPipe would report it: every landmark's visibility scaled by the
   measured edge curve for its new distance to the frame edge over the one for its
   old; then the measured frame-to-frame visibility noise (`visibility_noise`).
7. Jitter (`jitter`, `jitter_corr`): per landmark and frame, Gaussian, std = `jitter` x
   the measured std for the person's height and the landmark's visibility, in torso
   lengths (x and y alike in the metric frame; z `Z_OVER_XY` times more), AR(1) in
   camera frames with lag-1 correlation `jitter_corr`.

Landmarks with visibility exactly 0 are ones the data set does not have (UAV-Gesture's
16 missing points, OpenPose misses): they are left as they are.

Two ways in: `apply_sequence` / `apply_clip` for whole recordings before windowing
(stitched evaluation streams), `apply_windows` for a batch of training windows (fixed
shape in and out; vectorised).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from proxima.gesture.capture import measured
from proxima.gesture.geometry import Z_SCALE
from proxima.gesture.skeleton import L_HIP, L_SHOULDER, R_HIP, R_SHOULDER

if TYPE_CHECKING:
    from proxima.gesture.clip import Clip

SOURCE_FPS = 30.0
# EngineSettings.max_gap_s: a longer pause restarts the live window (and empties the
# decision rule). Field cameras lose the operator for 0.1-0.5 s every 10 s or so; a
# restart then costs the window's refill and the gathered evidence (docs/experiments.md,
# thirty-first session).
MAX_GAP_S = 0.6
# The longest pause inside a training window: windows bridging up to MAX_GAP_S trained
# no better (same log), so the recipe keeps the pauses it was measured with.
TRAIN_MAX_GAP_S = 0.25
RAMP_S = 0.3  # a `frame` loss drifts in and out over this long
PARTS: dict[str, tuple[int, ...]] = {
    "legs": (25, 26, 27, 28, 29, 30, 31, 32),  # knees, ankles, heels, feet
    "left_arm": (13, 15, 17, 19, 21),  # elbow, wrist, hand points
    "right_arm": (14, 16, 18, 20, 22),
}
LOSS_MODES = ("frame", "hidden")
_HIP_BY_PART = {"legs": (23, 24), "left_arm": (11,), "right_arm": (12,)}

Span = float | tuple[float, float]


class CaptureError(ValueError):
    """A capture parameter or an input array is unusable; the message says which."""


def _span(name: str, value: Span, lo: float, hi: float) -> tuple[float, float]:
    """A scalar or (low, high) pair checked against the documented range [lo, hi]."""
    if isinstance(value, int | float | np.integer | np.floating):
        pair = (float(value), float(value))
    else:
        try:
            a, b = value
            pair = (float(a), float(b))
        except (TypeError, ValueError):
            raise CaptureError(f"{name}: expected a number or (low, high), got {value!r}") from None
    if not all(math.isfinite(v) for v in pair):
        raise CaptureError(f"{name}: {value!r} is not finite")
    if pair[0] > pair[1]:
        raise CaptureError(f"{name}: low {pair[0]} is above high {pair[1]}")
    if pair[0] < lo or pair[1] > hi:
        raise CaptureError(f"{name}: {value!r} is outside the allowed range {lo}..{hi}")
    return pair


def _number(name: str, value: float, lo: float, hi: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise CaptureError(f"{name}: expected a number, got {value!r}") from None
    if not (lo <= v <= hi):
        raise CaptureError(f"{name}: {value!r} is outside the allowed range {lo}..{hi}")
    return v


@dataclass(frozen=True)
class Captured:
    """A captured recording: the poses the engine receives, in order.

    `t` (F,) seconds; `frames` (F,) 1-based camera frame numbers at `fps`, so
    `t == (frames - 1) / fps` (the replay source's clock); `xyz` (F, 33, 3) normalised;
    `visibility` (F, 33)."""

    t: np.ndarray
    frames: np.ndarray
    xyz: np.ndarray
    visibility: np.ndarray
    fps: float

    def __len__(self) -> int:
        return len(self.t)


@dataclass(frozen=True)
class CaptureModel:
    """The effects and their strengths; see the module docstring for what each does.

    Spans are a number or (low, high): each sequence draws its value uniformly from the
    span; angles are magnitudes with a random sign except the elevation. The defaults are
    the measured live pose path on a LASER-like shot: jitter and visibility noise as
    measured, the person as recorded, no camera motion, 30 fps, nothing lost.

    Raises:
        CaptureError: (constructor) a value outside its documented range.
    """

    jitter: float = 1.0  # x the measured live-path jitter; 0..8
    jitter_corr: float = measured.JITTER_CORR  # lag-1, camera frames; 0..0.95
    visibility_noise: float = 1.0  # x the measured visibility noise; 0..4
    person_height: Span | None = None  # fraction of the frame height; 0.1..1.0; None: as is
    elevation_deg: Span = 0.0  # camera above the eye line, looking down; 0..45
    yaw_deg: Span = 0.0  # magnitude; only with depth; 0..60
    roll_deg: Span = 0.0  # magnitude; 0..15
    fps: Span = SOURCE_FPS  # camera frame rate; 10..30
    drop_rate: float = 0.0  # share of camera frames lost at random; 0..0.5
    gap_rate_hz: float = 0.0  # runs of lost frames per second; 0..2
    gap_s: Span = (0.1, 0.5)  # their length; 1/30..5 s (windows: at most max_gap_s)
    loss_rate: float = 0.0  # share of sequences with a lost part; 0..1
    loss_parts: tuple[str, ...] = tuple(PARTS)
    loss_modes: tuple[str, ...] = LOSS_MODES
    loss_s: Span = (1.0, 4.0)  # how long; 0.1..60 s
    loss_cut: Span = (0.2, 0.9)  # `frame`: where the edge cuts the part (0 root, 1 tip)

    def __post_init__(self) -> None:
        def put(name: str, value: object) -> None:
            object.__setattr__(self, name, value)

        put("jitter", _number("jitter", self.jitter, 0.0, 8.0))
        put("jitter_corr", _number("jitter_corr", self.jitter_corr, 0.0, 0.95))
        put("visibility_noise", _number("visibility_noise", self.visibility_noise, 0.0, 4.0))
        if self.person_height is not None:
            put("person_height", _span("person_height", self.person_height, 0.1, 1.0))
        put("elevation_deg", _span("elevation_deg", self.elevation_deg, 0.0, 45.0))
        put("yaw_deg", _span("yaw_deg", self.yaw_deg, 0.0, 60.0))
        put("roll_deg", _span("roll_deg", self.roll_deg, 0.0, 15.0))
        put("fps", _span("fps", self.fps, 10.0, SOURCE_FPS))
        put("drop_rate", _number("drop_rate", self.drop_rate, 0.0, 0.5))
        put("gap_rate_hz", _number("gap_rate_hz", self.gap_rate_hz, 0.0, 2.0))
        put("gap_s", _span("gap_s", self.gap_s, 1 / SOURCE_FPS, 5.0))
        put("loss_rate", _number("loss_rate", self.loss_rate, 0.0, 1.0))
        put("loss_s", _span("loss_s", self.loss_s, 0.1, 60.0))
        put("loss_cut", _span("loss_cut", self.loss_cut, 0.0, 1.0))
        parts, modes = tuple(self.loss_parts), tuple(self.loss_modes)
        bad = [p for p in parts if p not in PARTS]
        if bad or not parts:
            raise CaptureError(f"loss_parts: {bad or parts!r}; choose from {sorted(PARTS)}")
        bad = [m for m in modes if m not in LOSS_MODES]
        if bad or not modes:
            raise CaptureError(f"loss_modes: {bad or modes!r}; choose from {list(LOSS_MODES)}")
        put("loss_parts", parts)
        put("loss_modes", modes)

    def _s(self, name: str) -> tuple[float, float]:
        return cast(tuple[float, float], getattr(self, name))

    def describe(self) -> dict[str, Any]:
        """The parameters as a JSON-ready dict."""
        return {f.name: _jsonable(getattr(self, f.name)) for f in fields(self)}

    @property
    def timing(self) -> bool:
        """Whether frames are lost or resampled (fps below 30, drops or gaps)."""
        return self._s("fps")[0] < SOURCE_FPS or self.drop_rate > 0 or self.gap_rate_hz > 0

    def source_frames(self, window: int) -> int:
        """Source rows (30 fps) a window batch needs so that `window` received poses fit
        at the lowest frame rate with the expected losses and a 20% margin."""
        if not self.timing:
            return window
        longest = min(self._s("gap_s")[1], TRAIN_MAX_GAP_S)
        kept = 1.0 - self.drop_rate - self.gap_rate_hz * longest
        span = (window - 1) * SOURCE_FPS / self._s("fps")[0] / max(kept, 0.2)
        return math.ceil(1.2 * span) + 1

    # --- whole recordings ---------------------------------------------------------------

    def apply_clip(self, clip: Clip, rng: np.random.Generator) -> Captured:
        """`apply_sequence` on a clip, its rows at (frame - 1) / 30 s."""
        t = (np.asarray(clip.frames, np.float64) - 1.0) / SOURCE_FPS
        return self.apply_sequence(
            t, clip.xyz, clip.visibility, rng, aspect=clip.aspect, has_z=clip.has_z
        )

    def apply_sequence(
        self,
        t: np.ndarray,
        xyz: np.ndarray,
        visibility: np.ndarray,
        rng: np.random.Generator,
        *,
        aspect: float = 16 / 9,
        has_z: bool = True,
    ) -> Captured:
        """One recording (rows at times `t`, seconds, increasing; 30 fps with gaps where
        nobody was detected) as the camera and pose path would deliver it.

        Camera frames fall at k / fps; a frame whose time lies between two source rows
        more than one frame apart (nobody detected there) has no pose. Gaps of any length
        are kept (the engine restarts its window after `MAX_GAP_S`).

        Raises:
            CaptureError: arrays of the wrong shape, or times not increasing.
        """
        t = np.asarray(t, np.float64)
        xyz, visibility = _check(np.asarray(xyz)[None], np.asarray(visibility)[None], "sequence")
        xyz, visibility = xyz[0], visibility[0]
        if t.shape != (len(xyz),):
            raise CaptureError(f"t: expected shape ({len(xyz)},), got {t.shape}")
        if len(t) < 2 or np.any(np.diff(t) <= 0):
            raise CaptureError("t: need at least two rows with increasing times")
        fps = float(rng.uniform(*self._s("fps")))
        k = np.arange(math.ceil(t[0] * fps - 1e-9), math.floor(t[-1] * fps + 1e-9) + 1)
        tau = k / fps
        pos = np.interp(tau, t, np.arange(len(t)))
        lo = np.clip(np.floor(pos + 1e-9).astype(np.int64), 0, len(t) - 1)
        hi = np.minimum(lo + 1, len(t) - 1)
        frac = np.where(hi > lo, pos - lo, 0.0)
        exact = frac < 1e-6
        present = exact | (t[hi] - t[lo] <= 1.5 / SOURCE_FPS)
        lost = self._lost(rng, tau[None], 1, max_gap=None)[0]
        keep = present & ~lost
        k, tau, lo, hi, frac = k[keep], tau[keep], lo[keep], hi[keep], frac[keep]
        f3 = frac[:, None, None]
        xs = xyz[lo] * (1 - f3) + xyz[hi] * f3
        vs = visibility[lo] * (1 - frac[:, None]) + visibility[hi] * frac[:, None]
        out_x, out_v = self._effects(
            xs[None], vs[None], tau[None], k[None].astype(np.float64), rng,
            np.array([aspect], np.float64), np.array([has_z]),
        )  # fmt: skip
        return Captured(tau, k + 1, out_x[0].astype(np.float32), out_v[0].astype(np.float32), fps)

    # --- training windows ---------------------------------------------------------------

    def apply_windows(
        self,
        xyz: np.ndarray,
        visibility: np.ndarray,
        rng: np.random.Generator,
        *,
        aspect: float | np.ndarray = 16 / 9,
        has_z: bool | np.ndarray = True,
        window: int | None = None,
        max_gap_s: float = TRAIN_MAX_GAP_S,
        with_times: bool = False,
    ) -> tuple[np.ndarray, ...]:
        """A batch of source windows (N, S, 33, 3) and (N, S, 33), rows 1/30 s apart, as
        the engine's window would hold them at the end of each: (N, W, 33, 3), (N, W, 33)
        with W = `window` (default S).

        With frame-rate or loss effects (`timing`) the last W poses received span more
        than W source rows: S must be at least `source_frames(W)`. Gaps are at most
        `max_gap_s` (default `TRAIN_MAX_GAP_S`, within the live window's `MAX_GAP_S`).
        In the rare draw where fewer than W frames survive, the oldest losses are undone.
        With `with_times`, also each received pose's time (N, W) in seconds (source
        row / 30), for a filter that runs over the window.

        Raises:
            CaptureError: bad shapes, or S too short for W at this model's frame rates.
        """
        xyz, visibility = _check(xyz, visibility, "windows")
        n, s = xyz.shape[:2]
        w = s if window is None else int(window)
        if w < 2 or w > s:
            raise CaptureError(f"window: {window} must be 2..{s} (the source window length)")
        try:
            a = np.broadcast_to(np.asarray(aspect, np.float64), (n,)).copy()
            z = np.broadcast_to(np.asarray(has_z, bool), (n,)).copy()
        except ValueError:
            raise CaptureError(
                f"windows: aspect and has_z must be scalars or one per window ({n})"
            ) from None
        if not self.timing:
            rows = np.broadcast_to(np.arange(s - w, s, dtype=np.float64), (n, w))
            xs, vs = xyz[:, s - w :], visibility[:, s - w :]
            k = rows.copy()
        else:
            need = self.source_frames(w)
            if s < need:
                raise CaptureError(
                    f"windows: {s} source frames are too few for {w} poses at "
                    f"{self._s('fps')[0]:g} fps with these losses; cut {need}"
                )
            rows, k = self._received_rows(rng, n, s, w, max_gap_s)
            lo = np.floor(rows + 1e-9).astype(np.int64)
            hi = np.minimum(lo + 1, s - 1)
            frac = rows - lo
            idx = np.arange(n)[:, None]
            f3 = frac[..., None, None]
            xs = xyz[idx, lo] * (1 - f3) + xyz[idx, hi] * f3
            vs = visibility[idx, lo] * (1 - frac[..., None]) + visibility[idx, hi] * frac[..., None]
        tau = rows / SOURCE_FPS
        out_x, out_v = self._effects(xs, vs, tau, k, rng, a, z)
        if with_times:
            return out_x.astype(np.float32), out_v.astype(np.float32), np.array(tau)
        return out_x.astype(np.float32), out_v.astype(np.float32)

    def _received_rows(
        self, rng: np.random.Generator, n: int, s: int, w: int, max_gap_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Source row positions (N, W) of the last W camera frames received before each
        window's end, oldest first, and their camera frame numbers (negative: counted
        back from the last)."""
        fps = rng.uniform(*self._s("fps"), size=n)
        t_end = (s - 1) / SOURCE_FPS
        m = math.floor(t_end * self._s("fps")[1] + 1e-9) + 1
        j = np.arange(m)[None, :]
        tau = t_end - j / fps[:, None]  # (N, M), newest first
        valid = tau >= -1e-9
        lost = self._lost(rng, tau, n, max_gap=max_gap_s) & valid
        # A run of losses never makes a pause over max_gap_s. Walking back from the
        # newest frame, a lost frame is kept when dropping it too would make the pause
        # from the last kept frame to the next candidate longer than that.
        last = tau[:, 0].copy()
        for col in range(1, m - 1):
            restore = lost[:, col] & (last - tau[:, col + 1] > max_gap_s + 1e-9)
            lost[:, col] &= ~restore
            last = np.where(lost[:, col], last, tau[:, col])
        kept = valid & ~lost
        short = w - kept.sum(axis=1)
        # Undo the oldest losses where fewer than W frames survived.
        back = np.cumsum(lost[:, ::-1], axis=1)[:, ::-1]
        kept |= lost & (back <= short[:, None])
        sel = kept & (np.cumsum(kept, axis=1) <= w)
        rows_j = np.nonzero(sel)[1].reshape(n, w)[:, ::-1]  # oldest first
        tau_sel = np.take_along_axis(tau, rows_j, axis=1)
        rows = np.clip(tau_sel * SOURCE_FPS, 0.0, s - 1.0)
        return rows, -rows_j.astype(np.float64)

    def _lost(
        self, rng: np.random.Generator, tau: np.ndarray, n: int, max_gap: float | None
    ) -> np.ndarray:
        """(N, M) camera frames at times `tau` lost to random drops or gaps."""
        lost = rng.random(tau.shape) < self.drop_rate
        if self.gap_rate_hz <= 0:
            return lost
        t0, t1 = np.nanmin(tau, axis=1), np.nanmax(tau, axis=1)
        count = rng.poisson(self.gap_rate_hz * (t1 - t0 + self._s("gap_s")[1]))
        kmax = int(count.max()) if len(count) else 0
        if kmax == 0:
            return lost
        lo_g, hi_g = self._s("gap_s")
        if max_gap is not None:
            lo_g, hi_g = min(lo_g, max_gap), min(hi_g, max_gap)
        start = rng.uniform(0, 1, (n, kmax)) * (t1 - t0 + hi_g)[:, None] + (t0 - hi_g)[:, None]
        length = rng.uniform(lo_g, hi_g, (n, kmax))
        on = np.arange(kmax)[None, :] < count[:, None]
        t = tau[:, :, None]
        inside = (t >= start[:, None, :]) & (t < (start + length)[:, None, :]) & on[:, None, :]
        return lost | inside.any(axis=2)

    # --- the effects on received frames ---------------------------------------------------

    def _effects(
        self,
        xyz: np.ndarray,
        vis: np.ndarray,
        tau: np.ndarray,
        k: np.ndarray,
        rng: np.random.Generator,
        aspect: np.ndarray,
        has_z: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Effects 2-7 on sequences (N, T, 33, 3) and (N, T, 33) at times `tau` (N, T),
        camera frame numbers `k` (N, T)."""
        n = len(xyz)
        present = vis > 0
        # float32 throughout: this runs inside training augmentation.
        scale = np.stack([aspect, np.ones(n), aspect * Z_SCALE], axis=1).astype(np.float32)
        scale = scale[:, None, None, :]
        m = xyz.astype(np.float32) * scale  # metric: image-height units
        torso0 = _torso(m)  # (N,)
        moves = (
            self.person_height is not None
            or self._s("elevation_deg")[1] > 0
            or (self._s("yaw_deg")[1] > 0 and bool(has_z.any()))
            or self._s("roll_deg")[1] > 0
            or self.loss_rate > 0
        )
        d_src = _edge_distance(m, aspect) / torso0[:, None, None] if moves else None
        centre = np.stack([aspect / 2, np.full(n, 0.5), np.zeros(n)], axis=1)[:, None, None, :]

        factor = np.ones(n)
        if self.person_height is not None:
            factor = rng.uniform(*self._s("person_height"), size=n) / (
                measured.STATURE_TORSO * torso0
            )
            m = centre + factor[:, None, None, None] * (m - centre)
        torso = torso0 * factor
        height = measured.STATURE_TORSO * torso

        elev = np.deg2rad(rng.uniform(*self._s("elevation_deg"), size=n))
        yaw = np.deg2rad(_signed(rng, self._s("yaw_deg"), n)) * has_z
        if np.any(elev) or np.any(yaw):
            # MediaPipe's z leans an upright torso towards the camera (LASER front view:
            # shoulders 0.6 torso lengths nearer than the hips): a bias, not a pose.
            # Turn the body with that lean taken out, then put it back.
            lean = _lean(m)[:, None, None]
            m[..., 2] -= lean * (m[..., 1] - _hips(m)[..., 1])
            pivot = _hips(m).mean(axis=1, keepdims=True)  # (N, 1, 1, 3)
            rot = (_rx(elev) @ _ry(yaw)).astype(np.float32)
            m = (m - pivot) @ rot.transpose(0, 2, 1)[:, None] + pivot
            m[..., 2] += lean * (m[..., 1] - _hips(m)[..., 1])
            m[..., 2] = np.where(has_z[:, None, None], m[..., 2], 0.0)
        roll = np.deg2rad(_signed(rng, self._s("roll_deg"), n))
        if np.any(roll):
            c, s = np.cos(roll)[:, None, None], np.sin(roll)[:, None, None]
            x, y = m[..., 0] - centre[..., 0], m[..., 1] - centre[..., 1]
            m[..., 0] = centre[..., 0] + c * x - s * y
            m[..., 1] = centre[..., 1] + s * x + c * y

        vis = vis.astype(np.float32)
        if self.loss_rate > 0:
            m, vis = self._loss(m, vis, tau, rng, aspect)
        if d_src is not None:  # landmarks moved: visibility follows the edge curve
            d_new = _edge_distance(m, aspect) / torso[:, None, None]
            edge = measured.edge_factor(d_new) / measured.edge_factor(d_src)
            vis = np.clip(vis * edge, 0.0, 1.0).astype(np.float32)

        if self.jitter > 0:
            sd = (self.jitter * measured.jitter_torso(height) * torso)[:, None, None]
            sd = sd * measured.visibility_factor(vis)  # (N, T, 33)
            e = _ar1(rng.standard_normal(m.shape, dtype=np.float32), k, self.jitter_corr)
            m[..., :2] += sd[..., None] * e[..., :2]
            m[..., 2] += np.where(has_z[:, None, None], measured.Z_OVER_XY * sd * e[..., 2], 0.0)
        if self.visibility_noise > 0:
            noise = self.visibility_noise * measured.visibility_noise_sd(vis)
            draw = rng.standard_normal(vis.shape, dtype=np.float32)
            vis = np.clip(vis + noise * draw, 0.0, 1.0).astype(np.float32)

        out = m / scale
        if not present.all():  # points the data set does not have stay as they were
            keep = ~present
            out[keep] = xyz[keep]
            vis[keep] = 0.0
        return out, vis

    def _loss(
        self,
        m: np.ndarray,
        vis: np.ndarray,
        tau: np.ndarray,
        rng: np.random.Generator,
        aspect: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Effect 5 (metric coordinates): for the sequences drawn, one part leaves the
        frame or is hidden for `loss_s` seconds."""
        n = len(m)
        hit = rng.random(n) < self.loss_rate
        part_i = rng.integers(len(self.loss_parts), size=n)
        mode_i = rng.integers(len(self.loss_modes), size=n)
        length = rng.uniform(*self._s("loss_s"), size=n)
        t0, t1 = tau.min(axis=1), tau.max(axis=1)
        middle = t0 + rng.random(n) * (t1 - t0)
        start, end = middle - length / 2, middle + length / 2
        cut = rng.uniform(*self._s("loss_cut"), size=n)
        level = rng.uniform(*measured.ABSENT_VISIBILITY, size=n)
        ramp = np.clip(np.minimum(tau - start[:, None], end[:, None] - tau) / RAMP_S, 0, 1)
        ramp = ramp * ramp * (3 - 2 * ramp)  # smoothstep: the drift starts and ends gently
        active = (tau >= start[:, None]) & (tau <= end[:, None])  # (N, T)
        m, vis = m.copy(), vis.copy()
        for p_i, part in enumerate(self.loss_parts):
            idx = list(PARTS[part])
            roots = list(_HIP_BY_PART[part])
            for mode_k, mode in enumerate(self.loss_modes):
                sel = hit & (part_i == p_i) & (mode_i == mode_k)
                if not sel.any():
                    continue
                if mode == "hidden":
                    low = np.minimum(vis[sel][:, :, idx], level[sel][:, None, None])
                    cur = vis[sel]
                    cur[:, :, idx] = np.where(active[sel][:, :, None], low, cur[:, :, idx])
                    vis[sel] = cur
                    continue
                ms = m[sel]
                root = ms[:, :, roots, :].mean(axis=2)  # (n', T, 3)
                if part == "legs":
                    tip = np.median(ms[:, :, [27, 28], 1].mean(axis=2), axis=1)
                    base = np.median(root[:, :, 1], axis=1)
                    edge_at = base + cut[sel] * (tip - base)
                    shift = np.maximum(1.0 - edge_at, 0.0)  # move down: the edge cuts there
                    ms[..., 1] += (ramp[sel] * shift[:, None])[:, :, None]
                else:
                    reach = ms[:, :, idx, 0] - root[:, :, None, 0]  # (n', T, J)
                    far = reach.reshape(len(ms), -1)
                    pick = np.abs(far).argmax(axis=1)
                    extreme = far[np.arange(len(ms)), pick]
                    base = np.median(root[:, :, 0], axis=1)
                    edge_at = base + cut[sel] * extreme
                    width = aspect[sel]
                    shift = np.where(
                        extreme > 0, np.maximum(width - edge_at, 0), -np.maximum(edge_at, 0)
                    )
                    ms[..., 0] += (ramp[sel] * shift[:, None])[:, :, None]
                m[sel] = ms
        return m, vis


def _jsonable(value: object) -> object:
    if isinstance(value, tuple):
        return list(value)
    return value


def _check(xyz: np.ndarray, vis: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    xyz, vis = np.asarray(xyz), np.asarray(vis)
    if xyz.ndim != 4 or xyz.shape[2:] != (33, 3):
        raise CaptureError(f"{what}: xyz must be (..., T, 33, 3), got {xyz.shape}")
    if vis.shape != xyz.shape[:3]:
        raise CaptureError(f"{what}: visibility must be {xyz.shape[:3]}, got {vis.shape}")
    if not (np.all(np.isfinite(xyz)) and np.all(np.isfinite(vis))):
        raise CaptureError(f"{what}: xyz or visibility holds NaN or infinity")
    return xyz, vis


def _signed(rng: np.random.Generator, span: tuple[float, float], n: int) -> np.ndarray:
    return rng.uniform(*span, size=n) * rng.choice((-1.0, 1.0), size=n)


def _hips(m: np.ndarray) -> np.ndarray:
    return (m[..., L_HIP : L_HIP + 1, :] + m[..., R_HIP : R_HIP + 1, :]) / 2


def _lean(m: np.ndarray) -> np.ndarray:
    """(N,) dz/dy of the torso (shoulder midpoint minus hip midpoint), median over time:
    how far MediaPipe's z leans the upper body towards the camera per unit of height."""
    d = (m[..., L_SHOULDER, :] + m[..., R_SHOULDER, :] - m[..., L_HIP, :] - m[..., R_HIP, :]) / 2
    dy = np.where(np.abs(d[..., 1]) > 1e-4, d[..., 1], -1e-4)
    return np.median(d[..., 2] / dy, axis=1)


def _torso(m: np.ndarray) -> np.ndarray:
    """(N,) median torso length (x, y) of metric sequences (N, T, 33, 3)."""
    d = (
        m[..., L_SHOULDER, :2] + m[..., R_SHOULDER, :2] - m[..., L_HIP, :2] - m[..., R_HIP, :2]
    ) / 2
    return np.maximum(np.median(np.linalg.norm(d, axis=-1), axis=1), 1e-3)


def _edge_distance(m: np.ndarray, aspect: np.ndarray) -> np.ndarray:
    """(N, T, 33) signed distance to the nearest frame edge (metric), positive outside."""
    width = aspect[:, None, None]
    x, y = m[..., 0], m[..., 1]
    return np.maximum(np.maximum(x - width, -x), np.maximum(y - 1.0, -y))


def _rx(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(angle), np.zeros_like(angle)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1),
                     np.stack([z, s, c], -1)], -2)  # fmt: skip


def _ry(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(angle), np.zeros_like(angle)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1),
                     np.stack([-s, z, c], -1)], -2)  # fmt: skip


def _ar1(e: np.ndarray, k: np.ndarray, rho: float) -> np.ndarray:
    """Unit-variance AR(1) noise along axis 1 from white noise `e` (N, T, ...), with
    correlation rho ** (frames apart) between received frames `k` (N, T)."""
    if rho <= 0:
        return e
    out = e.copy()
    gap = np.diff(k, axis=1)  # (N, T-1) camera frames between received ones
    r = rho ** np.maximum(gap, 1.0)
    r = r.reshape(*r.shape, *([1] * (e.ndim - 2)))
    q = np.sqrt(1 - r * r)
    for i in range(1, e.shape[1]):
        out[:, i] = r[:, i - 1] * out[:, i - 1] + q[:, i - 1] * e[:, i]
    return out
