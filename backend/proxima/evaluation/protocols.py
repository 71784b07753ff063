"""The evaluation protocols behind the model card and the README's results table: train
on each split's training part with `proxima train`'s code, score on its test part."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from proxima.evaluation.metrics import evaluate_checkpoint
from proxima.gesture.train import TrainConfig
from proxima.gesture.windows import parse_calibration
from proxima.gesture.workflow import train_model

LASER_PROTOCOLS = ("temporal", "cross-view:f", "cross-view:l", "cross-view:r")
UAV_PROTOCOLS = ("uav-gesture:1", "uav-gesture:2", "uav-gesture:3")


def run_protocols(
    splits: Sequence[str],
    model: str,
    data: Sequence[str] | None,
    cfg: TrainConfig,
    eval_data: Sequence[str] | None = None,
    on_result: Callable[[dict[str, Any]], None] | None = None,
    keep_dir: Path | None = None,
) -> list[dict[str, Any]]:
    """Train and evaluate once per split. `eval_data` (default: `data`) picks the test
    set: e.g. train on LASER + UAV-Gesture but score the temporal split on LASER only."""
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for split in splits:
            folder = keep_dir or Path(tmp)
            ckpt = folder / f"{model}-{split.replace(':', '-')}.pt"
            tr = train_model(data, model, split, ckpt, replace(cfg))
            inner = (parse_calibration(split) or (split, 0.0))[0]
            ev_data = data if inner.startswith("uav-gesture") else (eval_data or data)
            m = evaluate_checkpoint(ckpt, ev_data, split)
            row = {
                "split": split,
                "model": model,
                "accuracy": m["accuracy"],
                "macro_f1": m["macro_f1"],
                "clip_accuracy": m["clip_accuracy"],
                "windows": m["windows"],
                "epochs": len(tr.history),
                "train_seconds": round(tr.seconds, 1),
            }
            results.append(row)
            if on_result:
                on_result(row)
    return results


def results_table(rows: Sequence[dict[str, Any]]) -> str:
    """A Markdown table of protocol results."""
    lines = [
        "| model | split | window accuracy | macro F1 | clip accuracy | test windows |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['split']} | {r['accuracy']:.3f} | {r['macro_f1']:.3f} | "
            f"{r['clip_accuracy']:.3f} | {r['windows']} |"
        )
    return "\n".join(lines)


def save_results(rows: Sequence[dict[str, Any]], path: Path) -> None:
    """Write protocol results as a JSON list (the model card reads them back)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(list(rows), indent=1))
