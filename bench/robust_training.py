"""Issue 21 (items 2 and 3): capture-augmented training and the evidence decision rule.

    python -m bench.robust_training windows --model NAME=CKPT:SPLIT ... --out J
    python -m bench.robust_training streams --checkpoint T.pt --out J [--streams 12]

`windows`: each checkpoint's window accuracy on its split's LASER test parts, as the
engine sees them (captured whole, One Euro smoothed, cut every 5 frames), clean
unsmoothed (what `proxima evaluate` scores), clean smoothed, `field` level 1 and 2
(`proxima.evaluation.robust_training.window_accuracy`; seed 0).
`streams`: stitched held-out streams of the temporal test parts, clean and under `field`
level 1 (captured per clip at 30 fps), through the engine's pipeline (offline replay,
the engine's own code); the evidence rule tuned on tuning streams (seeds 0..) of both
conditions, then the moving average (today's defaults) against it on the evaluation
streams (seeds 1000..); `--by-command` adds per-command evidence thresholds tuned on
the same tuning streams. Several checkpoints joined by commas score as their ensemble
(`proxima.gesture.ensemble`). Writes the JSON to --out.
"""

from __future__ import annotations

import argparse
import json
import pickle
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import torch

from proxima.control import AVERAGE_RULE, ControlSettings
from proxima.engine import load_classifier
from proxima.engine.config import EngineSettings
from proxima.evaluation.latency import evaluate_config
from proxima.evaluation.robust_training import (
    decision_streams,
    pool,
    recognitions,
    summary_row,
    tune_by_command,
    tune_evidence,
    window_accuracy,
)
from proxima.gesture.capture import condition
from proxima.gesture.datasets import load_data
from proxima.gesture.ensemble import members_of
from proxima.gesture.windows import WINDOW, split_clips

CONDITIONS = {
    "clean_unsmoothed": ("clean", 1, False),
    "clean": ("clean", 1, True),
    "field1": ("field", 1, True),
    "field2": ("field", 2, True),
}


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def temperatures(clf: Any) -> list[float]:
    """The softmax temperature of each member (one for a single checkpoint)."""
    return [m.temperature for m in members_of(clf)]


def windows_cmd(args: argparse.Namespace) -> dict:
    data = load_data(["laser"])
    out: dict = {}
    for spec in args.model:
        name, _, rest = spec.partition("=")
        path, _, split = rest.partition(".pt:")  # splits have colons of their own
        path += ".pt"
        clf = load_classifier(path)  # comma-joined: their ensemble
        test = split_clips(data.clips, split, WINDOW).test
        row = {"checkpoint": path, "split": split, "temperature": temperatures(clf)}
        for key, (cond, level, smoothed) in CONDITIONS.items():
            row[key] = window_accuracy(clf, test, condition(cond, level), args.seed, smoothed)
        out[name] = row
        log(f"{name}: " + ", ".join(f"{k} {row[k]['accuracy']}" for k in CONDITIONS))
    return out


def engine_settings(args: argparse.Namespace) -> EngineSettings:
    """The engine settings the streams are recognised with: the defaults, with
    `--max-gap` where given (`streams` has no such option)."""
    gap = getattr(args, "max_gap", None)
    return EngineSettings() if gap is None else EngineSettings(max_gap_s=gap)


def recognised_streams(checkpoint: str, args: argparse.Namespace, cache: Path | None) -> tuple:
    """(tuning sets, evaluation sets): per condition (clean, `field` 1) the stitched
    streams (`args.tune_streams` from seed 0, `args.streams` from seed 1000, of
    `args.segments` gestures) and the checkpoint's recognitions of them, read from
    `cache` when it exists and written there when it does not."""
    if cache is not None and cache.is_file():  # the same checkpoint and stream options
        log(f"recognitions from {cache}")
        return pickle.loads(cache.read_bytes())
    clips = load_data(["laser"]).clips
    clf = load_classifier(checkpoint)  # comma-joined: their ensemble
    settings = engine_settings(args)
    tune_sets, eval_sets = {}, {}
    whole = getattr(args, "whole_stream_capture", False)  # `streams` has no such option
    for key, model in {"clean": condition("clean"), "field1": condition("field", 1)}.items():
        t0 = time.perf_counter()
        s = decision_streams(clips, range(args.tune_streams), args.segments, model, whole)
        tune_sets[key] = (s, recognitions(s, clf, settings))
        s = decision_streams(clips, range(1000, 1000 + args.streams), args.segments, model, whole)
        eval_sets[key] = (s, recognitions(s, clf, settings))
        log(f"{key}: streams recognised in {time.perf_counter() - t0:.0f} s")
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_bytes(pickle.dumps((tune_sets, eval_sets)))
    return tune_sets, eval_sets


def write_doc(out: Path, benchmark: str, module: str, result: dict, t0: float) -> None:
    """The benchmark's JSON: its name, the command that made it, date, result, seconds."""
    doc = {
        "benchmark": benchmark,
        "command": f"python -m bench.{module} " + shlex.join(sys.argv[1:]),
        "date": time.strftime("%Y-%m-%d"),
        "result": result,
        "seconds": round(time.perf_counter() - t0, 1),
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1))
    log(f"wrote {out} ({doc['seconds']} s)")


def streams_cmd(args: argparse.Namespace) -> dict:
    clf = load_classifier(args.checkpoint)
    tune_sets, eval_sets = recognised_streams(args.checkpoint, args, args.cache)
    best, rows = tune_evidence(list(tune_sets.values()))
    log(f"evidence rule selected: {best}")
    keys = ("evidence_threshold", "evidence_half_life_s", "evidence_clip", "confirm")
    params = {k: best[k] for k in keys}
    evidence = ControlSettings(decision="evidence", **params)
    rules = {"average": AVERAGE_RULE, "evidence": evidence}
    result: dict = {"tuning": {"selected": best, "top": rows[:10], "configs": len(rows)}}
    if args.by_command:
        by_best, by_rows = tune_by_command(list(tune_sets.values()), evidence)
        log(f"per-command thresholds selected: {by_best}")
        table = by_best["evidence_threshold_by_command"]
        rules["evidence_by_command"] = evidence.model_copy(
            update={"evidence_threshold_by_command": table}
        )
        result["tuning_by_command"] = {"selected": by_best, "configs": len(by_rows)}
    for rule, control in rules.items():
        per = {}
        for key, (streams, recs) in eval_sets.items():
            per[key] = summary_row(evaluate_config(streams, recs, control))
        tuned = {k: pool([evaluate_config(s, r, control)]) for k, (s, r) in tune_sets.items()}
        result[rule] = {"control": control.model_dump(), "eval": per, "tuning_streams": tuned}
        log(f"{rule}: " + json.dumps({k: {m: v[m] for m in ('hit_rate', 'latency_p95_s', 'wrong')}
                                       for k, v in per.items()}))  # fmt: skip
    hours = {k: round(sum(x.duration_s for x in s) / 3600, 3) for k, (s, _) in eval_sets.items()}
    result["streams"] = {
        "eval_seeds": [1000, 1000 + args.streams - 1],
        "tune_seeds": [0, args.tune_streams - 1],
        "segments": args.segments,
        "eval_hours": hours,
        "checkpoint": args.checkpoint,
        "temperature": temperatures(clf),
    }
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    w = sub.add_parser("windows")
    w.add_argument(
        "--model", action="append", required=True, help="NAME=CKPT.pt[,CKPT.pt...]:SPLIT"
    )
    w.add_argument("--seed", type=int, default=0)
    w.add_argument("--out", type=Path, required=True)
    s = sub.add_parser("streams")
    s.add_argument("--checkpoint", required=True, help="CKPT, or CKPT,CKPT,... (an ensemble)")
    s.add_argument("--streams", type=int, default=12)
    s.add_argument("--tune-streams", type=int, default=6)
    s.add_argument("--segments", type=int, default=40)
    s.add_argument("--out", type=Path, required=True)
    s.add_argument("--cache", type=Path, help="pickle of the recognitions (made if absent)")
    s.add_argument(
        "--by-command",
        action="store_true",
        help="also tune per-command evidence thresholds on the tuning streams",
    )
    args = ap.parse_args()
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    result = windows_cmd(args) if args.cmd == "windows" else streams_cmd(args)
    write_doc(args.out, f"robust_training {args.cmd}", "robust_training", result, t0)


if __name__ == "__main__":
    main()
