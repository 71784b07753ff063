"""Decision-rule variants on the live check of `proxima robustness` (36 stitched
held-out streams of the temporal split, clean and `field` level 1):

    python bench/decision_variants.py CHECKPOINT OUT.json

Variants: the evidence rule and the average rule at 0.95 with the checkpoint's
temperature, and both rules with T = 1."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import torch

from proxima.control import AVERAGE_RULE, ControlSettings
from proxima.evaluation.robustness import RobustnessConfig, live_robustness
from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.datasets import load_data
from proxima.gesture.windows import split_clips

KEYS = ("command_precision", "command_recall", "wrong_per_hour", "p95_onset_to_command_s")
EVIDENCE_4 = ControlSettings(decision="evidence", evidence_threshold=4.0, confirm=2)
VARIANTS: dict[str, tuple[ControlSettings, float | None]] = {
    # The evidence rule's first setting (4 nats, two decisions), as this bench measured it.
    "evidence": (EVIDENCE_4, None),
    "average_T1": (AVERAGE_RULE, 1.0),
    "evidence_T1": (EVIDENCE_4, 1.0),
    "average_th095": (AVERAGE_RULE.model_copy(update={"threshold": 0.95}), None),
}


def main(checkpoint: str, out: str) -> None:
    torch.set_num_threads(2)
    data = load_data(["laser"])
    window = GestureClassifier.load(checkpoint).window
    parts = split_clips(data.clips, "temporal", window, data.uav_dir)
    test = [c for c in parts.test if len(c) >= 2]
    results: dict[str, dict[str, dict[str, float]]] = {}
    for name, (control, temperature) in VARIANTS.items():
        t0 = time.monotonic()
        clf = GestureClassifier.load(checkpoint)
        if temperature is not None:
            clf.temperature = temperature
        live = live_robustness(clf, test, RobustnessConfig(control=control))
        results[name] = {c: {k: live[c][k] for k in KEYS} for c in ("clean", "field")}
        print(name, json.dumps(results[name]), f"{time.monotonic() - t0:.0f} s", flush=True)
    Path(out).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
