"""Commands against wrong commands as the evidence threshold moves: held-out models alone
or as ensembles, on `bench.decision_check`'s held-out evaluation streams (48 per seed and
condition; recognitions cached as that bench caches them).

    python -m bench.operating_curve --whole-stream-capture \
        --curve w30=runs/window/w30-s0.pt,runs/window/w30-s1.pt,runs/window/w30-s2.pt \
        --curve 'w30x3=runs/window/w30-s0.pt+runs/window/w30-s1.pt+runs/window/w30-s2.pt' \
        --thresholds 12,14,16,18,20 --out bench/results/operating_curve.json \
        [--set 'confirm_by_command={"land": 3}']

A curve is LABEL=MODEL,MODEL,...: its figures pool the models' streams (a seed's hours
each). A MODEL of `+`-joined checkpoints is their ensemble, the mean of the members'
calibrated probabilities, which is what the engine runs for `--checkpoint a.pt,b.pt`
(`gesture.ensemble`), here taken from each member's cached recognitions. Every other
decision setting is the shipped default, and `have_command`'s threshold keeps its
default share of the base threshold (12 of 18 since 2026-12-06's five members; 12 of 20
before, so files made earlier that day used 0.6); `--set FIELD=JSON` sets a field at
every point, over those (a table entry by entry: `evidence_threshold_by_command=
'{"have_command": 14}'` holds arming at 14 nats; `evidence_bridged_weight=1` counts windows
across a bridged pause in full). `--max-gap 0.25` recognises the streams with the window
restarting after a pause over 0.25 s, as the engine did until 2026-12-06. The PNG
beside the JSON plots, per condition, the commands the script asks for that were given
against the wrong commands that act on a drone (motions, landings, aborts) per hour.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

from bench.decision_check import check, merged, variant
from bench.robust_training import log, recognised_streams, write_doc
from bench.window_length import add_stream_args, cache_path
from proxima.control import ControlSettings

matplotlib.use("Agg")
import matplotlib.pyplot as plt

CONDITIONS = ("clean", "field1")


def ensemble_sets(members: list[str], args: argparse.Namespace) -> dict[str, tuple]:
    """The evaluation sets (condition -> (streams, recognitions)) of `members`' ensemble:
    the first member's recognitions with the mean of every member's probabilities.

    Raises:
        ValueError: the members were not classified at the same frames (another window).
    """
    evals = [recognised_streams(m, args, cache_path(m, args))[1] for m in members]
    out = {}
    for cond in CONDITIONS:
        streams, first = evals[0][cond]
        merged = []
        for k, rec in enumerate(first):
            others = [e[cond][1][k] for e in evals[1:]]
            if any(not np.array_equal(o.classified, rec.classified) for o in others):
                raise ValueError(f"{'+'.join(members)}: members classify different frames")
            probs = np.mean([rec.probs, *(o.probs for o in others)], axis=0)
            merged.append(replace(rec, probs=probs))
        out[cond] = (streams, merged)
    return out


def curve(
    sets: list[tuple], thresholds: list[float], extra: dict[str, Any] | None = None
) -> list[dict[str, Any]]:
    """One row per base threshold (with `extra`'s settings): per condition the commands by
    the script, the wrong commands split by what they do, the hours and the median and
    p95 latency."""
    base = ControlSettings()
    share = base.evidence_threshold_by_command["have_command"] / base.evidence_threshold
    hours = {  # unrounded: check() rounds its hours to 0.01
        cond: sum(x.duration_s for _, es in sets for x in es[cond][0]) / 3600 for cond in CONDITIONS
    }
    rows = []
    for th in thresholds:
        # `variant` keeps the table's other entries
        point = {
            "evidence_threshold": th,
            "evidence_threshold_by_command": {"have_command": share * th},
        }
        update = merged(point, extra or {})  # `extra` wins, a table entry by entry
        out = check(sets, variant(update))
        row: dict[str, Any] = {"threshold": th}
        for cond in CONDITIONS:
            o = out[cond]
            row[cond] = {
                "by_script": o["hit_rate_by_script"],
                "wrong_acting": o["wrong_acting"],
                "wrong_arming": o["wrong_arming"],
                "re_arms": o["re_arms"],
                "hours": o["hours"],
                "wrong_acting_per_hour": round(o["wrong_acting"] / hours[cond], 2),
                "latency_median_s": o["mean"]["latency_median_s"],
                "latency_p95_s": o["mean"]["latency_p95_s"],
            }
        rows.append(row)
        log(f"  {th:g} nats: " + "; ".join(
            f"{c} {row[c]['by_script']} / {row[c]['wrong_acting']} acting" for c in CONDITIONS
        ))  # fmt: skip
    return rows


def plot(result: dict[str, list[dict[str, Any]]], path: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, cond in zip(axes, CONDITIONS, strict=True):
        for label, rows in result.items():
            x = [r[cond]["wrong_acting_per_hour"] for r in rows]
            y = [r[cond]["by_script"] for r in rows]
            ax.plot(x, y, "o-", label=label)
            for r, xi, yi in zip(rows, x, y, strict=True):
                ax.annotate(f"{r['threshold']:g}", (xi, yi), fontsize=7,
                            textcoords="offset points", xytext=(3, 3))  # fmt: skip
        ax.set_title({"clean": "clean", "field1": "field 1"}[cond])
        ax.set_xlabel("wrong commands that act on a drone, per hour")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("commands given, of those the script asks for")
    axes[1].legend(fontsize=8)
    fig.suptitle("Evidence threshold (nats, labels) moved: held-out streams", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--curve", action="append", required=True, metavar="LABEL=MODEL,...",
        help="MODEL: a checkpoint, or +-joined checkpoints: their ensemble",
    )  # fmt: skip
    ap.add_argument("--thresholds", default="12,14,16,18,20")
    ap.add_argument("--out", type=Path, default=Path("bench/results/operating_curve.json"))
    ap.add_argument(
        "--set", action="append", default=[], metavar="FIELD=JSON",
        help="another ControlSettings field at every point (JSON value)",
    )  # fmt: skip
    add_stream_args(ap)
    ap.set_defaults(tune_streams=0, streams=48)
    args = ap.parse_args()
    t0 = time.perf_counter()
    thresholds = [float(t) for t in args.thresholds.split(",")]
    extra = {k: json.loads(v) for k, _, v in (item.partition("=") for item in args.set)}
    result: dict[str, list[dict[str, Any]]] = {}
    for spec in args.curve:
        label, _, models = spec.partition("=")
        log(f"{label}:")
        sets = [(None, ensemble_sets(m.split("+"), args)) for m in models.split(",")]
        result[label] = curve(sets, thresholds, extra)
    doc = {"curves": result, "settings": extra}
    write_doc(args.out, "operating_curve", "operating_curve", doc, t0)
    plot(result, args.out.with_suffix(".png"))


if __name__ == "__main__":
    main()
