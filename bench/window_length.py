"""Issue 21's latency lever: the window length. Held-out temporal-split models trained
with `proxima train --window N` (seeds as given), each scored as `proxima evaluate`
scores it and on the stitched held-out streams of `bench.robust_training streams`
(12 evaluation streams, 6 tuning streams, 30 gestures each, clean and `field` level 1),
with four decision rules: the evidence rule tuned on the tuning streams, the moving
average at the model's fitted temperature, the moving average at T = 1 (the shipped
decision until 2026-12-05) and the shipped defaults (`ControlSettings()`, the evidence
rule since then); headline figures per view as well. With several seeds, also
one evidence setting for all of them (`evidence_shared`: tuned on every seed's tuning
streams pooled), as a shipped default would have to be.

    proxima train --data laser --split temporal --epochs 60 --patience 15 --threads 1 \
        --seed S --window N --out runs/window/wN-sS.pt          # about 4-6 min each
    python -m bench.window_length --model 30=runs/window/w30-s0.pt,... \
        --model 60=runs/window/w60-s0.pt,... --cache-dir runs/window \
        --out bench/results/window_length.json

The recognitions of each checkpoint are cached in --cache-dir (`recs-<stem>.pkl`, the
same pickle `bench.robust_training streams --cache` writes), so a rerun only re-scores.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from bench.robust_training import engine_settings, log, recognised_streams, write_doc
from bench.robust_untempered import untempered
from proxima.control import AVERAGE_RULE, ControlSettings
from proxima.engine import load_classifier
from proxima.evaluation.latency import evaluate_config, rank
from proxima.evaluation.metrics import evaluate_checkpoint
from proxima.evaluation.robust_training import pool, summary_row, tune_evidence

EVIDENCE_KEYS = ("evidence_threshold", "evidence_half_life_s", "evidence_clip", "confirm")
HEADLINE = ("hit_rate", "on_time_rate", "latency_median_s", "latency_p95_s", "wrong", "repeats")
VIEWS = "flr"  # decision_streams deals the views f, l, r in turn


def cache_path(checkpoint: str, args: argparse.Namespace) -> Path:
    """`recs-<stem>.pkl` for the default streams; other stream options name their own
    file, so a cache is never read for streams it does not hold. The engine's pause
    limit too: caches made while it was 0.25 s carry no mark, others `-gapS`."""
    sizes = (args.tune_streams, args.streams, args.segments)
    tail = "" if sizes == (6, 12, 30) else "-t{}-e{}-g{}".format(*sizes)
    tail += "-whole" if args.whole_stream_capture else ""
    gap = engine_settings(args).max_gap_s
    tail += f"-gap{gap:g}" if gap != 0.25 else ""
    return args.cache_dir / f"recs-{Path(checkpoint).stem}{tail}.pkl"


def headline_of(summary: dict[str, Any]) -> dict[str, Any]:
    """The headline figures of one score summary (`latency.evaluate_config`)."""
    row = summary_row(summary)
    return {k: row[k] for k in HEADLINE}


def headline(streams: list, recs: list, control: ControlSettings) -> dict[str, Any]:
    return headline_of(evaluate_config(streams, recs, control))


def score_rule(eval_sets: dict, control: ControlSettings, temperature: float | None) -> dict:
    """Headline figures per condition, overall and per view (`temperature`: undo it)."""
    out: dict[str, Any] = {}
    for key, (streams, recs) in eval_sets.items():
        if temperature is not None:
            recs = [untempered(r, temperature) for r in recs]
        out[key] = headline(streams, recs, control)
        out[key]["per_view"] = {
            v: headline(streams[k :: len(VIEWS)], recs[k :: len(VIEWS)], control)
            for k, v in enumerate(VIEWS)
        }
    return out


def mean_headline(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Each headline figure's mean over rows (None where a row has none)."""
    return {
        k: round(float(np.mean(v)), 3)
        for k in HEADLINE
        if (v := [r[k] for r in rows if r[k] is not None])
    }


def shared_evidence(sets: list[tuple]) -> dict[str, Any]:
    """One evidence setting for every seed (what a shipped default would be): the grid
    ranked on all seeds' tuning streams pooled, then each seed's evaluation streams."""
    best, _ = tune_evidence([s for tune_sets, _ in sets for s in tune_sets.values()])
    control = ControlSettings(decision="evidence", **{k: best[k] for k in EVIDENCE_KEYS})
    per_seed = [score_rule(eval_sets, control, None) for _, eval_sets in sets]
    mean = {cond: mean_headline([p[cond] for p in per_seed]) for cond in ("clean", "field1")}
    return {"setting": {k: best[k] for k in EVIDENCE_KEYS}, "per_seed": per_seed, "mean": mean}


def score_checkpoint(checkpoint: str, sets: tuple) -> dict[str, Any]:
    """Window accuracy, then the three rules on the checkpoint's recognised streams."""
    clf = load_classifier(checkpoint)
    temperature = float(getattr(clf, "temperature", 1.0))  # an ensemble has none: T = 1
    windows = evaluate_checkpoint(checkpoint, ["laser"], "temporal")
    tune_sets, eval_sets = sets
    best, _ = tune_evidence(list(tune_sets.values()))
    evidence = ControlSettings(decision="evidence", **{k: best[k] for k in EVIDENCE_KEYS})
    return {
        "checkpoint": checkpoint,
        "window": clf.window,
        "temperature": temperature,
        "window_accuracy": windows["accuracy"],
        "window_accuracy_per_view": {v: r["accuracy"] for v, r in windows["per_view"].items()},
        "evidence_setting": {k: best[k] for k in EVIDENCE_KEYS},
        "evidence": score_rule(eval_sets, evidence, None),
        "average_fitted_T": score_rule(eval_sets, AVERAGE_RULE, None),
        "average_T1": score_rule(eval_sets, AVERAGE_RULE, temperature),
        "defaults": score_rule(eval_sets, ControlSettings(), None),
        "stream_hours": {
            k: round(sum(x.duration_s for x in s) / 3600, 3) for k, (s, _) in eval_sets.items()
        },
    }


def add_stream_args(ap: argparse.ArgumentParser) -> None:
    """The held-out streams' size and the recognitions' cache folder."""
    ap.add_argument("--streams", type=int, default=12)
    ap.add_argument("--tune-streams", type=int, default=6)
    ap.add_argument("--segments", type=int, default=30)
    ap.add_argument("--cache-dir", type=Path, default=Path("runs/window"))
    ap.add_argument("--whole-stream-capture", action="store_true",
                    help="capture each stitched stream in one draw at the drawn frame rate "
                    "(15-30 fps under field), as proxima robustness does; default: each "
                    "clip at 30 fps")  # fmt: skip
    ap.add_argument("--max-gap", type=float, default=None, metavar="S",
                    help="the engine's max_gap_s for the recognitions (default: the "
                    "engine's; 0.25: the window restarts as it did until 2026-12-06)")  # fmt: skip


def held_out_sets(checkpoints: list[str], args: argparse.Namespace) -> list[tuple]:
    """Each checkpoint's (tuning, evaluation) recognised streams, cached."""
    return [recognised_streams(c, args, cache_path(c, args)) for c in checkpoints]


def held_out_start(
    ap: argparse.ArgumentParser, out: Path, **defaults: Any
) -> tuple[argparse.Namespace, list[str], list[tuple], float]:
    """The start the benchmarks over the held-out seeds share: `--model CKPT,CKPT,...`,
    the stream options (`defaults` overrides theirs) and `--out` parsed after `ap`'s
    own options, one torch thread, and each seed's cached (tuning, evaluation) sets.
    Returns (args, checkpoints, sets, start time)."""
    ap.add_argument("--model", required=True, help="CKPT,CKPT,...: the held-out seeds")
    add_stream_args(ap)
    ap.add_argument("--out", type=Path, default=out)
    ap.set_defaults(**defaults)  # after the options: argparse keeps an option's own default
    args = ap.parse_args()
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    checkpoints = args.model.split(",")
    return args, checkpoints, held_out_sets(checkpoints, args), t0


TUNING_KEYS = ("hit_rate", "on_time_rate", "wrong_or_spurious_per_hour")


def score_setting(sets: list[tuple], control: ControlSettings) -> dict[str, Any]:
    """One decision setting over several seeds: its figures on their tuning streams
    pooled, its `latency.rank` there, and its evaluation figures' mean over the seeds."""
    tune = pool([evaluate_config(s, r, control) for ts, _ in sets for s, r in ts.values()])
    per_seed = [score_rule(es, control, None) for _, es in sets]
    mean = {c: mean_headline([p[c] for p in per_seed]) for c in ("clean", "field1")}
    return {"tuning": {k: tune.get(k) for k in TUNING_KEYS}, "rank": list(rank(tune)),
            "eval_mean": mean}  # fmt: skip


def means(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per rule and condition, each headline figure's mean over the seeds."""
    accuracy = float(np.mean([r["window_accuracy"] for r in rows]))
    out: dict[str, Any] = {"window_accuracy": round(accuracy, 4)}
    for rule in ("evidence", "average_fitted_T", "average_T1", "defaults"):
        for cond in ("clean", "field1"):
            out[f"{rule}/{cond}"] = mean_headline([r[rule][cond] for r in rows])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", action="append", required=True,
                    help="LABEL=CKPT[,CKPT...]: the seeds of one window length")  # fmt: skip
    add_stream_args(ap)
    ap.add_argument("--out", type=Path, default=Path("bench/results/window_length.json"))
    args = ap.parse_args()
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    result: dict[str, Any] = {}
    for spec in args.model:
        label, _, paths = spec.partition("=")
        checkpoints = paths.split(",")
        sets = held_out_sets(checkpoints, args)
        rows = []
        for path, recognised in zip(checkpoints, sets, strict=True):
            log(f"{label}: {path}")
            rows.append(score_checkpoint(path, recognised))
        result[label] = {"seeds": rows, "mean": means(rows)}
        if len(rows) > 1:
            result[label]["evidence_shared"] = shared_evidence(sets)
        log(f"{label}: {json.dumps(result[label]['mean'])}")
    write_doc(args.out, "window_length", "window_length", result, t0)


if __name__ == "__main__":
    main()
