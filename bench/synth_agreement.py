"""Does each synthetic gesture look like the real one? The nearest real class of every
synthetic window, by a model trained on real clips only.

Synthetic clips are made with `proxima.synth` (the same code as `proxima synth`) for
the three LASER-like views, cut into 60-frame windows, and classified by a checkpoint
whose training data were real recordings only (LASER and / or UAV-Gesture; checked from
its metadata, refused otherwise). A gesture's agreement is the share of its windows the
model names as that gesture; a gesture with poor agreement has a motion unlike the real
one, whichever way the model reads it.

    python -m bench.synth_agreement [--checkpoint models/gesture-default.pt]
        [--scenes-per-view 6] [--seed 1] [--view front:-20..20:0..10 ...]

Writes bench/results/synth_agreement.json (per gesture, per view, where the windows go,
generation time per clip).
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.data_source import DATASETS
from proxima.gesture.windows import make_windows, window_starts
from proxima.synth.dataset import generate, is_synth_dir, load_synth_dir
from proxima.synth.views import DEFAULT_VIEWS, parse_view
from proxima.types import GESTURES

RESULTS = Path(__file__).resolve().parent / "results"
REAL_FOLDERS = {info.shared_dir for info in DATASETS.values()}


def trained_on_real_only(metadata: dict[str, Any]) -> tuple[bool, list[str]]:
    """Whether a checkpoint's training data were the real data sets only, and the
    folders it names."""
    folders = [str(f) for f in metadata.get("data", [])]
    ok = bool(folders) and all(
        Path(f).name in REAL_FOLDERS and not (Path(f).exists() and is_synth_dir(f)) for f in folders
    )
    return ok, folders


def agreement(
    checkpoint: Path | None, views: list[str], scenes_per_view: int, seed: int, stride: int
) -> dict[str, Any]:
    import torch

    from proxima.evaluation.metrics import window_probs
    from proxima.gesture.classifier import default_checkpoint
    from proxima.gesture.ensemble import load_checkpoint, members_of

    torch.set_num_threads(1)
    ckpt = checkpoint or default_checkpoint()
    clf = load_checkpoint(ckpt)  # one model or an ensemble (the shipped one)
    checks = [trained_on_real_only(m.metadata) for m in members_of(clf)]
    ok, folders = all(c[0] for c in checks), sorted({f for c in checks for f in c[1]})
    if not ok:
        raise SystemExit(f"{ckpt}: not trained on real data only (data: {folders})")
    view_ranges = [parse_view(v) for v in views]
    n_clips = len(GESTURES) * scenes_per_view * len(view_ranges)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        manifest = generate(Path(tmp) / "synth", n_clips, seed, view_ranges)
        gen_s = time.perf_counter() - t0
        clips = load_synth_dir(Path(tmp) / "synth")
    entries = {e["name"]: e for e in manifest["clip_list"]}
    view_of = {name: e["view_name"] for name, e in entries.items()}
    w = make_windows(clips, clf.window, stride, max_gap=5)
    # Windows that start once the gesture itself runs (after the move out of the idle
    # stance): make_windows cuts them in this order.
    steady = np.concatenate(
        [
            [
                c.frames[s] - 1 >= entries[c.name]["segments"][1]["onset"]
                for s in window_starts(c.frames, clf.window, stride, 5)[0]
            ]
            for c in clips
        ]
    ).astype(bool)
    t1 = time.perf_counter()
    probs = window_probs(clf, w)
    score_s = time.perf_counter() - t1
    pred = probs.argmax(axis=1)
    views_w = np.array([view_of[w.clip_names[c]] for c in w.clip])
    per_gesture: dict[str, Any] = {}
    for g, name in enumerate(GESTURES):
        sel = w.labels == g
        goes = Counter(GESTURES[p] for p in pred[sel])
        per_gesture[name] = {
            "windows": int(sel.sum()),
            "agreement": round(float(np.mean(pred[sel] == g)), 3),
            "steady_agreement": round(float(np.mean(pred[sel & steady] == g)), 3),
            "own_probability": round(float(probs[sel, g].mean()), 3),
            "read_as": {k: round(v / sel.sum(), 3) for k, v in goes.most_common(3)},
            "per_view": {
                v.name: round(float(np.mean(pred[sel & (views_w == v.name)] == g)), 3)
                for v in view_ranges
                if np.any(sel & (views_w == v.name))
            },
        }
    per_view = {
        v.name: round(float(np.mean(pred[views_w == v.name] == w.labels[views_w == v.name])), 3)
        for v in view_ranges
    }
    return {
        "command": "python -m bench.synth_agreement " + shlex.join(sys.argv[1:]),
        "checkpoint": str(ckpt),
        "checkpoint_data": folders,
        "checkpoint_command": clf.metadata.get("command", ""),
        "views": [v.spec() for v in view_ranges],
        "seed": seed,
        "clips": len(clips),
        "windows": len(w),
        "stride": stride,
        "agreement": round(float(np.mean(pred == w.labels)), 3),
        "steady_agreement": round(float(np.mean(pred[steady] == w.labels[steady])), 3),
        "steady_windows": int(steady.sum()),
        "mean_gesture_agreement": round(
            float(np.mean([r["agreement"] for r in per_gesture.values()])), 3
        ),
        "per_view": per_view,
        "per_gesture": per_gesture,
        "generate_seconds": round(gen_s, 2),
        "seconds_per_clip": round(gen_s / n_clips, 4),
        "frames": int(sum(len(c) for c in clips)),
        "score_seconds": round(score_s, 2),
    }


def table(result: dict[str, Any]) -> str:
    """The per-gesture agreement as a Markdown table (per view; "after onset": windows
    that start once the gesture runs, past the move out of the idle stance)."""
    views = list(result["per_view"])
    lines = [
        "| gesture | agreement | after onset | " + " | ".join(views) + " | read as (share) |",
        "|---|---|---|" + "---|" * len(views) + "---|",
    ]
    for g, r in result["per_gesture"].items():
        read = ", ".join(f"{k} {v:.2f}" for k, v in r["read_as"].items())
        cells = " | ".join(f"{r['per_view'].get(v, float('nan')):.2f}" for v in views)
        lines.append(
            f"| {g} | {r['agreement']:.2f} | {r['steady_agreement']:.2f} | {cells} | {read} |"
        )
    cells = " | ".join(f"{result['per_view'][v]:.2f}" for v in views)
    lines.append(
        f"| all windows | {result['agreement']:.2f} | {result['steady_agreement']:.2f} "
        f"| {cells} | |"
    )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--checkpoint", type=Path, default=None)
    ap.add_argument(
        "--view",
        action="append",
        default=None,
        help="view range (repeatable); default: the three LASER-like views",
    )
    ap.add_argument("--scenes-per-view", type=int, default=6)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--stride", type=int, default=5)
    ap.add_argument("--out", type=Path, default=RESULTS / "synth_agreement.json")
    args = ap.parse_args(argv)
    views = args.view or [v.spec() for v in DEFAULT_VIEWS]
    result = agreement(args.checkpoint, views, args.scenes_per_view, args.seed, args.stride)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    print(table(result))
    print(
        f"{result['clips']} clips, {result['windows']} windows; generation "
        f"{result['seconds_per_clip'] * 1000:.0f} ms a clip; -> {args.out}"
    )


if __name__ == "__main__":
    main()
