"""Where a temporal-split model goes wrong, and whether the data could have told it: each
model's decisions on the held-out windows beside the nearest training window's label
(`proxima.evaluation.temporal_errors` says how).

    python -m bench.temporal_errors --checkpoint A.pt [--checkpoint B.pt ...]

Writes bench/results/temporal_errors.json and temporal_errors.png (one panel per clip
that some model gets wrong: a row per model, the nearest neighbour last).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--checkpoint",
        type=Path,
        action="append",
        required=True,
        help="a model trained with --split temporal; repeat to compare several",
    )
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--out", type=Path, default=RESULTS / "temporal_errors.json")
    args = ap.parse_args(argv)
    from proxima.evaluation.plots import plot_temporal_errors
    from proxima.evaluation.temporal_errors import analyse

    result = analyse(args.checkpoint, args.data)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    if result["clips"]:
        plot_temporal_errors(result, args.out.with_suffix(".png"))
    else:
        print("no model gets a window wrong: no picture to draw")
    print(f"nearest neighbour accuracy {result['nearest_neighbour_accuracy']:.3f}")
    for m in result["models"]:
        print(
            f"{m['checkpoint']}: accuracy {m['accuracy']:.3f} ({m['wrong']} of "
            f"{result['test_windows']} wrong; nearest neighbour wrong too: "
            f"{m['wrong_and_nearest_neighbour_wrong']}, with the same label: "
            f"{m['wrong_and_nearest_neighbour_agrees']})"
        )
    print(
        f"wrong in every model: {result['wrong_in_every_model']}, and for the nearest "
        f"neighbour too: {result['wrong_in_every_model_and_nearest_neighbour_wrong']}"
    )
    for clip in result["clips"]:
        print(f"  {clip['clip']}: wrong {clip['wrong']} of {clip['windows']}")
    print(f"-> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
