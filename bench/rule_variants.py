"""Decision settings compared on one held-out ensemble's streams: the shipped defaults
and each `--variant` (the defaults updated with its fields), on `bench.decision_check`'s
evaluation streams (captured whole at 15-30 fps with `--whole-stream-capture`),
recognitions cached per member as `bench.operating_curve` caches them.

    python -m bench.rule_variants --whole-stream-capture --streams 96 \
        --members runs/sz/w30-body-smooth-z-s0.pt+...+runs/sz/w30-body-smooth-z-s4.pt \
        --variant 'off={"evidence_pair_margin": null}' \
        --variant 'wave_off18={"evidence_threshold_by_command": {"wave_off": 18}}' \
        --cache-dir runs/sz/cache --out bench/results/rule_variants-sz5.json

`--from N` scores only the streams from the N-th on (a later part that chose nothing).
`--base JSON` updates the defaults and every variant alike, e.g. '{"thumb_raise": 0.5}' for
a cache recognised with that arm check.
Per variant and condition: the commands the script asks for that were given, the wrong
commands split by what they do (re-arms, wrong armings, acting), by pair, the hours, and
the median and p95 latency (the mean over the one ensemble). `--per-view` adds the same
per camera view (`per_view`), with the commands lost behind a missed arming
(`lost_disarmed`: asked for by the script, not expected after the run's own arming).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import torch

from bench.decision_check import check, merged, variant
from bench.operating_curve import ensemble_sets
from bench.robust_training import log, write_doc
from bench.window_length import add_stream_args
from proxima.control import ControlSettings
from proxima.evaluation.latency import evaluate_config_by_script

PER_VIEW = ("wrong_acting", "re_arms", "wrong_arming", "latency_p95_s", "within_2_5_s")


def per_view(
    streams: list[Any], recognitions: list[Any], control: ControlSettings
) -> dict[str, Any]:
    """Each camera view's figures by the script, and what a missed arming cost there."""
    out: dict[str, Any] = {}
    for view in sorted({s.view for s in streams}):
        mine = [i for i, s in enumerate(streams) if s.view == view]
        own, script = evaluate_config_by_script(
            [streams[i] for i in mine], [recognitions[i] for i in mine], control
        )
        out[view] = {
            "expected_by_script": script["expected_commands"],
            "hit_rate_by_script": script["hit_rate"],
            "lost_disarmed": script["expected_commands"] - own["expected_commands"],
            **{k: script[k] for k in PER_VIEW},
            "missed_by_gesture": dict(
                sorted(script["missed_by_gesture"].items(), key=lambda kv: -kv[1])
            ),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--members", required=True, help="CKPT+CKPT+...: one ensemble")
    ap.add_argument("--variant", action="append", default=[], metavar="NAME=JSON",
                    help="the defaults updated with these settings (repeat)")  # fmt: skip
    ap.add_argument("--base", default="{}", metavar="JSON",
                    help="settings under the defaults and every variant")  # fmt: skip
    ap.add_argument("--from", dest="start", type=int, default=0, metavar="N",
                    help="score the evaluation streams from the N-th on")  # fmt: skip
    ap.add_argument("--per-view", action="store_true", help="also the figures per camera view")
    ap.add_argument("--out", type=Path, default=Path("bench/results/rule_variants.json"))
    add_stream_args(ap)
    ap.set_defaults(tune_streams=0, streams=48)
    args = ap.parse_args()
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    every = ensemble_sets(args.members.split("+"), args)
    sets = [(None, {c: (s[args.start :], r[args.start :]) for c, (s, r) in every.items()})]
    variants = {"defaults": {}} | {
        n: json.loads(u) for n, _, u in (v.partition("=") for v in args.variant)
    }
    base = json.loads(args.base)
    result: dict[str, Any] = {"members": args.members, "from": args.start, "base": base}
    for name, update in variants.items():
        control = variant(merged(base, update))
        row = check(sets, control)
        result[name] = {"update": update, **row}
        if args.per_view:
            for cond, (streams, recs) in sets[0][1].items():
                result[name][cond]["per_view"] = per_view(streams, recs, control)
        log(f"{name}: " + "; ".join(
            f"{c} {row[c]['hit_rate_by_script']} by the script, {row[c]['wrong_acting']} "
            f"acting, {row[c]['re_arms']} re-arms, {row[c]['wrong_arming']} armings"
            for c in ("clean", "field1")
        ))  # fmt: skip
    write_doc(args.out, "rule_variants", "rule_variants", result, t0)


if __name__ == "__main__":
    main()
