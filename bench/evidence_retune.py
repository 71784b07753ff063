"""The whole evidence setting re-tuned under the per-stream-second rule: threshold,
half-life, clip and the `have_command` / `wave_off` entries (as shares of the threshold)
ranked together on the three held-out 30-frame seeds' tuning streams pooled (clean and
`field` 1; `latency.rank`), each reported on their evaluation streams (mean of the
seeds), beside the shipped defaults (`ControlSettings()`).

    python -m bench.evidence_retune --model runs/window/w30-s0.pt,runs/window/w30-s1.pt,\
runs/window/w30-s2.pt --cache-dir runs/window --out bench/results/evidence_retune.json

The caches are `bench.window_length`'s (made there if missing). `--by-command` then
tunes every command's own threshold on top of the selected setting (`tune_by_command`,
the tuning streams pooled) and reports that too; with `--tune-streams 24` (1 h of tuning
streams per condition and seed, 6 h pooled) a wrong command in the tuning pool is one in
six hours, not one in 1.5. `--whole-stream-capture` captures every stream in one draw at
15-30 fps, as `proxima robustness` does; the shipped defaults come from that run
(`--tune-streams 24 --whole-stream-capture --by-command --out
bench/results/evidence_retune-t24-whole.json`).
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

from bench.robust_training import log, write_doc
from bench.window_length import held_out_start, score_setting
from proxima.control import ControlSettings
from proxima.evaluation.robust_training import tune_by_command

GRID: dict[str, list[float]] = {
    "evidence_threshold": [12.0, 16.0, 20.0, 24.0],
    "evidence_half_life_s": [0.5, 1.0, 2.0],
    "evidence_clip": [2.0, 3.0],
    "have_command": [0.75, 0.875, 1.0],  # shares of the threshold
    "wave_off": [1.0, 1.25],
}


def control_for(values: dict[str, float]) -> ControlSettings:
    t = values["evidence_threshold"]
    table = {g: round(values[g] * t, 2) for g in ("have_command", "wave_off") if values[g] != 1.0}
    return ControlSettings(
        decision="evidence",
        evidence_threshold=t,
        evidence_half_life_s=values["evidence_half_life_s"],
        evidence_clip=values["evidence_clip"],
        confirm=1,
        evidence_threshold_by_command=table,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--by-command", action="store_true",
                    help="then tune each command's threshold on top of the selection")  # fmt: skip
    args, checkpoints, sets, t0 = held_out_start(ap, Path("bench/results/evidence_retune.json"))
    rows = []
    for n, values in enumerate(itertools.product(*GRID.values()), 1):
        setting = dict(zip(GRID, values, strict=True))
        rows.append({"setting": setting, **score_setting(sets, control_for(setting))})
        if n % 12 == 0:
            log(f"{n} settings scored")
    rows.sort(key=lambda r: tuple(r["rank"]), reverse=True)
    defaults = score_setting(sets, ControlSettings())
    log(f"selected on the tuning streams: {rows[0]['setting']} -> {rows[0]['eval_mean']}")
    log(f"shipped defaults: {defaults['tuning']} -> {defaults['eval_mean']}")
    result = {"checkpoints": checkpoints, "grid": GRID, "defaults": defaults,
              "selected": rows[0], "top": rows[:15], "configs": len(rows)}  # fmt: skip
    if args.by_command:
        base = control_for(rows[0]["setting"])
        tune_pool = [st for ts, _ in sets for st in ts.values()]
        best, tried = tune_by_command(tune_pool, base)
        table = best["evidence_threshold_by_command"]
        log(f"per-command thresholds: {table}")
        by = score_setting(sets, base.model_copy(update={"evidence_threshold_by_command": table}))
        log(f"with them: {by['tuning']} -> {by['eval_mean']}")
        result["by_command"] = {"table": table, "tried": len(tried), **by}
    write_doc(args.out, "evidence_retune", "evidence_retune", result, t0)


if __name__ == "__main__":
    main()
