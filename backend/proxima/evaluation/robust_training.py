"""Measurements of issue 21's robust recipe (bench/robust_training.py runs them):

- `window_accuracy`: a checkpoint's window accuracy on a split's test parts as the live
  engine would see them: each part captured whole (`CaptureModel.apply_clip`, one draw
  per part), smoothed by the live One Euro filter (or not: `smooth=False`, what
  `proxima evaluate` scores) and cut as the engine's window (`live_windows`, stride 5).
- `captured_clips` / `decision_streams`: stitched held-out streams (the clips' temporal
  test parts) with a capture condition applied to every clip before stitching, at 30 fps
  (stitching joins 30 fps rows; frame-rate effects are left out of the streams), for the
  offline replay of the engine's pipeline and decision rules (`replay.recognize`/`decide`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings
from proxima.engine.stream import Classifier
from proxima.engine.window import DEFAULT_CLOCK, engine_clock
from proxima.evaluation.latency import VIEWS, brief, evaluate_config, rank, utility
from proxima.evaluation.replay import MemoClassifier, Recognitions, recognize
from proxima.evaluation.stitch import StitchedStream, random_plan, stitch_views
from proxima.gesture.capture import Captured, CaptureModel, live_windows
from proxima.gesture.clip import Clip
from proxima.pose.one_euro import one_euro_windows
from proxima.types import GESTURES


def smooth(captured: Captured) -> Captured:
    """`captured` through the live One Euro filter (reset after a 0.5 s pause)."""
    xyz = one_euro_windows(captured.xyz[None], captured.t[None])[0].astype(np.float32)
    return replace(captured, xyz=xyz)


def window_accuracy(
    classifier: Any,
    parts: Sequence[Clip],
    model: CaptureModel,
    seed: int,
    smoothed: bool = True,
    stride: int = 5,
) -> dict[str, Any]:
    """Accuracy and per-view accuracy of `classifier` on the engine's windows of `parts`
    under `model` (see the module), and the parts it gets under 90 % right (`weak_parts`:
    gesture, view, accuracy, the label it reads there most and its confidence)."""
    rng = np.random.default_rng(seed)
    right: list[np.ndarray] = []
    views: list[str] = []
    weak: list[dict[str, Any]] = []  # parts under 90 % right: where the errors are
    clock = engine_clock(DEFAULT_CLOCK, classifier.window_clock)  # the engine's default
    for part in parts:
        if len(part) < classifier.window + 1:
            continue
        cap = model.apply_clip(part, rng)
        if smoothed:
            cap = smooth(cap)
        xyz, _, _ = live_windows(cap, classifier.window, stride, clock=clock)
        if not len(xyz):
            continue
        probs = classifier.predict(xyz, aspect=part.aspect)
        ok = probs.argmax(1) == GESTURES.index(part.gesture)
        right.append(ok)
        views += [part.view] * len(xyz)
        if ok.mean() < 0.9:
            wrong = np.bincount(probs.argmax(1)[~ok], minlength=len(GESTURES))
            weak.append({
                "gesture": part.gesture, "view": part.view, "windows": len(ok),
                "accuracy": round(float(ok.mean()), 3),
                "read_as": GESTURES[int(wrong.argmax())],
                "confidence_when_wrong": round(float(probs[~ok].max(1).mean()), 3),
            })  # fmt: skip
    hits = np.concatenate(right) if right else np.zeros(0, bool)
    v = np.asarray(views)
    return {
        "windows": len(hits),
        "accuracy": round(float(hits.mean()), 4) if len(hits) else None,
        "by_view": {str(k): round(float(hits[v == k].mean()), 4) for k in sorted(set(views))},
        "weak_parts": weak,
    }


def captured_clips(clips: Sequence[Clip], model: CaptureModel, seed: int) -> list[Clip]:
    """Every clip through `model` at 30 fps (one draw per clip), as clips again."""
    rng = np.random.default_rng(seed)
    model = replace(model, fps=30.0)
    out = []
    for c in clips:
        cap = model.apply_clip(c, rng)
        frames = cap.frames.astype(np.int64)
        out.append(replace(c, frames=frames, xyz=cap.xyz, visibility=cap.visibility))
    return out


def decision_streams(
    clips: Sequence[Clip],
    seeds: Sequence[int],
    segments: int,
    model: CaptureModel,
    whole_stream: bool = False,
) -> list[StitchedStream]:
    """One stitched held-out stream per seed (views f, l, r in turn), its clips captured
    under `model` with that seed first, at 30 fps; with `whole_stream`, the stream
    stitched from the clips as recorded and then captured in one draw at the drawn frame
    rate (15-30 fps under `field`), as `proxima robustness`'s live check does: the
    evidence rule weighs a recognition by the seconds it stands for, so a setting tuned
    at 30 fps alone has not met the coarser steps of a slower camera."""
    from proxima.evaluation.robustness import captured_stream

    out = []
    for k, seed in enumerate(seeds):
        view = VIEWS[k % len(VIEWS)]
        own = [c for c in clips if c.view == view]
        plan = random_plan(np.random.default_rng(seed), segments, 3.0, 6.0)
        source = own if whole_stream else captured_clips(own, model, seed)
        stream = stitch_views(source, plan, (view,), "test", 0.5, 30.0, None, seed)[view]
        if whole_stream:
            stream = captured_stream(stream, model, np.random.default_rng(seed))
        out.append(stream)
    return out


def recognitions(
    streams: Sequence[StitchedStream], classifier: Classifier, settings: EngineSettings
) -> list[Recognitions]:
    memo = MemoClassifier(classifier)
    return [recognize(s, memo, settings, ControlSettings()) for s in streams]


EVIDENCE_GRID: dict[str, list[Any]] = {
    "evidence_threshold": [4.0, 6.0, 8.0, 12.0, 16.0, 24.0],
    "evidence_half_life_s": [0.5, 1.0, 2.0],
    "evidence_clip": [1.0, 1.5, 2.0, 3.0],
    "confirm": [1, 2],
}


def tune_evidence(
    sets: Sequence[tuple[Sequence[StitchedStream], Sequence[Recognitions]]],
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The evidence rule's grid on tuning streams (every set pooled: clean and field),
    ranked by `latency.rank` (fewer than 1 wrong or spurious per hour, then most commands
    within 2.5 s). Returns the best row and all rows."""
    rows = []
    for values in itertools.product(*EVIDENCE_GRID.values()):
        params = dict(zip(EVIDENCE_GRID, values, strict=True))
        control = ControlSettings(decision="evidence", **params)
        summaries = [evaluate_config(s, r, control) for s, r in sets]
        pooled = pool(summaries)
        rows.append({**params, **pooled})
    rows.sort(key=rank, reverse=True)
    return rows[0], rows


BY_COMMAND_FACTORS = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0)


def tune_by_command(
    sets: Sequence[tuple[Sequence[StitchedStream], Sequence[Recognitions]]],
    base: ControlSettings,
    passes: int = 2,
    factors: Sequence[float] = BY_COMMAND_FACTORS,
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Per-command evidence thresholds on top of `base` (an evidence setting): for each
    gesture in turn, its threshold times each of `factors`, the best by `rank`
    on the pooled tuning sets kept before the next gesture; `passes` rounds. A command the
    classifier confuses others with asks for more evidence, one it is slow to name for
    less. Returns the best row (with `evidence_threshold_by_command`) and every row."""
    by: dict[str, float] = dict(base.evidence_threshold_by_command)

    def score(table: dict[str, float]) -> dict[str, Any]:
        control = base.model_copy(update={"evidence_threshold_by_command": dict(table)})
        return {"evidence_threshold_by_command": dict(table),
                **pool([evaluate_config(s, r, control) for s, r in sets])}  # fmt: skip

    best = score(by)
    rows = [best]
    for _ in range(passes):
        for g in GESTURES:
            current = by.get(g, base.evidence_threshold)
            for f in factors:
                if f == 1.0:
                    continue
                trial = {**by, g: round(current * f, 2)}
                row = score(trial)
                rows.append(row)
                if rank(row) > rank(best):
                    best, by = row, trial
    rows.sort(key=rank, reverse=True)
    return best, rows


def pool(summaries: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Headline figures of several score summaries taken together (the worst p95, the
    summed counts), with `utility` for `rank`."""
    hours = sum(s["stream_hours"] for s in summaries)
    expected = sum(s["expected_commands"] for s in summaries)
    wrong = sum(s["wrong"] for s in summaries)
    repeats = sum(s["repeats"] for s in summaries)
    on_time = sum((s["on_time_rate"] or 0.0) * s["expected_commands"] for s in summaries)
    given = sum((s["hit_rate"] or 0.0) * s["expected_commands"] for s in summaries)
    p95 = [s["latency_p95_s"] for s in summaries if s["latency_p95_s"] is not None]
    out = {
        "expected_commands": expected,
        "hit_rate": round(given / expected, 4) if expected else None,
        "on_time_rate": round(on_time / expected, 4) if expected else None,
        "latency_p95_s_worst": max(p95) if p95 else None,
        "wrong": wrong,
        "repeats": repeats,
        "re_arms": sum(s["re_arms"] for s in summaries),
        "wrong_arming": sum(s["wrong_arming"] for s in summaries),
        "wrong_acting": sum(s["wrong_acting"] for s in summaries),
        "wrong_or_spurious_per_hour": round((wrong + repeats) / hours, 3) if hours else None,
    }
    out["utility"] = round(utility({**out, "expected_commands": expected}), 4)
    return out


def summary_row(summary: dict[str, Any]) -> dict[str, Any]:
    """`latency.brief` plus the wrong pairs and misses by gesture."""
    return {
        **brief(summary),
        "wrong_by_pair": summary["wrong_by_pair"],
        "missed_by_gesture": summary["missed_by_gesture"],
    }
