"""The capture model's constants that come from the LASER recordings (no MediaPipe run).

- Person height in torso lengths: on the front-view clips, the heel-to-nose span over
  the torso length (shoulder midpoint to hip midpoint, x and y in one scale), divided by
  0.91 (the nose sits at about 91% of stature).
- The operators' height in their frames (that ratio x the torso length), per view:
  what "as recorded" means for the distance effect.
- Visibility at the frame edge: the median visibility of every landmark of every clip
  against its signed distance to the nearest frame edge (negative inside, in torso
  lengths), as a factor of the median far inside the frame. MediaPipe reports
  landmarks outside the image (LASER y reaches 1.65) with falling visibility; the
  capture model uses this curve when it moves landmarks across the edge.

    python -m bench.capture_constants [--data DIR]

Writes bench/results/capture_constants.json.
"""

from __future__ import annotations

import argparse
import itertools
import json
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.clip import Clip
from proxima.gesture.geometry import to_metric

RESULTS = Path(__file__).resolve().parent / "results"
NOSE_STATURE = 0.91
# Signed distance to the frame edge, torso lengths (negative: inside the frame).
EDGE_BINS = (-9.0, -1.5, -1.0, -0.5, -0.25, -0.1, 0.0, 0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.5)


def torso_of(clip: Clip) -> np.ndarray:
    """Per-frame torso length (image-height units) of a clip."""
    m = to_metric(clip.xyz, clip.aspect)
    return np.linalg.norm(((m[:, 11] + m[:, 12]) - (m[:, 23] + m[:, 24]))[:, :2] / 2, axis=-1)


def edge_distance(clip: Clip) -> np.ndarray:
    """(T, 33) signed distance of each landmark to the nearest frame edge, in image-height
    units (x scaled by the aspect), positive outside the frame."""
    x, y = clip.xyz[..., 0], clip.xyz[..., 1]
    a = clip.aspect
    return np.maximum.reduce([(x - 1) * a, -x * a, y - 1, -y])


def measure(clips: Sequence[Clip]) -> dict[str, Any]:
    front = [c for c in clips if c.view == "f"]
    spans = []
    for c in front:
        m = to_metric(c.xyz, c.aspect)
        span = m[:, [29, 30], 1].mean(axis=1) - m[:, 0, 1]  # heels below the nose
        spans.append(float(np.median(span / torso_of(c))))
    heel_nose = float(np.median(spans))
    stature = heel_nose / NOSE_STATURE
    heights: dict[str, list[float]] = {}
    dist, vis = [], []
    for c in clips:
        torso = float(np.median(torso_of(c)))
        heights.setdefault(c.view, []).append(stature * torso)
        dist.append((edge_distance(c) / torso).ravel())
        vis.append(c.visibility.ravel())
    d, v = np.concatenate(dist), np.concatenate(vis)
    far = float(np.median(v[d <= EDGE_BINS[1]]))
    knots = []
    for lo, hi in itertools.pairwise(EDGE_BINS):
        m = (d > lo) & (d <= hi)
        knots.append({
            "distance_lo": lo, "distance_hi": hi, "n": int(m.sum()),
            "median_distance": float(np.median(d[m])),
            "median_visibility": float(np.median(v[m])),
            "factor": float(np.median(v[m]) / far),
        })  # fmt: skip
    return {
        "stature": {
            "heel_to_nose_torso_front_median": heel_nose,
            "nose_at_stature": NOSE_STATURE,
            "stature_torso": stature,
            "front_clips": len(front),
        },
        "recorded_height_by_view": {
            view: {"median": float(np.median(h)), "min": float(min(h)), "max": float(max(h))}
            for view, h in sorted(heights.items())
        },
        "edge_visibility": {"far_inside_median": far, "knots": knots},
    }


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--out", type=Path, default=RESULTS / "capture_constants.json")
    args = ap.parse_args(argv)
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    started = time.perf_counter()
    result = measure(load_laser_dir(resolve_dataset(args.data)))
    result["command"] = "python -m bench.capture_constants " + shlex.join(argv or sys.argv[1:])
    result["date"] = time.strftime("%Y-%m-%d")
    result["seconds"] = round(time.perf_counter() - started, 1)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    s = result["stature"]
    span = s["heel_to_nose_torso_front_median"]
    print(f"stature {s['stature_torso']:.3f} torso lengths (heel to nose {span:.3f})")
    for view, h in result["recorded_height_by_view"].items():
        print(f"view {view}: person height {h['median']:.3f} ({h['min']:.3f}-{h['max']:.3f})")
    for k in result["edge_visibility"]["knots"]:
        d, f = k["median_distance"], k["factor"]
        print(f"edge distance {d:+.3f} torso: visibility factor {f:.3f} (n={k['n']})")
    print(f"wrote {args.out} in {result['seconds']} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
