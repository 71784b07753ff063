"""Figures of a checkpoint on data no model of the console trained on, so a supervisor
can compare a candidate with the model in use before promoting it.

The set is synthetic (`proxima.synth`): a fixed seed, two synthetic people before two
cameras performing the 13 gestures once each. The shipped model trains on LASER and
UAV-Gesture, federated runs on LASER partitions and the console's kept samples, so
none of them has seen these clips. It is generated once into a folder beside the
database and reused; figures are cached per checkpoint file (path, size, mtime).
"""

from __future__ import annotations

import json
import logging
import threading
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)

EVAL_SEED = 26
EVAL_CLIPS = 26  # two people x 13 gestures
SET_NAME = "synthetic"
SET_DESCRIPTION = (
    f"{EVAL_CLIPS} synthetic clips (proxima synth, seed {EVAL_SEED}: 2 people x 13 "
    "gestures), which no model here trained on"
)
ABORT = "wave_off"


class ModelEvaluator:
    """Evaluates checkpoints on the held-out synthetic set; one evaluation at a time."""

    def __init__(self, work_dir: str | Path) -> None:
        self._dir = Path(work_dir)
        self._lock = threading.Lock()
        self._cache: dict[tuple[str, int, int], dict[str, Any]] = {}
        self._clips: list[Any] | None = None

    @staticmethod
    def _key(path: Path) -> tuple[str, int, int]:
        st = path.stat()
        return (str(path.resolve()), st.st_size, st.st_mtime_ns)

    def cached(self, checkpoint: str | Path) -> dict[str, Any] | None:
        """The figures if this file was evaluated already, else None (never evaluates)."""
        try:
            return self._cache.get(self._key(Path(checkpoint)))
        except OSError:
            return None

    def _eval_clips(self) -> list[Any]:
        from proxima.synth.dataset import generate, is_synth_dir, load_synth_dir

        if self._clips is None:
            folder = self._dir / f"eval-synth-s{EVAL_SEED}-{EVAL_CLIPS}"
            if not is_synth_dir(folder):
                generate(folder, EVAL_CLIPS, seed=EVAL_SEED, overwrite=True,
                         command="console promotion check")  # fmt: skip
            self._clips = load_synth_dir(folder)
        return self._clips

    def figures(self, checkpoint: str | Path) -> dict[str, Any]:
        """Window and clip accuracy and the abort gesture's recall of `checkpoint` on the
        held-out set (computed once per file).

        Raises:
            FileNotFoundError, ValueError: not a gesture checkpoint.
        """
        from proxima.evaluation.metrics import score_windows
        from proxima.gesture.ensemble import load_checkpoint
        from proxima.gesture.windows import make_windows

        path = Path(checkpoint)
        with self._lock:
            key = self._key(path)
            if key in self._cache:
                return self._cache[key]
            clf = load_checkpoint(path)  # one model or an ensemble file
            clips = self._eval_clips()
            windows = make_windows(clips, clf.window, 5, 5)
            scored = score_windows(clf, windows, clips)
            result = {
                "set": SET_NAME,
                "set_description": SET_DESCRIPTION,
                "windows": scored["windows"],
                "accuracy": round(scored["accuracy"], 4),
                "clip_accuracy": round(scored["clip_accuracy"], 4),
                "abort_gesture": ABORT,
                "abort_recall": round(scored["per_class"][ABORT]["recall"], 4),
                "reported_accuracy": reported_accuracy(clf.metadata),
                "created": clf.metadata.get("created"),
            }
            self._cache[key] = result
            log.info("evaluated %s on the %s set: %s", path, SET_NAME, json.dumps(result))
            return result


def reported_accuracy(metadata: dict[str, Any]) -> float | None:
    """The test accuracy the checkpoint's own training wrote, if any (on its own test
    split: not comparable between models trained on different data)."""
    value = metadata.get("test_accuracy")
    return float(value) if isinstance(value, int | float) else None


def concerns(
    candidate: dict[str, Any],
    active: dict[str, Any] | None,
    min_accuracy: float,
    tolerance: float,
) -> list[str]:
    """Why promoting `candidate` over `active` needs an override, in sentences ([] when
    it does not): below the floor, or worse than the model in use overall or on the
    abort gesture."""
    out = []
    acc, abort = candidate["accuracy"], candidate["abort_recall"]
    if acc < min_accuracy:
        out.append(f"accuracy {acc:.3f} is below the minimum {min_accuracy:.3f}")
    if active is not None:
        if acc < active["accuracy"] - tolerance:
            out.append(f"accuracy {acc:.3f} is below the model in use ({active['accuracy']:.3f})")
        if abort < active["abort_recall"] - tolerance:
            out.append(
                f"{ABORT} (the abort) recall {abort:.3f} is below the model in use "
                f"({active['abort_recall']:.3f})"
            )
    return out
