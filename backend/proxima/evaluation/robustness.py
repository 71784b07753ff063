"""Field robustness: a checkpoint under the capture model (`proxima.gesture.capture`).

Two checks, both on the held-out part of a split, both repeatable (fixed seeds):

- **Windows.** Each test clip part is captured whole (`CaptureModel.apply_clip`: one
  draw of height, angles, frame rate and losses per recording, as one drone position
  would give) and cut into the windows the live engine would classify
  (`live_windows`: 60 received poses, every `stride`, restarting after a pause over
  `MAX_GAP_S`). Window accuracy and macro F1 for `clean`, every effect of `EFFECTS` at its
  three `LEVELS`, and the combined `field` condition at its three levels (FIELD: level
  1 the measured live jitter, person 0.3-0.7 of the frame, elevation 0-30 deg, yaw
  +-20, roll +-10, 15-30 fps, 5% drops and 0.1 gaps/s, a lost part in 25% of the
  recordings; level 2 the same at twice the jitter; level 3 every effect at its
  harshest). Each condition is drawn `repeats` times per clip; the draw of a clip
  depends only on (seed, condition, level, repeat, clip), so a subset of conditions or
  `limit` gives the same numbers for what it keeps.
- **Live.** Held-out streams stitched from the clips' test parts (`latency.build_streams`:
  random scripts, views f, l, r in turn, seeds 1000...) go through the real engine
  (`replay.engine_run`: replay source, stream pipeline, merge, controller), as recorded
  (`clean`) and captured whole under `field` at `live_level` (one draw per stream), and
  their commands are scored (`scoring`): command precision and recall, wrong commands
  per hour and p95 onset-to-command; recall also against the script's own arming
  (`command_recall_script`: a stream whose `have_command` never arms control misses
  every command after it, where `command_recall` counts one miss); the wrong commands
  also split by what they do to the drone (`re_arms`: a `have_command` while armed, which
  moves nothing; `wrong_arming`; `wrong_acting_per_hour`: the rest).

`proxima robustness` runs both and writes the JSON and a PNG of accuracy against level.
"""

from __future__ import annotations

import time
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings
from proxima.engine.window import engine_clock
from proxima.evaluation.latency import build_streams, describe_streams
from proxima.evaluation.metrics import accuracy_by, metrics
from proxima.evaluation.replay import MemoClassifier, engine_run
from proxima.evaluation.scoring import Score
from proxima.evaluation.stitch import StitchedStream
from proxima.gesture.capture import EFFECTS, MAX_GAP_S, CaptureModel, condition, live_windows
from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.clip import Clip
from proxima.gesture.ensemble import EnsembleClassifier, load_checkpoint, members_of
from proxima.types import GESTURES

CONDITION_NAMES = (*EFFECTS, "field")  # what `conditions` may name (clean always runs)
LEVEL_NUMBERS = (1, 2, 3)
VIEW_KEYS = ("command_precision", "command_recall", "command_recall_script", "wrong_per_hour",
             "wrong_acting_per_hour", "p95_onset_to_command_s", "missed_by_gesture")  # fmt: skip
Progress = Callable[[str, int], None]  # (what was done, how many steps) -> None


class RobustnessError(ValueError):
    """A robustness request that cannot be met (unknown condition, nothing to score)."""


@dataclass(frozen=True)
class RobustnessConfig:
    """The benchmark's size and seeds (see the module)."""

    conditions: tuple[str, ...] = CONDITION_NAMES
    repeats: int = 3  # capture draws per clip and condition
    stride: int = 3  # received poses between windows (`proxima evaluate`'s default)
    limit: int | None = None  # at most this many windows per condition (evenly spaced)
    seed: int = 0
    live: bool = True
    live_streams: int = 36
    live_segments: int = 20
    live_min_s: float = 3.0
    live_max_s: float = 6.0
    live_level: int = 1
    control: ControlSettings = field(default_factory=ControlSettings)
    engine: EngineSettings = field(default_factory=EngineSettings)

    def __post_init__(self) -> None:
        bad = [c for c in self.conditions if c not in CONDITION_NAMES]
        if bad:
            raise RobustnessError(
                f"unknown condition(s) {bad}; choose from {list(CONDITION_NAMES)}"
            )
        if self.repeats < 1 or self.stride < 1 or self.live_streams < 1:
            raise RobustnessError("repeats, stride and live streams must be >= 1")
        if self.limit is not None and self.limit < 1:
            raise RobustnessError(f"limit must be >= 1 window, got {self.limit}")
        if self.live_level not in LEVEL_NUMBERS:
            raise RobustnessError(f"live level must be 1, 2 or 3, got {self.live_level}")

    def steps(self) -> int:
        """Progress steps: one per condition and level (and clean), one per live stream
        and condition."""
        window_steps = 1 + 3 * len(self.conditions)
        return window_steps + (2 * self.live_streams if self.live else 0)


def capture_rng(seed: int, name: str, level: int, repeat: int, item: int) -> np.random.Generator:
    """The generator of one capture draw: it depends on these values only (crc32 makes
    the name a stable number across runs and Python versions)."""
    key = [seed, zlib.crc32(name.encode()), level, repeat, item]
    return np.random.default_rng(np.random.SeedSequence(key))


# -- windows ----------------------------------------------------------------------------
@dataclass
class _Batch:
    xyz: list[np.ndarray] = field(default_factory=list)
    labels: list[np.ndarray] = field(default_factory=list)
    clip: list[np.ndarray] = field(default_factory=list)
    aspect: list[np.ndarray] = field(default_factory=list)
    has_z: list[np.ndarray] = field(default_factory=list)


def captured_windows(
    clips: Sequence[Clip],
    model: CaptureModel,
    name: str,
    level: int,
    config: RobustnessConfig,
    window: int,
    clock: str = "poses",
) -> dict[str, np.ndarray]:
    """The engine's windows of every clip captured under `model`, `repeats` times:
    xyz (N, window, 33, 3), labels, clip index, aspect and has_z per window, subsampled
    evenly to `limit`."""
    batch = _Batch()
    # `clean` draws nothing: one repeat is all of it.
    for repeat in range(1 if name == "clean" else config.repeats):
        for i, clip in enumerate(clips):
            if len(clip) < 2:
                continue
            cap = model.apply_clip(clip, capture_rng(config.seed, name, level, repeat, i))
            if len(cap) < window:
                continue
            xyz, _vis, _t = live_windows(cap, window, config.stride, clock=clock)
            n = len(xyz)
            if not n:
                continue
            batch.xyz.append(xyz)
            batch.labels.append(np.full(n, GESTURES.index(clip.gesture), np.int64))
            batch.clip.append(np.full(n, i, np.int64))
            batch.aspect.append(np.full(n, clip.aspect, np.float32))
            batch.has_z.append(np.full(n, clip.has_z, bool))
    if not batch.xyz:
        return {"xyz": np.zeros((0, window, 33, 3), np.float32), "labels": np.zeros(0, np.int64)}
    out = {
        "xyz": np.concatenate(batch.xyz),
        "labels": np.concatenate(batch.labels),
        "clip": np.concatenate(batch.clip),
        "aspect": np.concatenate(batch.aspect),
        "has_z": np.concatenate(batch.has_z),
    }
    if config.limit is not None and len(out["labels"]) > config.limit:
        keep = np.unique(np.linspace(0, len(out["labels"]) - 1, config.limit).round().astype(int))
        out = {k: v[keep] for k, v in out.items()}
    return out


def score_condition(
    clf: GestureClassifier | EnsembleClassifier,
    clips: Sequence[Clip],
    windows: dict[str, np.ndarray],
) -> dict[str, Any]:
    """Window accuracy, macro F1, per view and per class of `clf` on captured windows. An
    ensemble scores the mean of its members' calibrated probabilities, as the engine runs
    it; one model its own (untempered: the argmax is the same)."""
    from proxima.gesture.train import predict_proba

    if not len(windows["labels"]):
        return {"windows": 0, "accuracy": None, "macro_f1": None}
    members = members_of(clf)
    order = np.concatenate([np.flatnonzero(windows["has_z"] == hz) for hz in (True, False)])
    probs = np.zeros((len(order), len(clf.labels)), np.float32)
    for m in members:
        x = np.concatenate(
            [
                m.features(windows["xyz"][sel], windows["aspect"][sel], has_z=bool(hz))
                for hz in (True, False)
                if (sel := windows["has_z"] == hz).any()
            ]
        )
        temperature = m.temperature if len(members) > 1 else 1.0
        probs[order] += predict_proba(m.model, x, temperature=temperature) / len(members)
    full = metrics(windows["labels"], probs, windows["clip"])
    views = np.array([clips[c].view for c in windows["clip"]])
    return {
        "windows": full["windows"],
        "accuracy": round(full["accuracy"], 4),
        "macro_f1": round(full["macro_f1"], 4),
        "clip_accuracy": round(full["clip_accuracy"], 4),
        "per_view": {
            v: {"accuracy": round(r["accuracy"], 4), "windows": r["windows"]}
            for v, r in accuracy_by(views, windows["labels"], probs.argmax(axis=1)).items()
        },
        "recall_by_gesture": {
            g: round(r["recall"], 4) for g, r in full["per_class"].items() if r["support"]
        },
    }


def window_robustness(
    clf: GestureClassifier | EnsembleClassifier,
    clips: Sequence[Clip],
    config: RobustnessConfig,
    progress: Progress = lambda what, n: None,
) -> dict[str, Any]:
    """`clean` and every configured condition at levels 1-3 (see the module)."""

    clock = engine_clock(config.engine.window_clock, clf.window_clock)

    def run(name: str, level: int, model: CaptureModel) -> dict[str, Any]:
        w = captured_windows(clips, model, name, level, config, clf.window, clock)
        return score_condition(clf, clips, w)

    clean = run("clean", 0, condition("clean"))
    progress(f"clean: accuracy {clean['accuracy']}", 1)
    out: dict[str, Any] = {}
    for name in config.conditions:
        rows = []
        for level in LEVEL_NUMBERS:
            model = condition(name, level)
            row = run(name, level, model)
            drop = None
            if row["accuracy"] is not None and clean["accuracy"] is not None:
                drop = round(clean["accuracy"] - row["accuracy"], 4)
            rows.append({"level": level, **row, "drop_from_clean": drop,
                         "capture": model.describe()})  # fmt: skip
            progress(f"{name} {level}: accuracy {row['accuracy']}", 1)
        out[name] = rows
    return {"clean": clean, "conditions": out}


# -- live -------------------------------------------------------------------------------
def captured_stream(
    stream: StitchedStream, model: CaptureModel, rng: np.random.Generator
) -> StitchedStream:
    """`stream` as a drone camera under `model` would deliver it (one draw for the whole
    stream): the received poses at the drawn frame rate, the script's times unchanged."""
    t = (stream.frames.astype(np.float64) - 1.0) / stream.fps
    cap = model.apply_sequence(t, stream.xyz, stream.visibility, rng, aspect=16 / 9, has_z=True)
    # The replay URI carries the rate as `%g` (engine_run): use that rate so the replayed
    # times are the captured ones.
    fps = float(f"{cap.fps:g}")
    return StitchedStream(
        view=stream.view,
        fps=fps,
        frames=np.asarray(cap.frames, np.int64),
        xyz=cap.xyz,
        visibility=np.clip(cap.visibility, 0.0, 1.0),
        segments=list(stream.segments),
        blanks=list(stream.blanks),
        part=stream.part,
        seed=stream.seed,
    )


def command_figures(score: Score, script: Score) -> dict[str, Any]:
    """The live check's figures of a merged `Score`: command precision (right commands
    over all commands the operator's gestures caused; safety hovers apart) and recall
    (expected commands that came, late ones included; a withheld one is missed), wrong
    commands per hour and the p95 onset-to-command (s). `score` expects what the run's
    own arming allowed (a missed `have_command` is one miss; the gestures after it that
    disarmed control ignored count as `blocked_while_disarmed`); `script` scores the same
    commands against every command the script asks for once armed
    (`command_recall_script`): what the operator wanted, so a stream that never arms
    misses all of its commands."""
    s = score.summary()
    by_script = script.summary()
    right = score.hits + score.late
    issued = right + score.wrong + score.repeats
    return {
        "command_precision": round(right / issued, 4) if issued else None,
        "command_recall": s["hit_rate"],
        "command_recall_script": by_script["hit_rate"],
        "expected_by_script": by_script["expected_commands"],
        "blocked_while_disarmed": s["blocked_while_disarmed"],
        "wrong_per_hour": s["wrong_per_hour"],
        "wrong_acting_per_hour": s["wrong_acting_per_hour"],
        "wrong_or_spurious_per_hour": s["wrong_or_spurious_per_hour"],
        "p95_onset_to_command_s": s["latency_p95_s"],
        "median_onset_to_command_s": s["latency_median_s"],
        "on_time_rate": s["on_time_rate"],
        "expected_commands": s["expected_commands"],
        "commands_right": right,
        "missed": s["missed"],
        "wrong": s["wrong"],
        "re_arms": s["re_arms"],
        "wrong_arming": s["wrong_arming"],
        "repeats": s["repeats"],
        "stream_hours": s["stream_hours"],
        "missed_by_gesture": s["missed_by_gesture"],
        "latency_by_gesture": s["latency_by_gesture"],
        "wrong_by_pair": s["wrong_by_pair"],
        "wrong_examples": score.wrong_examples[:10],
    }


def view_figures(score: Score, script: Score) -> dict[str, Any]:
    """The `VIEW_KEYS` of `command_figures`: what the JSON keeps per camera view."""
    figures = command_figures(score, script)
    return {key: figures[key] for key in VIEW_KEYS}


def live_robustness(
    clf: GestureClassifier | EnsembleClassifier,
    clips: Sequence[Clip],
    config: RobustnessConfig,
    progress: Progress = lambda what, n: None,
) -> dict[str, Any]:
    """The live check (see the module): `clean` and `field` command figures."""
    seeds = list(range(1000, 1000 + config.live_streams))
    streams = build_streams(
        clips, seeds, config.live_segments, "test", config.live_min_s, config.live_max_s
    )
    model = condition("field", config.live_level)
    memo = MemoClassifier(clf)  # clean windows recur little, but the cost is nil
    out: dict[str, Any] = {}
    for name in ("clean", "field"):
        total, total_script = Score(), Score()
        per_view: dict[str, tuple[Score, Score]] = {}
        fps: list[float] = []
        for k, stream in enumerate(streams):
            if name == "field":
                rng = capture_rng(config.seed, "live-field", config.live_level, 0, k)
                stream = captured_stream(stream, model, rng)
            fps.append(stream.fps)
            run = engine_run(stream, config.control, config.engine, memo)
            score = run.score(stream)
            script = run.score(stream, by_script=True)
            total.merge(score)
            total_script.merge(script)
            view = per_view.setdefault(stream.view, (Score(), Score()))
            view[0].merge(score)
            view[1].merge(script)
            progress(f"live {name} {k + 1}/{len(streams)}", 1)
        out[name] = {
            **command_figures(total, total_script),
            "per_view": {v: view_figures(*s) for v, s in sorted(per_view.items())},
            "fps": [round(min(fps), 2), round(max(fps), 2)],
        }
    out["field_condition"] = {"level": config.live_level, "capture": model.describe()}
    out["streams"] = {
        **describe_streams(
            streams, seeds, config.live_segments, config.live_min_s, config.live_max_s
        ),
        "capture": "field: one draw per stream, applied to the whole stitched stream",
    }
    out["settings"] = {
        "control": config.control.model_dump(),
        "engine": config.engine.model_dump(mode="json"),
    }
    return out


# -- the whole benchmark ----------------------------------------------------------------
def run_robustness(
    checkpoint: str | Path | None,
    data_specs: Sequence[str] | None,
    split: str,
    config: RobustnessConfig,
    progress: Progress = lambda what, n: None,
) -> dict[str, Any]:
    """Both checks of `checkpoint` on `split`'s test part; the JSON-ready result.

    Raises:
        FileNotFoundError, ValueError: a missing or unreadable checkpoint.
        proxima.gesture.clip.DataError: the data cannot be loaded or split.
        RobustnessError: the live check on data with no LASER clips.
    """
    from proxima.gesture.datasets import load_data
    from proxima.gesture.windows import WINDOW, split_clips

    started = time.monotonic()
    clf = load_checkpoint(checkpoint)  # comma-joined paths: their ensemble
    data = load_data(data_specs)
    parts = split_clips(data.clips, split, WINDOW, data.uav_dir)  # the protocol's gaps
    test = [c for c in (parts.test or parts.train) if len(c) >= 2]
    result: dict[str, Any] = {
        "checkpoint": str(checkpoint),
        "model": clf.model_name,
        "data": list(data_specs or ["laser"]),
        "split": split,
        "seed": config.seed,
        "repeats": config.repeats,
        "stride": config.stride,
        "limit": config.limit,
        "test_clips": len(test),
        "method": "each test clip part captured whole (one draw per recording and repeat), "
        "cut into the live engine's windows (the model's window of received poses, or of "
        "seconds resampled on the time clock, every `stride`, restarting after "
        f"{MAX_GAP_S:g} s without a pose); live: stitched held-out streams through the "
        "real engine",
        "window_clock": engine_clock(config.engine.window_clock, clf.window_clock),
        "training_clock": clf.window_clock,
    }
    result.update(window_robustness(clf, test, config, progress))
    if config.live:
        laser = [c for c in data.clips if c.source == "laser"]
        if not laser:
            raise RobustnessError("the live check stitches LASER clips: give --data laser")
        if split != "temporal":
            result["live_note"] = (
                "the live streams are stitched from the temporal test parts whatever the split"
            )
        result["live"] = live_robustness(clf, laser, config, progress)
    result["wall_s"] = round(time.monotonic() - started, 1)
    return result


def _cell(row: dict[str, Any]) -> str:
    if row["accuracy"] is None:
        return "-"
    return f"{row['accuracy']:.3f} / {row['macro_f1']:.3f}"


def markdown_table(result: dict[str, Any]) -> str:
    """The window results as a Markdown table (accuracy / macro F1 per level), and the
    live check's figures when it ran: what the README quotes."""
    clean = result["clean"]
    lines = [
        "| condition | level 1 | level 2 | level 3 |",
        "|---|---|---|---|",
        f"| clean | {_cell(clean)} | | |",
    ]
    for name, levels in result["conditions"].items():
        lines.append(f"| {name} | " + " | ".join(_cell(r) for r in levels) + " |")
    live = result.get("live")
    if live:
        lines += [
            "",
            "| live streams | precision | recall | recall (script) | wrong / h "
            "| of them acting / h | p95 onset-to-command (s) |",
            "|---|---|---|---|---|---|---|",
        ]
        for name in ("clean", "field"):
            r = live[name]
            label = name if name == "clean" else f"field {live['field_condition']['level']}"
            lines.append(
                f"| {label} | {r['command_precision']} | {r['command_recall']} | "
                f"{r['command_recall_script']} | {r['wrong_per_hour']} | "
                f"{r['wrong_acting_per_hour']} | {r['p95_onset_to_command_s']} |"
            )
    return "\n".join(lines)
