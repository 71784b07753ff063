"""A tuned decision setting checked on more held-out hours than it was chosen with: the
shipped defaults (`ControlSettings()`), the single threshold before them,
`bench.evidence_retune`'s grid selection and its
per-command table (`--by-command`), each replayed on `--streams` evaluation streams per
seed and condition (from seed 1000, so the first 12 are `bench.window_length`'s), clean
and `field` 1. Wrong commands come a few per hour, so a difference needs hours: 48
streams are 2 h per condition and seed, 12 h over three seeds.

    python -m bench.decision_check --model runs/window/w30-s0.pt,runs/window/w30-s1.pt,\
runs/window/w30-s2.pt --retune bench/results/evidence_retune-t24-whole.json --streams 48 \
        --whole-stream-capture --out bench/results/decision_check-whole.json

`--whole-stream-capture` captures each stream in one draw at 15-30 fps, as `proxima
robustness` does (the shipped defaults were chosen so); without it, clip by clip at 30
fps (`bench/results/decision_check.json`). Recognitions are cached as
`bench.window_length` caches them (`recs-<stem>-t0-e48-g30[-whole].pkl`). `--prior
have_command=W` adds the defaults with that `evidence_prior_by_command` (W = 1: the
defaults before 2026-12-06, which had no prior), `--variant
'NAME={"evidence_threshold_by_command": {"have_command": 14}}'` the defaults with those
settings (tables updated entry by entry); the wrong
commands are also split by what they do to the drone (`scoring`: re-arms, wrong
armings, acting).
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path
from typing import Any

from bench.evidence_retune import control_for
from bench.robust_training import log, write_doc
from bench.window_length import headline_of, held_out_start, mean_headline
from proxima.control import ControlSettings
from proxima.evaluation.latency import evaluate_config_by_script
from proxima.evaluation.robust_training import pool

# The evidence rule's single-threshold defaults of 2026-12-05's morning
SINGLE_THRESHOLD = ControlSettings(
    evidence_threshold=16.0,
    evidence_half_life_s=1.0,
    evidence_threshold_by_command={"have_command": 12.0},
    evidence_prior_by_command={},
)


def merged(base: dict[str, Any], update: dict[str, Any]) -> dict[str, Any]:
    """`base` with `update`'s fields; a table (e.g. `evidence_threshold_by_command`) is
    updated entry by entry, not replaced."""
    out = dict(base)
    for key, value in update.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            value = {**out[key], **value}
        out[key] = value
    return out


def variant(update: dict[str, Any]) -> ControlSettings:
    """The defaults with `update`'s fields, tables entry by entry (`merged`)."""
    return ControlSettings.model_validate(merged(ControlSettings().model_dump(), update))


def settings_of(
    retune: dict[str, Any],
    priors: dict[str, float] | None = None,
    variants: dict[str, dict[str, Any]] | None = None,
) -> dict[str, ControlSettings]:
    """The defaults, the single threshold before them, the settings a
    `bench.evidence_retune` result selected, with `priors` the defaults with that
    `evidence_prior_by_command`, and each of `variants` (name -> `variant`'s update)."""
    out = {"defaults": ControlSettings(), "single_threshold": SINGLE_THRESHOLD}
    if priors:
        out["defaults_prior"] = variant({"evidence_prior_by_command": priors})
    for name, update in (variants or {}).items():
        out[name] = variant(update)
    selected = control_for(retune["selected"]["setting"])
    out["selected"] = selected
    if "by_command" in retune:
        table = retune["by_command"]["table"]
        out["by_command"] = selected.model_copy(update={"evidence_threshold_by_command": table})
    return out


def check(sets: list[tuple], control: ControlSettings) -> dict[str, Any]:
    """Per condition: the seeds' mean headline figures, and the wrong and repeated
    commands of all seeds' streams pooled (with the hours they came in)."""
    out: dict[str, Any] = {}
    for cond in ("clean", "field1"):
        # one pair per seed: against the run's own arming, against the script
        both = [evaluate_config_by_script(*es[cond], control) for _, es in sets]
        summaries = [own for own, _ in both]
        pooled = pool(summaries)
        script = pool([by_script for _, by_script in both])
        pairs = sum((Counter(s["wrong_by_pair"]) for s in summaries), Counter())
        out[cond] = {
            "mean": mean_headline([headline_of(s) for s in summaries]),
            "hours": round(sum(s["stream_hours"] for s in summaries), 2),
            "hit_rate_by_script": script["hit_rate"],
            "wrong": pooled["wrong"],
            "re_arms": pooled["re_arms"],
            "wrong_arming": pooled["wrong_arming"],
            "wrong_acting": pooled["wrong_acting"],
            "repeats": pooled["repeats"],
            "wrong_or_spurious_per_hour": pooled["wrong_or_spurious_per_hour"],
            "wrong_by_pair": dict(pairs.most_common()),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--retune", type=Path, required=True, help="bench.evidence_retune's JSON")
    ap.add_argument("--prior", action="append", default=[], metavar="GESTURE=WEIGHT",
                    help="also the defaults with this evidence prior (repeat)")  # fmt: skip
    ap.add_argument("--variant", action="append", default=[], metavar="NAME=JSON",
                    help="also the defaults updated with these settings (repeat)")  # fmt: skip
    out = Path("bench/results/decision_check.json")
    args, checkpoints, sets, t0 = held_out_start(ap, out, tune_streams=0, streams=48)
    retune = json.loads(args.retune.read_text())["result"]
    result: dict[str, Any] = {"checkpoints": checkpoints, "streams": args.streams}
    priors = {g: float(w) for g, _, w in (p.partition("=") for p in args.prior)}
    variants = {n: json.loads(u) for n, _, u in (v.partition("=") for v in args.variant)}
    for name, control in settings_of(retune, priors, variants).items():
        result[name] = {"setting": control.model_dump(), **check(sets, control)}
        row = result[name]
        log(f"{name}: {json.dumps({c: row[c]['mean'] for c in ('clean', 'field1')})}")
        rates = [row[c]["wrong_or_spurious_per_hour"] for c in ("clean", "field1")]
        log(f"  wrong or repeated per hour: clean {rates[0]}, field {rates[1]}")
        split = [(row[c]["re_arms"], row[c]["wrong_arming"], row[c]["wrong_acting"])
                 for c in ("clean", "field1")]  # fmt: skip
        log(
            f"  by the script: clean {row['clean']['hit_rate_by_script']}, "
            f"field {row['field1']['hit_rate_by_script']}"
        )
        log(f"  wrong as re-arms / arming / acting: clean {split[0]}, field {split[1]}")
    write_doc(args.out, "decision_check", "decision_check", result, t0)


if __name__ == "__main__":
    main()
