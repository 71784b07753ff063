"""How fast the capture model runs: on 60-frame training windows (one, and a batch of
512, as augmentation would call it) and on whole LASER clips, for each named condition.

    python -m bench.capture_speed [--repeats 5]

Writes bench/results/capture_speed.json. Single process, numpy's default threads; the
machine is shared, so the medians over `--repeats` runs are reported.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from numpy.random import Generator

from proxima.gesture.capture import CONDITIONS, CaptureModel, condition
from proxima.gesture.clip import Clip
from proxima.gesture.windows import Windows, make_windows

RESULTS = Path(__file__).resolve().parent / "results"
BATCH = 512


def median_ms(fn: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1000.0)
    return round(statistics.median(times), 3)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", type=Path, default=RESULTS / "capture_speed.json")
    args = ap.parse_args(argv)
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    clips = load_laser_dir(resolve_dataset(args.data))
    frames = sum(len(c) for c in clips)
    rows: dict[str, Any] = {}
    for name in CONDITIONS:
        for level in (1,) if name == "clean" else (1, 2, 3):
            model = condition(name, level)
            need = model.source_frames(60)
            w = make_windows(clips, window=need, stride=5)
            batch = w.subset(np.arange(min(BATCH, len(w))))
            one = w.subset(np.arange(1))
            rng = np.random.default_rng(0)
            clip = clips[len(clips) // 2]

            def windows(b: Windows, m: CaptureModel = model, g: Generator = rng) -> object:
                return m.apply_windows(b.xyz, b.vis, g, aspect=b.aspect, has_z=b.has_z,
                                       window=60)  # fmt: skip

            def whole(cs: list[Clip], m: CaptureModel = model, g: Generator = rng) -> object:
                return [m.apply_clip(c, g) for c in cs]

            r: dict[str, Any] = {
                "source_frames": need,
                "one_window_ms": median_ms(partial(windows, one), args.repeats),
                "batch_windows": len(batch),
                "batch_ms": median_ms(partial(windows, batch), args.repeats),
                "one_clip_rows": len(clip),
                "one_clip_ms": median_ms(partial(whole, [clip]), args.repeats),
                "all_clips_ms": median_ms(partial(whole, clips), max(1, args.repeats // 2)),
            }
            r["us_per_window_in_batch"] = round(1000.0 * r["batch_ms"] / len(batch), 1)
            rows[f"{name}:{level}"] = r
            print(f"{name:9s} {level}: 1 window {r['one_window_ms']:.2f} ms, {len(batch)} "
                  f"windows {r['batch_ms']:.1f} ms ({r['us_per_window_in_batch']} us each), "
                  f"one clip ({len(clip)} rows) {r['one_clip_ms']:.1f} ms, "
                  f"all {len(clips)} clips {r['all_clips_ms']:.0f} ms", flush=True)  # fmt: skip
    result = {
        "benchmark": "capture_speed",
        "command": "python -m bench.capture_speed " + shlex.join(argv or sys.argv[1:]),
        "date": time.strftime("%Y-%m-%d"),
        "cpus": os.cpu_count(),
        "loadavg_1_5_15": list(os.getloadavg()),
        "clips": len(clips),
        "clip_frames": frames,
        "conditions": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
