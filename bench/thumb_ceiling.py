"""How much of the error is the thumb? all_clear and not_clear are the same raised right
arm, thumb up or thumb down (the marshalling signals they come from). UAV-Gesture's
OpenPose joints hold no hand points, and the LASER left view hides the right hand behind
the body (MediaPipe guesses it). Each split's held-out model is scored as `proxima
evaluate` scores it (`evaluate_checkpoint`); from its confusion matrix this reports the
window accuracy, the accuracy with the two counted as one gesture, and the share of
errors between them.

    python -m bench.thumb_ceiling --checkpoint SPLIT=PATH [--checkpoint ...]
        [--streams 12 --segments 30] [--out bench/results/thumb_ceiling.json]

SPLIT is any split `proxima evaluate` takes (uav-gesture:N scores UAV-Gesture, every
other LASER); PATH a model that never saw the split's test part (e.g. `proxima train
--data uav-gesture --split uav-gesture:1 ...`). `--streams N` also counts, in the
stitched held-out streams of `python -m bench.robust_training streams` (seeds 1000 on,
views f, l, r in turn), the gestures per view: a left-view all_clear or not_clear is a
command whose deciding hand that camera does not see.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from proxima.evaluation.metrics import evaluate_checkpoint
from proxima.types import GESTURES

RESULTS = Path(__file__).resolve().parent / "results"
THUMB = ("all_clear", "not_clear")
PAIR = tuple(GESTURES.index(g) for g in THUMB)


def thumb_figures(confusion: np.ndarray) -> dict[str, float]:
    """Accuracy, accuracy with the pair merged, the pair's share of the errors, and each
    of the two gestures' recall, from a confusion matrix (rows: true gesture)."""
    a, n = PAIR
    total = confusion.sum()
    right = np.trace(confusion)
    between = confusion[a, n] + confusion[n, a]
    errors = total - right
    return {
        "windows": int(total),
        "accuracy": float(right / total),
        "accuracy_pair_merged": float((right + between) / total),
        "pair_share_of_errors": float(between / errors) if errors else 0.0,
        "pair_share_of_windows": float(confusion[[a, n]].sum() / total),
        "all_clear_recall": float(confusion[a, a] / max(confusion[a].sum(), 1)),
        "not_clear_recall": float(confusion[n, n] / max(confusion[n].sum(), 1)),
    }


def stream_gestures(streams: int, segments: int) -> dict[str, Any]:
    """Gestures per view in the stitched held-out streams (no classifier involved)."""
    from proxima.evaluation.robust_training import decision_streams
    from proxima.gesture.capture import condition
    from proxima.gesture.datasets import load_data

    clips = load_data(["laser"]).clips
    out: dict[str, Any] = {}
    for st in decision_streams(clips, range(1000, 1000 + streams), segments, condition("field", 1)):
        view = out.setdefault(st.view, {"segments": 0, "thumb": 0})
        view["segments"] += len(st.segments)
        view["thumb"] += sum(seg.gesture in THUMB for seg in st.segments)
    total = sum(v["segments"] for v in out.values())
    out["left_thumb_share"] = out["l"]["thumb"] / total if total else 0.0
    return out


def evaluate(checkpoint: str, split: str) -> tuple[dict[str, Any], str]:
    """One checkpoint's metrics on one split, and the `proxima evaluate` command that
    writes the same metrics."""
    data = "uav-gesture" if "uav-gesture" in split else "laser"
    command = f"proxima evaluate --checkpoint {checkpoint} --data {data} --split {split} --json J"
    return evaluate_checkpoint(checkpoint, [data], split), command


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--checkpoint", action="append", required=True, metavar="SPLIT=PATH")
    ap.add_argument("--streams", type=int, default=0, help="held-out streams to count")
    ap.add_argument("--segments", type=int, default=30, help="gestures a stream")
    ap.add_argument("--out", type=Path, default=RESULTS / "thumb_ceiling.json")
    args = ap.parse_args(argv)
    rows = []
    for item in args.checkpoint:
        split, sep, path = item.partition("=")
        if not sep:
            ap.error(f"--checkpoint {item!r}: expected SPLIT=PATH")
        metrics, command = evaluate(path, split)
        row = {"split": split, "checkpoint": path, "command": command}
        row |= thumb_figures(np.asarray(metrics["confusion"]))
        rows.append(row)
        print(f"{split}: accuracy {row['accuracy']:.3f}, all_clear + not_clear as one "
              f"{row['accuracy_pair_merged']:.3f} ({row['pair_share_of_errors']:.0%} of the "
              f"errors are between them)")  # fmt: skip
    mean = {k: float(np.mean([r[k] for r in rows]))
            for k in ("accuracy", "accuracy_pair_merged", "pair_share_of_errors")}  # fmt: skip
    result: dict[str, Any] = {"benchmark": "thumb_ceiling", "argv": sys.argv[1:], "rows": rows,
                              "mean": mean}  # fmt: skip
    if args.streams:
        counts = stream_gestures(args.streams, args.segments)
        result["streams"] = counts
        share = counts["left_thumb_share"]
        print(f"held-out streams: {share:.1%} of the gestures are left-view all_clear / not_clear")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(
        f"mean accuracy {mean['accuracy']:.3f}, pair merged {mean['accuracy_pair_merged']:.3f} "
        f"-> {args.out}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
