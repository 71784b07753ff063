"""Decision rules on cached recognitions (`bench.robust_training streams --cache`) with the
model's own probabilities (T = 1), recovered from the calibrated ones: softmax(z / T) ** T,
renormalised, is softmax(z).

    python -m bench.robust_untempered CACHE.pkl T OUT.json [STREAMS.json]

With STREAMS.json (that run's output) its selected evidence setting is replayed too.
"""

from __future__ import annotations

import json
import pickle
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from proxima.control import AVERAGE_RULE, ControlSettings
from proxima.evaluation.latency import evaluate_config
from proxima.evaluation.replay import Recognitions
from proxima.evaluation.robust_training import summary_row

FIELDS = ("hit_rate", "on_time_rate", "latency_p95_s", "wrong", "repeats")


def untempered(rec: Recognitions, temperature: float) -> Recognitions:
    p = np.clip(rec.probs.astype(np.float64), 1e-12, 1.0) ** temperature
    return replace(rec, probs=(p / p.sum(1, keepdims=True)).astype(np.float32))


def main() -> None:
    cache, temperature, out = Path(sys.argv[1]), float(sys.argv[2]), Path(sys.argv[3])
    _, eval_sets = pickle.loads(cache.read_bytes())
    rules = {"average": AVERAGE_RULE}
    if len(sys.argv) > 4:
        run = json.loads(Path(sys.argv[4]).read_text())
        rules["evidence"] = ControlSettings.model_validate(run["result"]["evidence"]["control"])
    res = {}
    for rule, control in rules.items():
        for key, (streams, recs) in eval_sets.items():
            recs1 = [untempered(r, temperature) for r in recs]
            s = summary_row(evaluate_config(streams, recs1, control))
            res[f"{rule}/{key}"] = {m: s[m] for m in FIELDS}
            print(rule, key, res[f"{rule}/{key}"], flush=True)
    out.write_text(json.dumps({"command": " ".join(sys.argv), "T1": res}, indent=1))


if __name__ == "__main__":
    main()
