"""Calibration to a new view or new people: window accuracy against the seconds of each
held-out clip that train (`--split calibrate:<split>:<seconds>`), on the unseen LASER
view (cross-view:f/l/r) and on UAV-Gesture's unseen people (uav-gesture:1/2/3).

    python -m bench.calibration_curve --group laser   # cross-view:f, l, r
    python -m bench.calibration_curve --group uav     # uav-gesture:1, 2, 3
    python -m bench.calibration_curve --merge         # one JSON and the PNG

Per split: the inner split's model (the 0 s point; `proxima train --split <split>`),
then for each further point both recipes where asked (`--compare`): fine-tuning that
model on train + calibration (`proxima train --init`) and training from scratch on it.
Each point is scored on its own remainder (each held-out clip after its calibration
and a one-window gap; it shrinks as the seconds grow) and on common tails that every
point up to T seconds shares (each clip after T s and the gap), per clip and per person.
Points run in the order --seconds gives (5 first: the target). Writes
bench/results/calibration-curve.<group>.json after every point; --merge writes
calibration-curve.json and calibration-curve.png.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"
RUNS = Path(__file__).resolve().parents[1] / "runs" / "calibration"
GROUPS = {
    "laser": ("laser", ("cross-view:f", "cross-view:l", "cross-view:r")),
    "uav": ("uav-gesture", ("uav-gesture:1", "uav-gesture:2", "uav-gesture:3")),
}
TAILS = (5.0, 10.0)  # common tails: what every point up to 5 s / up to 10 s leaves to test


def score(clf: Any, parts: Sequence[Any], stride: int = 3) -> dict[str, Any]:
    """Window accuracy of `clf` on clip parts: overall, per clip, per person, and the
    clip accuracy (one decision per clip part from its windows' mean probabilities)."""
    from proxima.gesture.train import features, predict_proba
    from proxima.gesture.windows import make_windows

    w = make_windows(list(parts), clf.window, stride, 5)
    if not len(w):
        return {"windows": 0, "clips": 0, "accuracy": None, "per_clip": {}, "per_person": {}}
    probs = predict_proba(clf.model, features(clf.pipeline, w))
    ok = probs.argmax(1) == w.labels
    subject = {p.name: p.subject for p in parts}
    per_clip: dict[str, Any] = {}
    clip_right = []
    for c in np.unique(w.clip):
        sel = w.clip == c
        name = w.clip_names[c]
        right = bool(probs[sel].mean(0).argmax() == w.labels[sel][0])
        clip_right.append(right)
        per_clip[name] = {
            "accuracy": round(float(ok[sel].mean()), 4),
            "windows": int(sel.sum()),
            "clip_right": right,
        }
    people = np.array([subject[w.clip_names[c]] for c in w.clip])
    per_person = {
        str(s): {
            "accuracy": round(float(ok[people == s].mean()), 4),
            "windows": int((people == s).sum()),
        }
        for s in np.unique(people)
    }
    return {
        "windows": len(w),
        "clips": len(per_clip),
        "accuracy": round(float(ok.mean()), 4),
        "clip_accuracy": round(float(np.mean(clip_right)), 4),
        "per_clip": per_clip,
        "per_person": per_person,
    }


def evaluate_point(
    clf: Any, clips: Sequence[Any], uav_dir: Any, inner: str, seconds: float
) -> dict:
    """A model's scores on the point's own remainder and on each common tail."""
    from proxima.gesture.windows import WINDOW, calibration_parts, split_clips

    held_out = split_clips(clips, inner, WINDOW, uav_dir).test
    out: dict[str, Any] = {}
    remainder = [calibration_parts(c, seconds, WINDOW)[1] for c in held_out]
    out["remainder"] = score(clf, [p for p in remainder if len(p)])
    for tail in TAILS:
        if seconds <= tail:
            parts = [calibration_parts(c, tail, WINDOW)[1] for c in held_out]
            out[f"tail_{tail:g}s"] = score(clf, [p for p in parts if len(p)])
    return out


def run_group(args: argparse.Namespace) -> None:
    import torch

    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.datasets import load_data
    from proxima.gesture.train import TrainConfig
    from proxima.gesture.workflow import train_model

    torch.set_num_threads(args.threads)
    data_name, splits = GROUPS[args.group]
    splits = tuple(args.split) if args.split else splits
    data = load_data([data_name])
    out = args.out or RESULTS / f"calibration-curve.{args.group}{args.tag}.json"
    result: dict[str, Any] = json.loads(out.read_text()) if out.exists() and args.resume else {}
    base_cfg = TrainConfig(
        epochs=args.epochs, patience=args.patience, threads=args.threads, seed=args.seed
    )
    if args.share is not None:  # a variant of the calibration's share of each epoch
        base_cfg.calibration_share = args.share
    result.setdefault("config", {}).update(
        epochs=args.epochs, patience=args.patience, tune_epochs=args.tune_epochs,
        threads=args.threads, seed=args.seed, data=data_name, pipeline=args.pipeline,
        share=base_cfg.calibration_share,
        pretrain=str(args.pretrain) if args.pretrain else None,
    )  # fmt: skip
    points = result.setdefault("points", [])
    RUNS.mkdir(parents=True, exist_ok=True)
    tune_cfg = replace(base_cfg, epochs=args.tune_epochs)

    def save() -> None:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result, indent=1))

    def done(split: str, seconds: float, recipe: str) -> bool:
        return any(
            (p["split"], p["seconds"], p["recipe"]) == (split, seconds, recipe) for p in points
        )

    def record(split: str, seconds: float, recipe: str, ckpt: Path, t: float, epochs: int) -> None:
        clf = GestureClassifier.load(ckpt)
        row = {"split": split, "seconds": seconds, "recipe": recipe,
               "train_seconds": round(t, 1), "epochs": epochs,
               **evaluate_point(clf, data.clips, data.uav_dir, split, seconds)}  # fmt: skip
        points.append(row)
        save()
        tails = {k: v["accuracy"] for k, v in row.items() if k.startswith("tail")}
        rem = row["remainder"]
        print(f"{split} {seconds:g}s {recipe}: remainder {rem['accuracy']} "
              f"({rem['windows']} windows) tails {tails} [{t:.0f} s]", flush=True)  # fmt: skip

    base: dict[str, Path] = {}
    pipe = args.pipeline
    tag = args.tag  # a variant's fine-tuned checkpoints apart from the main run's
    # inner models are shared by every variant with the same pipeline and start
    base_tag = (f"-{pipe}" if pipe and pipe != "body" else "") + (
        f"-pre-{args.pretrain.stem}" if args.pretrain else ""
    )
    for split in splits:  # the inner models: the 0 s point and what fine-tuning starts from
        ckpt = RUNS / f"base-{split.replace(':', '-')}-s{args.seed}{base_tag}.pt"
        if not ckpt.exists():
            t0 = time.perf_counter()
            r = train_model([data_name], "tcn", split, ckpt, replace(base_cfg), pipe,
                            init=args.pretrain)  # fmt: skip
            t, n = time.perf_counter() - t0, len(r.history)
        else:
            t, n = 0.0, 0
        base[split] = ckpt
        if not done(split, 0.0, "inner"):
            record(split, 0.0, "inner", ckpt, t, n)
    for seconds in args.seconds:
        if seconds == 0:
            continue
        for recipe in args.recipes if seconds in args.compare else args.recipes[:1]:
            for split in splits:
                if done(split, seconds, recipe):
                    continue
                cal = f"calibrate:{split}:{seconds:g}"
                name = f"{recipe}-{split.replace(':', '-')}-{seconds:g}s-s{args.seed}{tag}.pt"
                ckpt = RUNS / name
                t0 = time.perf_counter()
                if recipe == "finetune":
                    r = train_model([data_name], "tcn", cal, ckpt, replace(tune_cfg), pipe,
                                    init=base[split])  # fmt: skip
                else:
                    r = train_model([data_name], "tcn", cal, ckpt, replace(base_cfg), pipe)
                record(split, seconds, recipe, ckpt, time.perf_counter() - t0, len(r.history))


def merge() -> None:
    """calibration-curve.json (both groups) and calibration-curve.png."""
    merged: dict[str, Any] = {"groups": {}}
    for group in GROUPS:
        # a group's main run and any runs beside it (`--tag`), each point once
        for f in sorted(RESULTS.glob(f"calibration-curve.{group}*.json")):
            res = json.loads(f.read_text())
            into = merged["groups"].setdefault(group, {"config": res["config"], "points": []})
            have = {(p["split"], p["seconds"], p["recipe"]) for p in into["points"]}
            into["points"] += [
                p for p in res["points"] if (p["split"], p["seconds"], p["recipe"]) not in have
            ]
    (RESULTS / "calibration-curve.json").write_text(json.dumps(merged, indent=1))
    plot(merged, RESULTS / "calibration-curve.png")
    print(table(merged))
    print(f"wrote {RESULTS / 'calibration-curve.json'} and .png")


def table(merged: dict[str, Any]) -> str:
    """Markdown: one row per split, seconds and recipe; remainder and tails, with the
    windows and clips each is scored on, and the worst person's remainder accuracy."""

    def cell(r: dict[str, Any] | None) -> str:
        if not r or r["accuracy"] is None:
            return "-"
        return f"{r['accuracy']:.3f} ({r['windows']} w, {r['clips']} clips)"

    lines = [
        "| split | s | recipe | remainder | tail after 5 s | tail after 10 s | clip acc. "
        "(remainder) | worst person / clip (remainder) | epochs |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for res in merged["groups"].values():
        for p in sorted(res["points"], key=lambda p: (p["split"], p["seconds"], p["recipe"])):
            rem = p["remainder"]
            worst = "-"
            if rem.get("per_person") and len(rem["per_person"]) > 1:
                name, v = min(rem["per_person"].items(), key=lambda kv: kv[1]["accuracy"])
                worst = f"{name} {v['accuracy']:.3f}"
            elif rem.get("per_clip"):
                name, v = min(rem["per_clip"].items(), key=lambda kv: kv[1]["accuracy"])
                worst = f"{name} {v['accuracy']:.3f}"
            lines.append(
                f"| {p['split']} | {p['seconds']:g} | {p['recipe']} | {cell(rem)} | "
                f"{cell(p.get('tail_5s'))} | {cell(p.get('tail_10s'))} | "
                f"{rem.get('clip_accuracy', '-')} | {worst} | {p['epochs'] or 'cached'} |"
            )
    return "\n".join(lines)


def plot(merged: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = merged["groups"]
    fig, axes = plt.subplots(1, max(len(groups), 1), figsize=(6 * max(len(groups), 1), 4.2),
                             squeeze=False)  # fmt: skip
    for ax, (group, res) in zip(axes[0], groups.items(), strict=False):
        rows = res["points"]
        for i, split in enumerate(dict.fromkeys(p["split"] for p in rows)):
            colour = f"C{i}"
            for recipe, marker in (("finetune", "o"), ("scratch", "s")):
                pts = sorted(
                    (p for p in rows if p["split"] == split
                     and (p["recipe"] in (recipe, "inner"))),
                    key=lambda p: p["seconds"],
                )  # fmt: skip
                if len(pts) < 2:
                    continue
                xs = [p["seconds"] for p in pts]
                style = "-" if recipe == "finetune" else ":"
                ax.plot(xs, [p["remainder"]["accuracy"] for p in pts], style, marker=marker,
                        color=colour, label=f"{split} {recipe} (remainder)")  # fmt: skip
                tail = [(p["seconds"], p.get("tail_5s", {}).get("accuracy")) for p in pts]
                tail = [(x, y) for x, y in tail if y is not None]
                if recipe == "finetune" and tail:
                    ax.plot(*zip(*tail, strict=True), "--", marker=marker, color=colour,
                            alpha=0.6, label=f"{split} (tail after 5 s)")  # fmt: skip
        ax.axhline(0.95, color="grey", lw=0.8)
        ax.set_xlabel("calibration seconds per held-out clip")
        ax.set_ylabel("window accuracy")
        ax.set_title(group)
        ax.set_ylim(0, 1.02)
        ax.legend(fontsize=6, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--group", choices=sorted(GROUPS))
    ap.add_argument("--split", action="append", help="only these inner splits of the group")
    ap.add_argument("--merge", action="store_true")
    ap.add_argument("--seconds", type=float, nargs="+", default=[5.0, 0.0, 2.0, 10.0])
    ap.add_argument(
        "--recipes", nargs="+", default=["finetune", "scratch"],
        help="the first is the curve's; the others run at --compare points",
    )  # fmt: skip
    ap.add_argument("--compare", type=float, nargs="*", default=[5.0])
    ap.add_argument("--epochs", type=int, default=20, help="inner and scratch models")
    ap.add_argument("--patience", type=int, default=5)
    ap.add_argument("--tune-epochs", type=int, default=12)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--resume", action="store_true", help="keep the points already in the JSON")
    ap.add_argument(
        "--out",
        type=Path,
        default=None,
        help="the group's JSON (default: bench/results/calibration-curve."
        "<group><tag>.json, which --merge reads; a variant goes elsewhere)",
    )
    ap.add_argument("--share", type=float, default=None,
                    help="the calibration clips' share of each epoch (default: "
                    "TrainConfig.calibration_share)")  # fmt: skip
    ap.add_argument("--pipeline", default=None, help="body (default) or body-image")
    ap.add_argument("--pretrain", type=Path, default=None,
                    help="inner models start from this checkpoint (e.g. the synthetic "
                    "operator's model)")  # fmt: skip
    ap.add_argument("--tag", default="", help="write calibration-curve.<group><tag>.json "
                    "(and name a variant's fine-tuned checkpoints)")  # fmt: skip
    args = ap.parse_args(argv)
    if args.merge:
        merge()
    elif args.group:
        run_group(args)
    else:
        ap.error("give --group or --merge")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
