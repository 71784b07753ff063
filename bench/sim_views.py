"""How the closed-loop simulator's cameras read the synthetic operator: recognition by
the camera's bearing from the operator and by the live pose path's noise.

For each scene seed and gesture, the synthetic operator (`proxima.sim`, facing south)
performs the gesture for 6 s; a drone camera 5 m away at 2.5 m (gimballed, pitched 12
degrees down, 70 degrees wide, 1280x720) at each bearing from the operator's facing sees
them; the landmarks get the capture noise (`proxima.sim.noise`: none; x/y jitter and
visibility noise as measured; and the same with z's measured jitter ratio), then the
operator tracker's One Euro filter (min_cutoff 1, beta 30, as the engine runs it), and
every 60-frame window (stride 5) after the gesture's onset goes to the classifier. Per
cell: the mean probability of the performed gesture and the share of windows it wins.

    python -m bench.sim_views [--checkpoint models/gesture-default.pt] [--seeds 2 5]

Writes bench/results/sim_views.json and prints a table.
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"
GESTURES = ("hover", "have_command", "move_upward", "move_to_left", "land", "wave_off")
BEARINGS = (0.0, 20.0, 45.0, 70.0, 90.0)
NOISE = {
    "none": (0.0, 0.0, 0.0),
    "xy": (1.0, 1.0, 0.0),  # x/y jitter and visibility noise as measured, z clean
    "measured": (1.0, 1.0, 1.0),  # and z's jitter at its measured ratio (23 x x/y's)
}


def measure(checkpoint: Path | None, seeds: list[int]) -> dict[str, Any]:
    import torch

    from proxima.engine import load_classifier
    from proxima.pose.one_euro import OneEuroFilter
    from proxima.sim.config import OperatorConfig, SceneConfig, build_scene
    from proxima.sim.mount import CameraMount
    from proxima.sim.noise import CaptureNoise
    from proxima.synth.projection import project_landmarks

    torch.set_num_threads(1)
    clf = load_classifier(checkpoint)
    labels = list(clf.labels)
    mount = CameraMount(pitch_deg=-12.0)
    cells: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for seed in seeds:
        for gesture in GESTURES:
            scene_cfg = SceneConfig(
                seed=seed, operator=OperatorConfig(heading_deg=180.0, script=f"{gesture}:6")
            )
            op = build_scene(scene_cfg, "bench").operator
            seg = next(s for s in op.segments if s[0] == gesture)
            for bearing in BEARINGS:
                side = math.radians(180.0 + bearing)
                pos = (5 * math.cos(side), 5 * math.sin(side), -2.5)
                cam = mount.camera(pos, (0.0, 0.0, math.atan2(-pos[1], -pos[0])))
                seen = project_landmarks(op.world, cam, op.body)
                for noise_name, (jit, vis_n, depth) in NOISE.items():
                    rng = np.random.default_rng([seed, int(bearing)])
                    xyz, _ = CaptureNoise(jit, vis_n, depth).apply(
                        seen.xyz, seen.visibility, seen.aspect, rng
                    )
                    f = OneEuroFilter(1.0, 30.0)
                    xyz = np.stack([f(x, k / scene_cfg.fps) for k, x in enumerate(xyz)])
                    ends = range(seg[2] + 60, seg[3] + 1, 5)
                    wins = np.stack([xyz[e - 60 : e] for e in ends]).astype(np.float32)
                    p = clf.predict(wins, aspect=seen.aspect)
                    g = labels.index(gesture)
                    cells.append(
                        {
                            "seed": seed,
                            "gesture": gesture,
                            "bearing_deg": bearing,
                            "noise": noise_name,
                            "windows": len(wins),
                            "p_mean": round(float(p[:, g].mean()), 3),
                            "agreement": round(float((p.argmax(1) == g).mean()), 3),
                            "read_as": labels[int(np.bincount(p.argmax(1)).argmax())],
                        }
                    )
    return {
        "command": "python -m bench.sim_views " + shlex.join(sys.argv[1:]),
        "checkpoint": str(checkpoint) if checkpoint else "shipped default",
        "seeds": seeds,
        "camera": {"distance_m": 5.0, "height_m": 2.5, **mount.model_dump()},
        "noise": {
            k: dict(zip(("jitter", "visibility_noise", "depth_jitter"), v, strict=True))
            for k, v in NOISE.items()
        },
        "seconds": round(time.perf_counter() - t0, 1),
        "cells": cells,
    }


def table(result: dict[str, Any]) -> str:
    """Mean probability of the performed gesture, over seeds and gestures, per bearing and
    noise; then per gesture at each bearing with the measured noise."""
    cells = result["cells"]
    lines = ["| bearing | " + " | ".join(f"{n}: p / wins" for n in NOISE) + " |",
             "|---|" + "---|" * len(NOISE)]  # fmt: skip
    for b in BEARINGS:
        row = []
        for n in NOISE:
            sel = [c for c in cells if c["bearing_deg"] == b and c["noise"] == n]
            p = np.mean([c["p_mean"] for c in sel])
            a = np.mean([c["agreement"] for c in sel])
            row.append(f"{p:.2f} / {a:.2f}")
        lines.append(f"| {b:g} | " + " | ".join(row) + " |")
    lines += ["", "| gesture | " + " | ".join(f"{b:g}" for b in BEARINGS) + " |",
              "|---|" + "---|" * len(BEARINGS)]  # fmt: skip
    for g in GESTURES:
        row = []
        for b in BEARINGS:
            sel = [c for c in cells if c["gesture"] == g and c["bearing_deg"] == b]
            xy = np.mean([c["p_mean"] for c in sel if c["noise"] == "xy"])
            full = np.mean([c["p_mean"] for c in sel if c["noise"] == "measured"])
            row.append(f"{xy:.2f} / {full:.2f}")
        lines.append(f"| {g} (xy / measured) | " + " | ".join(row) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--checkpoint", type=Path, default=None)
    ap.add_argument("--seeds", type=int, nargs="+", default=[2, 5])
    ap.add_argument("--out", type=Path, default=RESULTS / "sim_views.json")
    args = ap.parse_args(argv)
    result = measure(args.checkpoint, args.seeds)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(table(result))
    print(f"{len(result['cells'])} cells in {result['seconds']} s -> {args.out}")


if __name__ == "__main__":
    main()
