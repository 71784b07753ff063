"""One Euro parameters for the operator tracker, tuned on the measured live-path jitter.

Ground truth: the 39 LASER clips as recorded (smooth, real gesture motion). Input: the
same clips with the capture model's jitter (`proxima.gesture.capture`, measured by
`bench.pose_jitter`: per landmark, by person size and visibility), at 30 fps as the
tracker sees them. Every (min_cutoff, beta, d_cutoff) of a small grid filters the noisy
clips with the equations of `proxima.pose.OneEuroFilter` (run for all settings at once;
checked against the class itself), resetting after a pause over 0.5 s as the tracker
does. Scored on x and y of the landmarks visible in the recording (visibility >= 0.5),
in torso lengths in the metric frame:

- error: RMS of filtered minus clean, over every frame of every clip (the objective);
- fast error: the same over the frames where the wrists move fastest (top 20%), where a
  filter that lags shows it; slow error: over those where they move least (bottom 50%);
- velocity error: RMS of the frame-to-frame step of filtered minus that of clean (the
  `body` features hold velocities);
- lag: the shift (0-10 frames, refined between frames) that best aligns the filtered
  clean clip with the clean clip on the elbows and wrists, in ms, and the distortion
  (RMS of filtered clean minus clean there).

Conditions: the person as recorded (about 0.57 of the frame height) at the measured
jitter (the one that chooses), twice the jitter, and the person at 0.3 and 0.9 of the
frame height. `best` has the least error; `recommended` the least error + velocity error.

    python -m bench.one_euro_tuning [--data DIR]

Writes bench/results/one_euro_tuning.json. Recommends; does not change the tracker.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.capture import CaptureModel
from proxima.gesture.clip import Clip
from proxima.gesture.geometry import to_metric

RESULTS = Path(__file__).resolve().parent / "results"
FPS = 30.0
RESET_AFTER_S = 0.5  # OperatorTracker.reset_after_s
MIN_CUTOFF = (0.25, 0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0)
BETA = (0.0, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0)
D_CUTOFF = (0.5, 1.0, 2.0, 4.0)
CURRENT = (1.0, 30.0, 1.0)  # OperatorTracker's today
ARMS = [13, 14, 15, 16]
CONDITIONS = {
    "recorded_x1": {"jitter": 1.0},
    "recorded_x2": {"jitter": 2.0},
    "height_0.3_x1": {"jitter": 1.0, "person_height": 0.3},
    "height_0.9_x1": {"jitter": 1.0, "person_height": 0.9},
}
MAX_LAG = 10


def one_euro_batch(x: np.ndarray, t: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Filter a sequence (T, ...) with every setting of `grid` (G, 3: min_cutoff, beta,
    d_cutoff) at once: (G, T, ...). The equations of `OneEuroFilter`; reset (output =
    input) at the first row and after a pause over RESET_AFTER_S."""
    shape = (len(grid),) + (1,) * (x.ndim - 1)
    mc, beta, dc = (grid[:, i].reshape(shape) for i in range(3))
    out = np.empty((len(grid), *x.shape))
    state = dx = None
    for i in range(len(x)):
        dt = t[i] - t[i - 1] if i else math.inf
        if state is None or dt > RESET_AFTER_S:
            state = np.broadcast_to(x[i], out.shape[:1] + x.shape[1:]).copy()
            dx = np.zeros_like(state)
        else:
            a_d = 1.0 / (1.0 + 1.0 / (2 * math.pi * dc * dt))
            dx = dx + a_d * ((x[i] - state) / dt - dx)
            cutoff = mc + beta * np.abs(dx)
            a = 1.0 / (1.0 + 1.0 / (2 * math.pi * cutoff * dt))
            state = state + a * (x[i] - state)
        out[:, i] = state
    return out


def check_against_class(x: np.ndarray, t: np.ndarray) -> float:
    """Largest difference between `one_euro_batch` and `proxima.pose.OneEuroFilter` (with
    the tracker's reset) on a clip, for the current setting."""
    from proxima.pose import OneEuroFilter

    f = OneEuroFilter(*CURRENT)
    ref = []
    for i in range(len(x)):
        if i and t[i] - t[i - 1] > RESET_AFTER_S:
            f.reset()
        ref.append(f(x[i], float(t[i])))
    mine = one_euro_batch(x, t, np.array([CURRENT]))[0]
    return float(np.abs(np.array(ref) - mine).max())


def prepared(clips: Sequence[Clip], condition: dict[str, Any], seed: int) -> list[dict]:
    """Each clip's clean and noisy landmarks under `condition` (same seed, so the clean
    one has the same person size), with times, torso length and masks."""
    out = []
    for i, clip in enumerate(clips):
        noisy = CaptureModel(visibility_noise=0.0, **condition)
        clean = CaptureModel(**{**condition, "jitter": 0.0, "visibility_noise": 0.0})
        a = noisy.apply_clip(clip, np.random.default_rng(seed + i))
        c = clean.apply_clip(clip, np.random.default_rng(seed + i))
        m = to_metric(c.xyz, clip.aspect)
        torso = float(np.median(np.linalg.norm(
            ((m[:, 11] + m[:, 12]) - (m[:, 23] + m[:, 24]))[:, :2] / 2, axis=-1)))  # fmt: skip
        speed = np.r_[0.0, np.linalg.norm(np.diff(m[:, [15, 16], :2], axis=0), axis=-1).max(1)]
        out.append({"t": a.t, "noisy": a.xyz.astype(np.float64), "clean": c.xyz.astype(np.float64),
                    "seen": clip.visibility >= 0.5, "torso": torso, "speed": speed,
                    "aspect": clip.aspect})  # fmt: skip
    return out


def score(data: list[dict], grid: np.ndarray) -> dict[str, np.ndarray]:
    """Error, fast error and lag per grid setting, plus the unfiltered error."""
    sq, sq_fast, sq_slow = np.zeros(len(grid)), np.zeros(len(grid)), np.zeros(len(grid))
    n = n_fast = n_slow = 0
    raw_sq = raw_fast = raw_slow = 0.0
    lag_sq = np.zeros((len(grid), MAX_LAG + 1))
    arms_n = 0
    vel_sq, abs_norm = np.zeros(len(grid)), np.zeros(len(grid))
    raw_vel = raw_abs = 0.0
    n_vel = 0
    speeds = np.concatenate([d["speed"] for d in data])
    fast_cut, slow_cut = np.percentile(speeds, 80), np.percentile(speeds, 50)
    for d in data:
        scale = np.array([d["aspect"], 1.0]) / d["torso"]
        filt = one_euro_batch(d["noisy"][..., :2], d["t"], grid) * scale  # (G, T, 33, 2)
        clean = d["clean"][..., :2] * scale
        err = ((filt - clean) ** 2).sum(-1)  # (G, T, 33)
        seen, fast, slow = d["seen"], d["speed"] >= fast_cut, d["speed"] <= slow_cut
        sq += (err * seen).sum((1, 2))
        sq_fast += (err[:, fast] * seen[fast]).sum((1, 2))
        sq_slow += (err[:, slow] * seen[slow]).sum((1, 2))
        n, n_fast, n_slow = n + seen.sum(), n_fast + seen[fast].sum(), n_slow + seen[slow].sum()
        raw = ((d["noisy"][..., :2] * scale - clean) ** 2).sum(-1)
        raw_sq += float((raw * seen).sum())
        raw_fast += float((raw[fast] * seen[fast]).sum())
        raw_slow += float((raw[slow] * seen[slow]).sum())
        # Velocity (what the features' frame-to-frame differences see) and mean absolute
        # error in normalised image units (the tracker docs' earlier figure).
        both = seen[1:] & seen[:-1]
        dv = np.diff(filt, axis=1) - np.diff(clean, axis=0)
        vel_sq += ((dv**2).sum(-1) * both).sum((1, 2))
        dv_raw = np.diff(d["noisy"][..., :2] * scale, axis=0) - np.diff(clean, axis=0)
        raw_vel += float(((dv_raw**2).sum(-1) * both).sum())
        n_vel += both.sum()
        abs_norm += (np.abs((filt - clean) / scale).mean(-1) * seen).sum((1, 2))
        raw_abs += float((np.abs(d["noisy"][..., :2] - d["clean"][..., :2]).mean(-1) * seen).sum())
        smooth = one_euro_batch(d["clean"][:, ARMS, :2], d["t"], grid) * scale
        ref = clean[:, ARMS]
        for lag in range(MAX_LAG + 1):
            diff = smooth[:, lag:] - ref[: len(ref) - lag]
            lag_sq[:, lag] += (diff**2).sum((1, 2, 3)) / diff[0].size
        arms_n += 1
    return {
        "error": np.sqrt(sq / n / 2),
        "fast_error": np.sqrt(sq_fast / n_fast / 2),
        "slow_error": np.sqrt(sq_slow / n_slow / 2),
        "lag_ms": subframe_argmin(lag_sq) * 1000.0 / FPS,
        "clean_distortion": np.sqrt(lag_sq[:, 0] / arms_n),
        "velocity_error": np.sqrt(vel_sq / n_vel / 2),
        "mean_abs_normalised": abs_norm / n,
        "raw_error": np.sqrt(raw_sq / n / 2),
        "raw_velocity_error": np.full(1, np.sqrt(raw_vel / n_vel / 2)),
        "raw_mean_abs_normalised": np.full(1, raw_abs / n),
        "raw_fast_error": np.sqrt(raw_fast / n_fast / 2),
        "raw_slow_error": np.sqrt(raw_slow / n_slow / 2),
    }


def subframe_argmin(curve: np.ndarray) -> np.ndarray:
    """Per row of `curve` (G, L), the argmin refined by a parabola through its
    neighbours (in frames)."""
    i = curve.argmin(axis=1)
    j = np.clip(i, 1, curve.shape[1] - 2)
    rows = np.arange(len(curve))
    a, b, c = curve[rows, j - 1], curve[rows, j], curve[rows, j + 1]
    den = a - 2 * b + c
    off = np.where(den > 0, 0.5 * (a - c) / np.where(den > 0, den, 1.0), 0.0)
    return np.where((i > 0) & (i < curve.shape[1] - 1), j + np.clip(off, -0.5, 0.5),
                    np.maximum(j + np.clip(off, -1, 0.5), 0.0))  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=RESULTS / "one_euro_tuning.json")
    args = ap.parse_args(argv)
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    started = time.perf_counter()
    clips = load_laser_dir(resolve_dataset(args.data))
    grid = np.array(list(itertools.product(MIN_CUTOFF, BETA, D_CUTOFF)), np.float64)
    t0 = (clips[0].frames - 1) / FPS
    check = check_against_class(clips[0].xyz.astype(np.float64), t0)
    scores = {}
    for name, cond in CONDITIONS.items():
        scores[name] = score(prepared(clips, cond, args.seed), grid)
        print(f"{name}: {time.perf_counter() - started:.0f} s", flush=True)

    def row(i: int) -> dict[str, Any]:
        mc, beta, dc = grid[i]
        return {
            "min_cutoff": mc, "beta": beta, "d_cutoff": dc,
            **{name: {k: round(float(v[i]), 5) for k, v in s.items() if not k.startswith("raw")}
               for name, s in scores.items()},
        }  # fmt: skip

    main_s = scores["recorded_x1"]
    best = int(np.argmin(main_s["error"]))
    current = int(np.flatnonzero((grid == np.array(CURRENT)).all(axis=1))[0])
    # Among settings within 2% of the best error, the one with the least lag.
    near = np.flatnonzero(main_s["error"] <= 1.02 * main_s["error"][best])
    least_lag = int(near[np.lexsort((main_s["error"][near], main_s["lag_ms"][near]))[0]])
    best_velocity = int(np.argmin(main_s["velocity_error"]))
    # The features hold positions and velocities: the setting best at both together.
    recommended = int(np.argmin(main_s["error"] + main_s["velocity_error"]))
    order = np.argsort(main_s["error"])
    result: dict[str, Any] = {
        "benchmark": "one_euro_tuning",
        "command": "python -m bench.one_euro_tuning " + shlex.join(argv or sys.argv[1:]),
        "date": time.strftime("%Y-%m-%d"),
        "clips": len(clips),
        "frames": int(sum(len(c) for c in clips)),
        "conditions": CONDITIONS,
        "units": "RMS per axis (x, y) in torso lengths, landmarks with recorded visibility >= 0.5",
        "grid": {"min_cutoff": MIN_CUTOFF, "beta": BETA, "d_cutoff": D_CUTOFF},
        "batch_filter_max_diff_from_OneEuroFilter": check,
        "unfiltered": {
            name: {
                "error": round(float(s["raw_error"]), 5),
                "fast_error": round(float(s["raw_fast_error"]), 5),
                "slow_error": round(float(s["raw_slow_error"]), 5),
                "velocity_error": round(float(s["raw_velocity_error"][0]), 5),
                "mean_abs_normalised": round(float(s["raw_mean_abs_normalised"][0]), 6),
            }
            for name, s in scores.items()
        },
        "best": row(best),
        "best_within_2pct_least_lag": row(least_lag),
        "best_velocity": row(best_velocity),
        "recommended": row(recommended),
        "recommended_rule": "least error + velocity_error at recorded_x1",
        "best_per_condition": {
            name: row(int(np.argmin(sc["error"]))) for name, sc in scores.items()
        },
        "current": row(current),
        "top10": [row(int(i)) for i in order[:10]],
        "all": [row(i) for i in range(len(grid))],
        "seconds": round(time.perf_counter() - started, 1),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    shown = {"best": "best", "least lag": "best_within_2pct_least_lag",
             "velocity": "best_velocity", "recommended": "recommended",
             "current": "current"}  # fmt: skip
    for name, key in shown.items():
        r = result[key]
        m = r["recorded_x1"]
        print(f"{name:9s} min_cutoff {r['min_cutoff']:g} beta {r['beta']:g} d_cutoff "
              f"{r['d_cutoff']:g}: error {m['error']:.4f} fast {m['fast_error']:.4f} "
              f"slow {m['slow_error']:.4f} velocity {m['velocity_error']:.4f} "
              f"lag {m['lag_ms']:.0f} ms")  # fmt: skip
    u = result["unfiltered"]["recorded_x1"]
    print(f"unfiltered: error {u['error']:.4f} fast {u['fast_error']:.4f} "
          f"slow {u['slow_error']:.4f} velocity {u['velocity_error']:.4f}")  # fmt: skip
    print(f"batch filter vs OneEuroFilter: max diff {check:.2e}")
    print(f"wrote {args.out} in {result['seconds']} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
