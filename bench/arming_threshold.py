"""Per-command evidence thresholds for `have_command` (arming) and `wave_off` (abort) on
top of the shared 30-frame evidence setting (16 nats, half-life 1 s, clip 3, confirm 1;
`bench/window_length.py`, `evidence_shared`), on the cached recognitions of the three
held-out 30-frame models: each pair is ranked on the tuning streams pooled
(`latency.rank`: fewer than 1 wrong or spurious command per hour, then most on time)
and reported on the evaluation streams (mean of the seeds, clean and `field` 1).

    python -m bench.arming_threshold --model runs/window/w30-s0.pt,runs/window/w30-s1.pt,\
runs/window/w30-s2.pt --cache-dir runs/window --out bench/results/arming_threshold.json

The caches are `bench.window_length`'s (made there if missing).
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path
from typing import Any

from bench.robust_training import log, write_doc
from bench.window_length import held_out_start, score_setting
from proxima.control import ControlSettings

SHARED: dict[str, Any] = {
    "evidence_threshold": 16.0,
    "evidence_half_life_s": 1.0,
    "evidence_clip": 3.0,
    "confirm": 1,
}
GRID = {"have_command": [16.0, 12.0, 10.0, 8.0, 6.0], "wave_off": [16.0, 12.0, 8.0, 6.0]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    args, checkpoints, sets, t0 = held_out_start(ap, Path("bench/results/arming_threshold.json"))
    rows: list[dict[str, Any]] = []
    for values in itertools.product(*GRID.values()):
        table = {
            g: v for g, v in zip(GRID, values, strict=True) if v != SHARED["evidence_threshold"]
        }
        control = ControlSettings(
            decision="evidence", **SHARED, evidence_threshold_by_command=table
        )
        rows.append({"by_command": table, **score_setting(sets, control)})
        log(f"{table}: tuning {rows[-1]['tuning']} | field1 {rows[-1]['eval_mean']['field1']}")
    best = max(rows, key=lambda r: tuple(r["rank"]))
    log(f"selected on the tuning streams: {best['by_command']}")
    result = {"shared": SHARED, "checkpoints": checkpoints, "selected": best, "rows": rows}
    write_doc(args.out, "arming_threshold", "arming_threshold", result, t0)


if __name__ == "__main__":
    main()
