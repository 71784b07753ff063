"""Landmark jitter of the live pose path on a person who does not move.

The live path is MediaPipe's Tasks PoseLandmarker in VIDEO mode (`proxima.pose.
PoseEstimator`, the live default of 2 poses) followed by the operator tracker's One Euro
filter (`OperatorTracker`, its defaults). Its input here: still photos of a person
(matplotlib's grace_hopper.jpg, scikit-image's astronaut.png) placed at the centre of a
grey 1280x720 (16:9) frame at several sizes, and every frame gets what a real sensor
adds to a still scene: Gaussian sensor noise (`--noise` grey levels in each colour
channel) and a sub-pixel shift (uniform +-0.5 px in x and y, by bilinear resampling).
The known shift is subtracted from the landmarks, so what is left is the estimator's
own jitter.

Person size is the person's height as a fraction of the frame height, defined through
the torso as the estimator sees it: height = STATURE_TORSO x torso length (shoulder
midpoint to hip midpoint, median over the run; 2.65, from the LASER front view by
`python -m bench.capture_constants`). The photos show the upper body only; at these
scales MediaPipe reads each as a small whole person (hips inside the photo, visibility
near 1, legs guessed at low visibility), so the torso is the scale the estimator itself
works at. The photo scales (PHOTO_SCALES) put that person at about 12-90% of the frame
height; the height reached is measured, not assumed.

Two protocols per photo: `fresh`, a new stream per scale (the estimator must find the
person, as when a drone first sees its operator), and `tracked`, one stream through
all the scales from the largest down (the person walks away while tracked).

Reported per run (`--frames` frames at 30 fps, the first WARMUP left out): per landmark
and axis, the jitter (standard deviation about the run's mean, in normalised image
units and in torso lengths in a metric frame where x and y share one scale), the
frame-to-frame step RMS, the lag-1..3 autocorrelation, the mean visibility and its
frame-to-frame step, before and after the tracker's One Euro filter; then pooled: the
visible landmarks' jitter against size and every landmark's against visibility, with
fits, which `proxima.gesture.capture` uses.

    python -m bench.pose_jitter [--frames 150] [--noise 4] [--reanalyse]

Writes bench/results/pose_jitter.json and pose_jitter.png. MediaPipe is heavy: run one
at a time (`taskset -c 0` keeps it on one core).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from proxima.gesture.capture.measured import STATURE_TORSO
from proxima.gesture.geometry import Z_SCALE

RESULTS = Path(__file__).resolve().parent / "results"
WIDTH, HEIGHT = 1280, 720
ASPECT = WIDTH / HEIGHT
FPS = 30.0
# Photo scales: the person from about 15% to 90% of the frame height as the estimator
# sees it. Grace Hopper's photo above 0.7 makes MediaPipe place the hips far below the
# photo (visibility near 0), so its torso, hence its size, means nothing there.
PHOTO_SCALES = {
    "grace_hopper": (0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.6, 0.7),
    "astronaut": (0.3, 0.4, 0.5, 0.6, 0.7, 0.85, 1.0, 1.2, 1.4),
}
TRANSITION = 10  # frames of zoom between two held scales
REF_HEIGHT = 0.6  # about the LASER operators' height in their frames
VISIBLE = 0.8  # "visible landmark" for the size figures
VIS_BINS = (0.0, 0.1, 0.3, 0.5, 0.8, 0.95, 1.0001)
WARMUP = 10  # frames the One Euro filter (and VIDEO-mode tracking) settle in
BACKGROUND = 110  # grey level of the frame around the photo


def load_photo(name: str) -> np.ndarray:
    """A BGR photo of a person from a pip package (no download)."""
    if name == "grace_hopper":
        import matplotlib.cbook as cbook

        path = cbook.get_sample_data("grace_hopper.jpg", asfileobj=False)
        image = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if image is None:
            raise FileNotFoundError(f"cannot read matplotlib's sample photo {path}")
        return np.asarray(image)
    if name == "astronaut":
        from skimage.data import astronaut

        return np.ascontiguousarray(astronaut()[:, :, ::-1])
    raise ValueError(f"unknown photo {name!r}")


def compose(photo: np.ndarray, scale: float) -> np.ndarray:
    """The photo resized by `scale`, pasted at the centre of a grey 1280x720 frame
    (cropped to the frame if larger)."""
    p = cv2.resize(photo, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    frame = np.full((HEIGHT, WIDTH, 3), BACKGROUND, np.uint8)
    h, w = p.shape[:2]
    y0, x0 = (HEIGHT - h) // 2, (WIDTH - w) // 2
    fy0, fx0 = max(y0, 0), max(x0, 0)
    py0, px0 = fy0 - y0, fx0 - x0
    hh, ww = min(h - py0, HEIGHT - fy0), min(w - px0, WIDTH - fx0)
    frame[fy0 : fy0 + hh, fx0 : fx0 + ww] = p[py0 : py0 + hh, px0 : px0 + ww]
    return frame


def perturb(frame: np.ndarray, dx: float, dy: float, noise: float) -> np.ndarray:
    """`frame` shifted by (dx, dy) pixels (bilinear) plus Gaussian noise of `noise` grey
    levels, independent in each colour channel (cv2's RNG, seeded by the caller)."""
    m = np.array([[1, 0, dx], [0, 1, dy]], np.float32)
    shifted = cv2.warpAffine(frame, m, (WIDTH, HEIGHT), flags=cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_REPLICATE)  # fmt: skip
    if noise <= 0:
        return shifted
    n = np.empty(frame.shape, np.int16)
    cv2.randn(n, np.zeros(3), np.full(3, noise))  # one Scalar per channel
    return np.clip(shifted.astype(np.int16) + n, 0, 255).astype(np.uint8)


def torso_metric(xyz: np.ndarray) -> np.ndarray:
    """Torso length (shoulder midpoint to hip midpoint, x and y) of normalised landmarks
    (..., 33, 3) in units of the frame height."""
    sh = (xyz[..., 11, :2] + xyz[..., 12, :2]) / 2
    hp = (xyz[..., 23, :2] + xyz[..., 24, :2]) / 2
    d = sh - hp
    return np.hypot(d[..., 0] * ASPECT, d[..., 1])


def run_stream(photo: np.ndarray, scales: np.ndarray, noise: float, seed: int,
               num_poses: int) -> dict[str, np.ndarray]:  # fmt: skip
    """One video stream of the photo, frame k at `scales[k]`, through a fresh
    `PoseEstimator` (VIDEO mode, 30 fps timestamps) and `OperatorTracker`: the raw and
    filtered landmarks (known shift removed; NaN where nobody was found), visibility, and
    which frames had the operator."""
    from proxima.pose import OperatorTracker, PoseEstimator

    rng = np.random.default_rng(seed)
    cv2.setRNGSeed(seed)
    tracker = OperatorTracker()
    n = len(scales)
    raw, filt = np.full((n, 33, 3), np.nan), np.full((n, 33, 3), np.nan)
    vis, found = np.full((n, 33), np.nan), np.zeros(n, bool)
    base, base_scale = compose(photo, float(scales[0])), scales[0]
    with PoseEstimator(num_poses=num_poses) as est:
        for k, scale in enumerate(scales):
            if scale != base_scale:
                base, base_scale = compose(photo, float(scale)), scale
            dx, dy = rng.uniform(-0.5, 0.5, size=2)
            t = k / FPS
            poses = est.estimate(perturb(base, dx, dy, noise), t)
            for p in poses:  # the shift is known: remove it (also before the filter)
                p.xyz[:, 0] -= dx / WIDTH
                p.xyz[:, 1] -= dy / HEIGHT
            pose = tracker.update(poses, t)
            if pose is None:
                continue
            # The tracker's pose shares the chosen detection's visibility array.
            i = next(j for j, q in enumerate(poses) if q.visibility is pose.visibility)
            raw[k], filt[k], vis[k], found[k] = poses[i].xyz, pose.xyz, pose.visibility, True
    return {"raw": raw, "filtered": filt, "vis": vis, "found": found}


def autocorr(dev: np.ndarray, lag: int) -> float:
    """Pooled lag-`lag` autocorrelation of deviations (T, ...) over all trailing axes."""
    a, b = dev[:-lag].ravel(), dev[lag:].ravel()
    return float(np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b)))


def jitter_stats(xyz: np.ndarray, torso: float) -> dict[str, Any]:
    """Per-landmark jitter of landmarks (T, 33, 3) of a still person: std about the mean
    and frame-to-frame step RMS per axis, normalised units (x, y, z as MediaPipe gives
    them) and metric units relative to `torso` (x * aspect, y, z * aspect * Z_SCALE;
    'xy' is the RMS of x and y), and the autocorrelation of the x/y jitter."""
    metric = xyz * np.array([ASPECT, 1.0, ASPECT * Z_SCALE])
    dev_n = xyz - xyz.mean(axis=0)
    dev_m = metric - metric.mean(axis=0)
    step_m = np.diff(metric, axis=0)
    std_n = dev_n.std(axis=0)  # (33, 3)
    std_m = np.sqrt((dev_m**2).mean(axis=0)) / torso
    step_rms_m = np.sqrt((step_m**2).mean(axis=0)) / torso
    step_rms_n = np.sqrt((np.diff(xyz, axis=0) ** 2).mean(axis=0))
    return {
        "std_norm_x": std_n[:, 0],
        "std_norm_y": std_n[:, 1],
        "std_norm_z": std_n[:, 2],
        "step_rms_norm_x": step_rms_n[:, 0],
        "step_rms_norm_y": step_rms_n[:, 1],
        "std_torso_xy": np.sqrt((std_m[:, :2] ** 2).mean(axis=1)),
        "std_torso_z": std_m[:, 2],
        "step_rms_torso_xy": np.sqrt((step_rms_m[:, :2] ** 2).mean(axis=1)),
        "autocorr_xy": [autocorr(dev_m[..., :2] / torso, lag) for lag in (1, 2, 3)],
    }


def summarise(stats: dict[str, Any], xyz: np.ndarray, torso: float, vis: np.ndarray
              ) -> dict[str, Any]:  # fmt: skip
    """Medians over the visible landmarks (mean visibility >= VISIBLE) of a run, and
    their jitter's autocorrelation."""
    seen = vis >= VISIBLE
    out: dict[str, Any] = {"visible_landmarks": int(seen.sum())}
    for key in ("std_torso_xy", "step_rms_torso_xy", "std_torso_z", "std_norm_x",
                "std_norm_y", "step_rms_norm_x", "step_rms_norm_y"):  # fmt: skip
        vals = np.asarray(stats[key])[seen]
        out[key] = float(np.median(vals)) if len(vals) else None
    out["autocorr_xy_visible"] = visible_autocorr(xyz, torso, vis)
    return out


def visible_autocorr(xyz: np.ndarray, torso: float, vis: np.ndarray) -> list[float]:
    """Lag-1..3 autocorrelation of the x/y jitter of the visible landmarks only."""
    seen = vis >= VISIBLE
    if not seen.any():
        return []
    metric = xyz[:, seen, :2] * np.array([ASPECT, 1.0])
    dev = (metric - metric.mean(axis=0)) / torso
    return [round(autocorr(dev, lag), 3) for lag in (1, 2, 3)]


def _r(x: Any, nd: int = 5) -> Any:
    if isinstance(x, np.ndarray):
        return np.round(x, nd).tolist()
    if isinstance(x, float):
        return round(x, nd)
    if isinstance(x, list):
        return [_r(v, nd) for v in x]
    if isinstance(x, dict):
        return {k: _r(v, nd) for k, v in x.items()}
    return x


def zoom_schedule(scales: Sequence[float], hold: int) -> tuple[np.ndarray, list[slice]]:
    """Per-frame photo scales: each scale held `hold` frames, TRANSITION frames of linear
    change between holds (the person walks away while tracked); the holds' slices."""
    parts, holds, at = [], [], 0
    for i, scale in enumerate(scales):
        if i:
            parts.append(np.linspace(scales[i - 1], scale, TRANSITION + 2)[1:-1])
            at += TRANSITION
        parts.append(np.full(hold, scale))
        holds.append(slice(at, at + hold))
        at += hold
    return np.concatenate(parts), holds


def describe(name: str, scale: float, protocol: str, out: dict[str, np.ndarray],
             hold: slice, frames: int) -> dict[str, Any]:  # fmt: skip
    """The figures of one held scale of one stream (frames `hold` of `out`)."""
    found = out["found"][hold]
    row: dict[str, Any] = {"photo": name, "scale": scale, "protocol": protocol,
                           "frames": frames, "found": int(found.sum())}  # fmt: skip
    good = found.copy()
    good[:WARMUP] = False
    if good.sum() < 20:
        row["note"] = "fewer than 20 frames with a person after the warm-up"
        print(f"{name:13s} {protocol:7s} scale {scale:.2f}: {row['note']}")
        return row
    raw = out["raw"][hold][good]
    filt, vis = out["filtered"][hold][good], out["vis"][hold][good]
    torso = float(np.median(torso_metric(raw)))
    mean_vis = vis.mean(axis=0)
    row.update(
        height=round(STATURE_TORSO * torso, 4),
        torso=round(torso, 5),
        mean_visibility=mean_vis,
        visibility_step_rms=np.sqrt((np.diff(vis, axis=0) ** 2).mean(axis=0)),
        raw=jitter_stats(raw, torso),
        filtered=jitter_stats(filt, torso),
    )
    row["raw_visible"] = summarise(row["raw"], raw, torso, mean_vis)
    row["filtered_visible"] = summarise(row["filtered"], filt, torso, mean_vis)
    rv, fv = row["raw_visible"], row["filtered_visible"]
    print(
        f"{name:13s} {protocol:7s} scale {scale:.2f} height {row['height']:.3f} "
        f"found {row['found']}/{frames} visible {rv['visible_landmarks']} "
        f"jitter/torso raw {rv['std_torso_xy']:.4f} One Euro {fv['std_torso_xy']:.4f} "
        f"rho1 {rv['autocorr_xy_visible'][0]:.2f}",
        flush=True,
    )
    return row


def measure(photos: Sequence[str], frames: int, noise: float, num_poses: int, seed: int
            ) -> list[dict[str, Any]]:  # fmt: skip
    """Each photo under two protocols. `fresh`: one new stream per scale (the estimator
    must find the person itself, as when a drone first sees its operator). `tracked`:
    one stream through all its scales from the largest down, each held `frames` frames
    (the person walks away while tracked). Each hold is measured after WARMUP frames."""
    runs = []
    for p_i, name in enumerate(photos):
        photo = load_photo(name)
        scales = sorted(PHOTO_SCALES[name], reverse=True)
        started = time.perf_counter()
        for s_i, scale in enumerate(scales):
            out = run_stream(photo, np.full(frames, scale), noise, seed + 10 * p_i + s_i,
                             num_poses)  # fmt: skip
            runs.append(describe(name, scale, "fresh", out, slice(0, frames), frames))
        schedule, holds = zoom_schedule(scales, frames)
        out = run_stream(photo, schedule, noise, seed + 100 * (p_i + 1), num_poses)
        for scale, hold in zip(scales, holds, strict=True):
            runs.append(describe(name, scale, "tracked", out, hold, frames))
        print(f"{name}: {time.perf_counter() - started:.1f} s", flush=True)
    return runs


def size_law(h: np.ndarray, s: np.ndarray) -> dict[str, Any]:
    """Fit std = a + b * (0.6 / h) ** p (least squares on log std): a floor that every
    size has, and a part that grows as the person shrinks."""
    from scipy.optimize import curve_fit

    def model(hh: np.ndarray, a: float, b: float, p: float) -> np.ndarray:
        return np.log(a + b * (REF_HEIGHT / hh) ** p)

    (a, b, p), _ = curve_fit(model, h, np.log(s), p0=[0.006, 0.003, 2.0],
                             bounds=([0, 0, 0], [1, 1, 8]))  # fmt: skip
    resid = model(h, a, b, p) - np.log(s)
    return {
        "form": f"std_torso_xy(visible) = a + b * ({REF_HEIGHT} / height) ** p",
        "a": float(a),
        "b": float(b),
        "p": float(p),
        "rms_log_residual": float(np.sqrt(np.mean(resid**2))),
        "at": {f"{hh}": float(np.exp(model(np.array(hh), a, b, p))) for hh in (0.2, 0.3, 0.6, 0.9)},
    }


def by_visibility(ok: list[dict[str, Any]], kind: str) -> list[dict[str, Any]]:
    """Each landmark's jitter over its run's visible median, and its visibility's
    frame-to-frame step, binned by the landmark's mean visibility."""
    ratio = np.concatenate(
        [np.asarray(r[kind]["std_torso_xy"]) / r[f"{kind}_visible"]["std_torso_xy"] for r in ok]
    )
    vis = np.concatenate([np.asarray(r["mean_visibility"]) for r in ok])
    vstep = np.concatenate([np.asarray(r["visibility_step_rms"]) for r in ok])
    table = []
    for lo, hi in itertools.pairwise(VIS_BINS):
        m = (vis >= lo) & (vis < hi)
        if m.any():
            table.append({
                "vis_lo": lo, "vis_hi": min(hi, 1.0), "n": int(m.sum()),
                "median_visibility": float(np.median(vis[m])),
                "median_factor": float(np.median(ratio[m])),
                "p25": float(np.percentile(ratio[m], 25)),
                "p75": float(np.percentile(ratio[m], 75)),
                "visibility_step_rms": float(np.median(vstep[m])),
            })  # fmt: skip
    return table


def visibility_knots(table: list[dict[str, Any]]) -> dict[str, list[float]]:
    """The jitter factor against visibility as knots for linear interpolation: each
    bin's median visibility and median factor, made non-increasing with visibility
    (a landmark never jitters less for being seen less)."""
    at = [b["median_visibility"] for b in table]
    factor = np.maximum.accumulate(np.array([b["median_factor"] for b in table])[::-1])[::-1]
    return {"visibility": at, "factor": factor.tolist()}


def pooled(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Over all runs: per photo, the size law of the visible landmarks' jitter; the
    reference law (the photo read with less jitter, the other's excess over it); the
    visibility factor; temporal correlation; z and x/y against the visible x/y jitter;
    how much of it the One Euro filter keeps."""
    ok = [r for r in runs if "raw" in r]
    out: dict[str, Any] = {}
    for photo in sorted({r["photo"] for r in ok}):
        mine = [r for r in ok if r["photo"] == photo]
        h = np.array([r["height"] for r in mine])
        out[photo] = {
            "runs": len(mine),
            "height_range": [float(h.min()), float(h.max())],
            "raw_std_torso_xy_median": float(
                np.median([r["raw_visible"]["std_torso_xy"] for r in mine])
            ),
            "autocorr_xy_visible_median": np.median(
                [r["raw_visible"]["autocorr_xy_visible"] for r in mine], axis=0
            ).tolist(),
        }
        for kind in ("raw", "filtered"):
            s = np.array([r[f"{kind}_visible"]["std_torso_xy"] for r in mine])
            out[photo][f"{kind}_size_law"] = size_law(h, s)
    photos = sorted(out, key=lambda ph: out[ph]["raw_std_torso_xy_median"])
    ref = photos[0]
    out["reference_photo"] = ref
    out["raw_size_law"] = out[ref]["raw_size_law"]
    out["filtered_size_law"] = out[ref]["filtered_size_law"]
    law = out["raw_size_law"]
    for other in photos[1:]:
        mine = [r for r in ok if r["photo"] == other]
        expect = [law["a"] + law["b"] * (REF_HEIGHT / r["height"]) ** law["p"] for r in mine]
        ratio = [r["raw_visible"]["std_torso_xy"] / e for r, e in zip(mine, expect, strict=True)]
        out[other]["raw_over_reference_law_median"] = float(np.median(ratio))
    h_all = np.array([r["height"] for r in ok])
    s_all = np.array([r["raw_visible"]["std_torso_xy"] for r in ok])
    out["both_photos_size_law"] = size_law(h_all, s_all)
    for kind in ("raw", "filtered"):
        out[f"{kind}_visibility_factor"] = by_visibility(ok, kind)
        out[f"{kind}_visibility_knots"] = visibility_knots(out[f"{kind}_visibility_factor"])
    rv = [r["raw_visible"] for r in ok]
    out["autocorr_xy_visible_median"] = np.median(
        [v["autocorr_xy_visible"] for v in rv], axis=0
    ).tolist()
    out["z_over_xy_median"] = float(np.median([v["std_torso_z"] / v["std_torso_xy"] for v in rv]))
    out["x_over_y_metric_median"] = float(
        np.median([v["std_norm_x"] * ASPECT / v["std_norm_y"] for v in rv])
    )
    kept = [r["filtered_visible"]["std_torso_xy"] / r["raw_visible"]["std_torso_xy"] for r in ok]
    out["filter_ratio_visible_median"] = float(np.median(kept))
    # What MediaPipe reports for body parts absent from the image but inside the frame:
    # the photos show no legs (knees, ankles, heels, feet).
    legs = np.concatenate([np.asarray(r["mean_visibility"])[25:33] for r in ok])
    out["absent_legs_visibility_p25_p50_p75"] = np.percentile(legs, [25, 50, 75]).tolist()
    return out


def plot(result: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in result["runs"] if "raw" in r]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    colours = {"grace_hopper": "#4477aa", "astronaut": "#ee6677"}
    marks = {"fresh": "o", "tracked": "^"}
    ax = axes[0]
    for name, col in colours.items():
        for protocol, mark in marks.items():
            rs = sorted((r for r in ok if r["photo"] == name and r["protocol"] == protocol),
                        key=lambda r: r["height"])  # fmt: skip
            h = [r["height"] for r in rs]
            ax.plot(h, [r["raw_visible"]["std_torso_xy"] for r in rs], mark + "-", color=col,
                    label=f"{name} {protocol}")  # fmt: skip
            ax.plot(h, [r["filtered_visible"]["std_torso_xy"] for r in rs], mark + ":",
                    color=col, alpha=0.45, mfc="none")  # fmt: skip
    law = result["pooled"]["raw_size_law"]
    hh = np.linspace(0.1, 1.0, 60)
    ref = result["pooled"]["reference_photo"]
    ax.plot(hh, law["a"] + law["b"] * (REF_HEIGHT / hh) ** law["p"], "k:",
            label=f"fit to {ref} (the model's)")  # fmt: skip
    ax.set(xlabel="person height / frame height", ylabel="jitter std / torso length",
           title=f"visible landmarks (vis >= {VISIBLE}); dotted: One Euro",
           yscale="log")  # fmt: skip
    ax.legend(fontsize=7)
    ax = axes[1]
    for r in ok:
        ax.scatter(r["mean_visibility"], r["raw"]["std_torso_xy"], s=8, alpha=0.5,
                   color=plt.cm.viridis(r["height"]))  # fmt: skip
    ax.set(xlabel="mean visibility of the landmark", ylabel="jitter std / torso length",
           yscale="log", title="every landmark (colour: person height)")  # fmt: skip
    ax = axes[2]
    for name, col in colours.items():
        rs = sorted((r for r in ok if r["photo"] == name), key=lambda r: r["height"])
        h = [r["height"] for r in rs]
        ax.plot(h, [r["raw_visible"]["step_rms_norm_x"] for r in rs], "o", color=col,
                label=f"{name} x")  # fmt: skip
        ax.plot(h, [r["raw_visible"]["step_rms_norm_y"] for r in rs], "^", color=col,
                mfc="none", label=f"{name} y")  # fmt: skip
    ax.set(xlabel="person height / frame height", ylabel="frame-to-frame step RMS",
           title="visible landmarks, normalised image units (raw)", yscale="log")  # fmt: skip
    ax.legend(fontsize=7)
    fig.suptitle(f"live pose path jitter on still photos (noise {result['noise']} grey levels, "
                 "+-0.5 px shifts, 1280x720)", fontsize=9)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=150, help="measured frames per run")
    ap.add_argument("--noise", type=float, default=4.0, help="sensor noise, grey levels")
    ap.add_argument("--photos", default="grace_hopper,astronaut")
    ap.add_argument("--num-poses", type=int, default=2, help="as the live engine (2)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=RESULTS / "pose_jitter.json")
    ap.add_argument("--reanalyse", action="store_true",
                    help="recompute the pooled figures and the PNG from --out's runs "
                         "(no MediaPipe run)")  # fmt: skip
    args = ap.parse_args(argv)
    result: dict[str, Any]
    if args.reanalyse:
        result = json.loads(args.out.read_text())
        result["pooled"] = pooled(result["runs"])
        result["reanalysed"] = {"command": "python -m bench.pose_jitter "
                                + shlex.join(argv or sys.argv[1:]),
                                "date": time.strftime("%Y-%m-%d")}  # fmt: skip
        return write(result, args.out)
    if args.frames < WARMUP + 20:
        ap.error(f"--frames must be at least {WARMUP + 20}")
    os.environ.setdefault("GLOG_minloglevel", "2")

    started, cpu0 = time.perf_counter(), time.process_time()
    runs = measure(args.photos.split(","), args.frames, args.noise, args.num_poses, args.seed)
    import mediapipe

    result = {
        "benchmark": "pose_jitter",
        "command": "python -m bench.pose_jitter " + shlex.join(argv or sys.argv[1:]),
        "date": time.strftime("%Y-%m-%d"),
        "machine": {"cpus_visible": len(os.sched_getaffinity(0)), "platform": platform.platform()},
        "mediapipe": mediapipe.__version__,
        "frame": [WIDTH, HEIGHT],
        "fps": FPS,
        "noise": args.noise,
        "shift_px": 0.5,
        "num_poses": args.num_poses,
        "warmup_frames": WARMUP,
        "visible_threshold": VISIBLE,
        "stature_torso": STATURE_TORSO,
        "one_euro": {"min_cutoff": 1.0, "beta": 30.0, "d_cutoff": 1.0},
        "runs": runs,
    }
    result["pooled"] = pooled(runs)
    result["seconds"] = round(time.perf_counter() - started, 1)
    result["cpu_seconds"] = round(time.process_time() - cpu0, 1)
    return write(result, args.out)


def write(result: dict[str, Any], out: Path) -> int:
    """Write the JSON and the PNG; print the pooled figures."""
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(_r(result), indent=1) + "\n")
    plot(result, out.with_suffix(".png"))
    p = result["pooled"]
    law = p["raw_size_law"]
    print(f"size law ({p['reference_photo']}): {law['a']:.4f} + {law['b']:.4f} "
          f"* (0.6/h)^{law['p']:.2f}")  # fmt: skip
    knots = p["raw_visibility_knots"]
    pairs = zip(knots["visibility"], knots["factor"], strict=True)
    print("visibility factor: " + ", ".join(f"{f:.2f} at {v:.2f}" for v, f in pairs))
    print(f"One Euro keeps {p['filter_ratio_visible_median']:.2f} of the visible jitter")
    print(f"wrote {out} in {result['seconds']} s ({result['cpu_seconds']} s CPU)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
