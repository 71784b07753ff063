"""Gesture model speed: inference latency for one window (batch 1, median of 200 after
warm-up, 1 and 2 torch threads) and training time per epoch, for each model.

    .venv/bin/python -m bench.gesture_inference [--epochs 2] [--out PATH]

Writes bench/results/gesture_inference.json. Absolute times on this shared 2-core machine
are noisy; the ratios between models and thread counts are the stable part.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np
import torch

from proxima.gesture.datasets import load_data
from proxima.gesture.features import make_pipeline
from proxima.gesture.geometry import to_metric
from proxima.gesture.models import DEFAULT_PIPELINE, MODELS, build_model
from proxima.gesture.train import TrainConfig, fit
from proxima.gesture.windows import make_windows, split_clips

OUT = Path(__file__).parent / "results" / "gesture_inference.json"


def latency_ms(model: torch.nn.Module, x: torch.Tensor, threads: int, n: int = 200) -> dict:
    torch.set_num_threads(threads)
    model.eval()
    times = []
    with torch.no_grad():
        for _ in range(20):
            model(x)
        for _ in range(n):
            t0 = time.perf_counter()
            model(x)
            times.append((time.perf_counter() - t0) * 1000)
    return {"median_ms": float(np.median(times)), "p95_ms": float(np.percentile(times, 95))}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--epochs", type=int, default=2, help="epochs timed per model")
    ap.add_argument("--out", type=Path, default=OUT, help="results JSON")
    args = ap.parse_args()
    data = load_data(None)
    parts = split_clips(data.clips, "temporal")
    w = make_windows(parts.train, stride=3)
    results: dict = {
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "torch": torch.__version__},
        "load_average_at_start": os.getloadavg()[0],
        "train_windows": len(w),
        "models": {},
    }  # fmt: skip
    for name in MODELS:
        pipe = make_pipeline(DEFAULT_PIPELINE[name]).fit(to_metric(w.xyz, w.aspect))
        model = build_model(name, num_features=pipe.num_features)
        x = torch.from_numpy(pipe.transform(to_metric(w.xyz[:1], w.aspect[:1]), w.has_z[:1]))
        entry = {
            "parameters": sum(p.numel() for p in model.parameters()),
            "latency_1_thread": latency_ms(model, x, 1),
            "latency_2_threads": latency_ms(model, x, 2),
        }
        cfg = TrainConfig(epochs=args.epochs, threads=2)
        hist = fit(model, pipe, w, None, cfg)
        entry["train_seconds_per_epoch"] = float(np.median([h.seconds for h in hist]))
        results["models"][name] = entry
        print(name, json.dumps(entry))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=1))
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
