"""The engine window's clock on `proxima robustness`'s live check (issue 21's latency).

    .venv/bin/python -m bench.window_clock --model runs/window/w30-s0.pt --clocks poses,time
        [--model ...] [--out bench/results/window_clock.json]

Each model runs the live check of `proxima robustness` (36 stitched held-out streams of
the LASER temporal test parts, clean and under `field` 1 at 15-30 fps, the real engine
with the shipped decision settings) once per engine `window_clock` named, and the JSON
keeps the command figures of each (recall, wrong commands, p95 and median
onset-to-command, misses per gesture, per view). Models trained on the temporal split
only (`proxima train --data laser --split temporal --window 30 [--window-clock time]`).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

OUT = Path(__file__).parent / "results" / "window_clock.json"
KEYS = (
    "command_recall",
    "wrong",
    "wrong_per_hour",
    "p95_onset_to_command_s",
    "median_onset_to_command_s",
    "expected_commands",
    "missed_by_gesture",
    "per_view",
)


def run(model: str, clocks: list[str]) -> dict[str, Any]:
    from proxima.engine.config import EngineSettings
    from proxima.evaluation.robustness import RobustnessConfig, live_robustness
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.datasets import load_data

    clf = GestureClassifier.load(model)
    laser = [c for c in load_data(["laser"]).clips if c.source == "laser"]
    out: dict[str, Any] = {"trained_clock": clf.metadata.get("train_config", {}).get(
        "window_clock", "poses")}  # fmt: skip
    for clock in clocks:
        t0 = time.monotonic()
        cfg = RobustnessConfig(engine=EngineSettings(window_clock=clock))  # type: ignore[arg-type]
        live = live_robustness(clf, laser, cfg)
        out[clock] = {k: {key: live[k][key] for key in KEYS} for k in ("clean", "field")}
        out[clock]["wall_s"] = round(time.monotonic() - t0, 1)
        for k in ("clean", "field"):
            v = live[k]
            print(model, clock, k, v["command_recall"], v["wrong"], v["p95_onset_to_command_s"],
                  v["median_onset_to_command_s"], flush=True)  # fmt: skip
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", action="append", required=True, help="checkpoint (repeat)")
    ap.add_argument("--clocks", default="poses,time", help="engine window clocks to run")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    clocks = [c for c in args.clocks.split(",") if c]
    result = {
        "benchmark": "bench.window_clock",
        "command": "python -m bench.window_clock " + " ".join(sys.argv[1:]),
        "models": {m: run(m, clocks) for m in args.model},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
