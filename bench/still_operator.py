"""What an armed operator who stands still is commanded to do: every still stance of the
LASER clips, after arming, through the real engine with the default settings
(`proxima.evaluation.still` says how).

    python -m bench.still_operator [--checkpoint models/gesture-default.pt]

Writes bench/results/still_operator.json and still_operator.png.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--checkpoint", type=Path, default=None, help="default: the shipped model")
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--out", type=Path, default=RESULTS / "still_operator.json")
    args = ap.parse_args(argv)

    import torch

    torch.set_num_threads(1)
    from proxima.evaluation.plots import plot_stances
    from proxima.evaluation.still import still_operator
    from proxima.gesture.classifier import default_checkpoint
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    started = time.perf_counter()
    clips = load_laser_dir(resolve_dataset(args.data))
    result = still_operator(args.checkpoint or default_checkpoint(), clips)
    result["command"] = "python -m bench.still_operator " + shlex.join(argv or sys.argv[1:])
    result["date"] = time.strftime("%Y-%m-%d")
    result["seconds"] = round(time.perf_counter() - started, 1)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    plot_stances(result, {c.name: c for c in clips}, args.out.with_suffix(".png"))
    for s in result["stances"]:
        said = ", ".join(f"{c['command']} at {c['t_after_start_s']} s" for c in s["commands"])
        print(f"{s['clip']:28s} armed={s['armed_at_start']!s:5s} {said or 'no command'}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
