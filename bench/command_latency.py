"""Gesture onset -> command latency and wrong/spurious commands per hour, on held-out
stitched streams through the real engine (`proxima.evaluation.latency` says how).

    python -m bench.command_latency --checkpoint /tmp/gesture-temporal.pt --tune

Writes bench/results/command_latency.json, a PNG of the latency distribution, one per
gesture and view (-gestures.png) and one of where the time goes (-stages.png).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--checkpoint", type=Path, required=True, help="a model trained with --split temporal"
    )
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--streams", type=int, default=36, help="evaluation streams")
    ap.add_argument("--segments", type=int, default=60, help="gestures per stream")
    ap.add_argument("--min-s", type=float, default=3.0)
    ap.add_argument("--max-s", type=float, default=6.0)
    ap.add_argument("--tune", action="store_true", help="search settings on tuning streams")
    ap.add_argument("--tune-streams", type=int, default=18)
    ap.add_argument("--out", type=Path, default=RESULTS / "command_latency.json")
    args = ap.parse_args(argv)

    import torch

    torch.set_num_threads(1)
    from proxima.evaluation.latency import LatencyConfig, measure
    from proxima.evaluation.plots import plot_gestures, plot_latency, plot_stages
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    t_start = time.perf_counter()

    def log(msg: str) -> None:
        print(f"[{time.perf_counter() - t_start:6.0f}s] {msg}", flush=True)

    clf = GestureClassifier.load(args.checkpoint)
    split = clf.metadata.get("split")
    if split != "temporal":
        print(
            f"warning: {args.checkpoint} was trained with split {split!r}, not temporal: "
            "the test parts are not held out",
            file=sys.stderr,
        )
    clips = load_laser_dir(resolve_dataset(args.data))
    result: dict[str, Any] = {
        "benchmark": "command_latency",
        "command": "python -m bench.command_latency " + shlex.join(argv or sys.argv[1:]),
        "checkpoint": {
            "path": str(args.checkpoint),
            "model": clf.model_name,
            "split": split,
            "created": clf.metadata.get("created"),
            "data_sha256": clf.metadata.get("data_sha256"),
        },
        "machine": {
            "cpu": platform.processor() or platform.machine(),
            "cores": os.cpu_count(),
            "torch_threads": 1,
            "python": platform.python_version(),
        },
        "date": time.strftime("%Y-%m-%d"),
    }
    config = LatencyConfig(
        streams=args.streams,
        segments=args.segments,
        min_s=args.min_s,
        max_s=args.max_s,
        tune=args.tune,
        tune_streams=args.tune_streams,
    )
    report = measure(clf, clips, config, log)
    result.update(report.result, seconds=round(time.perf_counter() - t_start, 1))
    summary = result["result"]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    plot_latency(
        report.latencies,
        args.out.with_suffix(".png"),
        f"{summary['stream_hours']:.1f} h of held-out replay, {len(report.latencies)} commands",
    )
    plot_gestures(result["per_view_gesture"], args.out.with_name(args.out.stem + "-gestures.png"))
    plot_stages(report.stages, args.out.with_name(args.out.stem + "-stages.png"))
    log(f"result {summary}")
    log(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
