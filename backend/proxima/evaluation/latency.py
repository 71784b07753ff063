"""Gesture onset -> command latency and wrong/spurious commands per hour.

Long replay streams are stitched from the temporal test parts (last 30%) of the LASER
clips, which a checkpoint trained with `--split temporal` never saw, in random gesture
order with 0.5 s transitions, one camera view per stream (f, l, r in turn). Each stream
is run through the real engine (`replay:` source, stream pipeline, time-ordered merge,
controller, event bus) and its commands are scored against the ground truth with
`proxima.evaluation.scoring` (hits, late hits, misses, repeats, wrong commands).

With tuning, decision settings are first searched on separate tuning streams (other
seeds) by the offline replay (`proxima.evaluation.replay`: the engine's stream pipeline
once per stride, then its filter, hand evidence and controller for each setting); the
evaluation streams are never used to choose settings. `bench/command_latency.py` runs it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from proxima.control import AVERAGE_RULE, ControlSettings
from proxima.engine.config import EngineSettings
from proxima.engine.stream import Classifier
from proxima.evaluation.replay import MemoClassifier, Recognitions, Run, decide, engine_run
from proxima.evaluation.replay import recognize as recognize_stream
from proxima.evaluation.scoring import Score, latency_figures
from proxima.evaluation.stitch import StitchedStream, random_plan, stitch_views
from proxima.gesture.clip import Clip

VIEWS = ("f", "l", "r")
STAGES = ("named", "passed", "commanded")  # see onset_stages
Log = Callable[[str], None]


# -- streams --------------------------------------------------------------------------
def build_streams(
    clips: Sequence[Clip],
    seeds: Sequence[int],
    segments: int,
    part: str,
    min_s: float,
    max_s: float,
) -> list[StitchedStream]:
    """One stitched stream per seed, views f, l, r in turn."""
    out = []
    for k, seed in enumerate(seeds):
        view = VIEWS[k % len(VIEWS)]
        plan = random_plan(np.random.default_rng(seed), segments, min_s, max_s)
        out.append(stitch_views(clips, plan, (view,), part, 0.5, 30.0, None, seed)[view])
    return out


def describe_streams(
    streams: Sequence[StitchedStream],
    seeds: Sequence[int],
    segments: int,
    min_s: float,
    max_s: float,
) -> dict[str, Any]:
    """The result files' record of a `build_streams` set of held-out streams."""
    return {
        "count": len(streams),
        "seeds": [seeds[0], seeds[-1]],
        "part": "test",
        "segments_per_stream": segments,
        "segment_s": [min_s, max_s],
        "transition_s": 0.5,
        "views": sorted({s.view for s in streams}),
    }


def recognize_all(
    streams: Sequence[StitchedStream],
    classifier: Classifier,
    settings: EngineSettings,
    control: ControlSettings,
) -> list[Recognitions]:
    """`proxima.evaluation.replay.recognize` for each stream."""
    return [recognize_stream(s, classifier, settings, control) for s in streams]


# -- where the time goes --------------------------------------------------------------
def onset_stages(stream: StitchedStream, run: Run, filter_size: int) -> list[dict[str, Any]]:
    """Where the time from onset to command goes, per gesture performed in `stream`, from
    an offline replay's `run`: seconds from its onset until the classifier names it in
    `filter_size` recognitions running (`named_s`), until the decision rule passes it
    (`passed_s`: its averaged probability or its evidence reached its threshold) and
    until its command (`commanded_s`); None when that did not happen before the next
    gesture began."""
    # (t, top label, recognitions running with that top label, what the filter passed);
    # runs restart with the window, as the filter does
    recognitions: list[tuple[float, str, int, str]] = []
    for when, top, filtered, new_window in run.recognitions:
        running = 1
        if not new_window and recognitions and recognitions[-1][1] == top:
            running = recognitions[-1][2] + 1
        recognitions.append((when, top, running, filtered))
    rows = []
    segments = stream.segments
    for n, seg in enumerate(segments):
        onset = seg.onset_t
        end = segments[n + 1].onset_t if n + 1 < len(segments) else stream.duration_s
        mine = [r for r in recognitions if onset <= r[0] < end]
        named = next(
            (when - onset for when, top, count, _ in mine
             if top == seg.gesture and count >= filter_size),
            None,
        )  # fmt: skip
        passed = next((when - onset for when, _, _, a in mine if a == seg.gesture), None)
        mine_cmd = [c["t"] for c in run.commands if c["command"] == seg.gesture]
        commanded = next((when - onset for when in mine_cmd if onset <= when < end), None)
        rows.append(
            {"view": stream.view, "gesture": seg.gesture, "named_s": named, "passed_s": passed,
             "commanded_s": commanded}
        )  # fmt: skip
    return rows


def stage_figures(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Latency figures of each stage over the gestures that were commanded (so the three
    stages describe the same gestures), and how many gestures never reached a stage."""
    done = [r for r in rows if r["commanded_s"] is not None]
    return {
        "gestures": len(rows),
        "with_command": len(done),
        "never_named": sum(r["named_s"] is None for r in rows),
        "never_passed": sum(r["passed_s"] is None for r in rows),
        **{
            stage: latency_figures([r[f"{stage}_s"] for r in done if r[f"{stage}_s"] is not None])
            for stage in STAGES
        },
    }


# -- tuning ---------------------------------------------------------------------------
GRID: dict[str, list[Any]] = {
    "stride": [3, 5],
    "threshold": [0.7, 0.75, 0.8, 0.85, 0.9],
    "confirm": [1, 2, 3, 4],
    "debounce_s": [1.0, 2.0, 3.0, 4.0, 5.0],
}
# The paper's filter of three recognitions is kept (filter_size=3). The agreement `land`
# alone needs (decisions in a row) is tried on the grid's fastest settings: a wrong land
# ends a flight, and land_direction's arms-down phase is what the classifier most often
# takes for land. Then the release time is refined around the selected setting.
LAND_CONFIRM = [6, 9, 12, 15, 20]
LAND_TRIED_ON = 20  # the grid's settings with the most commands on time
REFINE = {"release_s": [1.0, 2.0, 4.0, 6.0]}
MAX_WRONG_PER_HOUR = 1.0  # the target for wrong or spurious commands
WRONG_COST = 3.0  # a wrong or spurious command costs as much as this many on-time commands
TUNED = ("threshold", "confirm", "debounce_s", "filter_size", "release_s", "confirm_by_command")
PAPER = ControlSettings(filter_size=3, threshold=0.0, confirm=1, debounce_s=10.0)
BRIEF = (
    "latency_median_s",
    "latency_p95_s",
    "hit_rate",
    "on_time_rate",
    "expected_commands",
    "missed",
    "wrong",
    "repeats",
    "wrong_or_spurious_per_hour",
)


def brief(summary: dict[str, Any]) -> dict[str, Any]:
    """The headline figures of a `Score.summary()`."""
    return {k: summary[k] for k in BRIEF}


def utility(s: dict[str, Any]) -> float:
    """Commands answered within 2.5 s, minus WRONG_COST per wrong or spurious command,
    per expected command (reported alongside; not the selection rule)."""
    on_time = (s["on_time_rate"] or 0.0) * s["expected_commands"]
    return (on_time - WRONG_COST * (s["wrong"] + s["repeats"])) / max(s["expected_commands"], 1)


def rank(row: dict[str, Any]) -> tuple[bool, float, float]:
    """Selection rule, best first when sorted descending: settings with fewer than
    MAX_WRONG_PER_HOUR wrong or spurious commands beat the rest, and among them the one
    with the most commands within 2.5 s wins; if none qualifies, the fewest wrong."""
    wrong = row["wrong_or_spurious_per_hour"]
    ok = wrong < MAX_WRONG_PER_HOUR
    return (ok, (row["on_time_rate"] or 0.0) if ok else -wrong, row["utility"])


def evaluate_config(
    streams: Sequence[StitchedStream],
    recognitions: Sequence[Recognitions],
    control: ControlSettings,
) -> dict[str, Any]:
    """The score summary of the decision settings `control` over `streams` (offline
    replay of their `recognitions`)."""
    total = Score()
    for stream, rec in zip(streams, recognitions, strict=True):
        total.merge(decide(rec, control).score(stream))
    return total.summary()


def evaluate_config_by_script(
    streams: Sequence[StitchedStream],
    recognitions: Sequence[Recognitions],
    control: ControlSettings,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """`evaluate_config`'s summary and the same runs' against every command the script
    asks for once armed (`replay.Run.score`); each stream is decided once."""
    own, script = Score(), Score()
    for stream, rec in zip(streams, recognitions, strict=True):
        run = decide(rec, control)
        own.merge(run.score(stream))
        script.merge(run.score(stream, by_script=True))
    return own.summary(), script.summary()


def tune(
    streams: Sequence[StitchedStream],
    classifier: Classifier,
    base: ControlSettings,
    settings: EngineSettings,
    log: Log,
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Search the decision settings on `streams` (offline replay): the GRID, then `land`'s
    own agreement on the grid's fastest settings, then the release time around the best.
    Returns the selected row (by `rank`) and every row tried, best first."""
    memo = MemoClassifier(classifier)
    recs = {
        stride: recognize_all(streams, memo, settings.model_copy(update={"stride": stride}), base)
        for stride in GRID["stride"]
    }
    rows: list[dict[str, Any]] = []

    def try_config(stride: int, params: dict[str, Any]) -> None:
        summary = evaluate_config(streams, recs[stride], base.model_copy(update=params))
        rows.append(
            {"stride": stride, **params, **brief(summary), "utility": round(utility(summary), 4)}
        )

    combos = list(itertools.product(*GRID.values()))
    for n, values in enumerate(combos, 1):
        params = dict(zip(GRID, values, strict=True))
        try_config(params.pop("stride"), params)
        if n % 30 == 0:
            log(f"  tuning {n}/{len(combos)}")
    fastest = sorted(rows, key=lambda r: -(r["on_time_rate"] or 0.0))[:LAND_TRIED_ON]
    for row in fastest:
        params = {k: row[k] for k in ("threshold", "confirm", "debounce_s")}
        for n in LAND_CONFIRM:
            if n > params["confirm"]:
                try_config(row["stride"], {**params, "confirm_by_command": {"land": n}})
    log(f"  tuning: {len(rows)} settings tried, refining the release time")
    best = max(rows, key=rank)
    for values in itertools.product(*REFINE.values()):
        params = {k: best[k] for k in ("threshold", "confirm", "debounce_s")}
        if "confirm_by_command" in best:
            params["confirm_by_command"] = best["confirm_by_command"]
        params.update(dict(zip(REFINE, values, strict=True)))
        try_config(best["stride"], params)
    rows.sort(key=rank, reverse=True)
    return rows[0], rows


# -- the benchmark --------------------------------------------------------------------
@dataclass(frozen=True)
class LatencyConfig:
    """The benchmark's size: evaluation streams (seeds 1000...) of `segments` random
    gestures of `min_s`..`max_s` seconds; with `tune`, `tune_streams` tuning streams
    (seeds 0...) first."""

    streams: int = 36
    segments: int = 60
    min_s: float = 3.0
    max_s: float = 6.0
    tune: bool = False
    tune_streams: int = 18


@dataclass
class LatencyReport:
    """The benchmark's JSON-ready `result`, every scored latency of the engine run (for
    the histogram) and the offline replay's `onset_stages` rows (for the stages plot)."""

    result: dict[str, Any]
    latencies: list[float] = field(default_factory=list)
    stages: list[dict[str, Any]] = field(default_factory=list)


def measure(
    classifier: Classifier,
    clips: Sequence[Clip],
    config: LatencyConfig,
    log: Log = lambda msg: None,
) -> LatencyReport:
    """Run the benchmark (see the module) with `classifier` on the LASER `clips`."""
    settings = EngineSettings()
    # Tuning searches the moving average's grid; without it, the shipped defaults.
    control = AVERAGE_RULE if config.tune else ControlSettings()
    result: dict[str, Any] = {}
    if config.tune:
        seeds = list(range(config.tune_streams))
        log(f"tuning on {len(seeds)} streams (seeds {seeds[0]}..{seeds[-1]})")
        tune_streams = build_streams(
            clips, seeds, config.segments, "test", config.min_s, config.max_s
        )
        best, rows = tune(tune_streams, classifier, control, settings, log)
        hours = sum(s.duration_s for s in tune_streams) / 3600
        result["tuning"] = {
            "seeds": seeds,
            "stream_hours": round(hours, 3),
            "method": "offline replay of the filter and controller on cached "
            "classifier outputs; selected by rank(): most commands within 2.5 s among "
            f"settings with < {MAX_WRONG_PER_HOUR} wrong or spurious per hour",
            "selected": best,
            "top": rows[:15],
            "configs": len(rows),
            "fewest_wrong": min(
                rows, key=lambda r: (r["wrong_or_spurious_per_hour"], -r["utility"])
            ),
            "all": rows,
        }
        log(f"selected {best}")
        settings = settings.model_copy(update={"stride": best["stride"]})
        control = control.model_copy(update={k: best[k] for k in TUNED if k in best})
    seeds = list(range(1000, 1000 + config.streams))
    log(f"evaluating on {len(seeds)} streams (seeds {seeds[0]}..{seeds[-1]}) with {control}")
    streams = build_streams(clips, seeds, config.segments, "test", config.min_s, config.max_s)
    memo = MemoClassifier(classifier)  # the offline replays below reuse the engine's answers
    total, per_view, events = Score(), {v: Score() for v in VIEWS}, 0
    for n, stream in enumerate(streams, 1):
        run = engine_run(stream, control, settings, memo)
        events += run.events
        score = run.score(stream)
        total.merge(score)
        per_view[stream.view].merge(score)
        if n % 6 == 0:
            log(f"  engine {n}/{len(streams)}: {brief(total.summary())}")
    # The same evaluation streams through the offline replay: our settings (a check
    # against the engine, and the stages), the paper's, the cautious profile's.
    cautious = result.get("tuning", {}).get("fewest_wrong")
    recs = {settings.stride: recognize_all(streams, memo, settings, control)}
    paper_summary = evaluate_config(streams, recs[settings.stride], PAPER)
    ours, stages = Score(), []
    for stream, rec in zip(streams, recs[settings.stride], strict=True):
        run = decide(rec, control)
        ours.merge(run.score(stream))
        stages += onset_stages(stream, run, control.filter_size)
    ours_offline = ours.summary()
    if cautious:
        # The tuning grid's setting with the fewest wrong commands, on the evaluation
        # streams: what avoiding wrong commands costs in latency.
        params = {
            k: cautious[k]
            for k in ("threshold", "confirm", "debounce_s", "release_s", "confirm_by_command")
            if k in cautious
        }
        cautious_control = control.model_copy(update=params)
        stride = cautious["stride"]
        if stride not in recs:
            stride_settings = settings.model_copy(update={"stride": stride})
            recs[stride] = recognize_all(streams, memo, stride_settings, control)
        result["cautious_profile"] = {
            "stride": stride,
            "control": cautious_control.model_dump(),
            **brief(evaluate_config(streams, recs[stride], cautious_control)),
            "note": "the tuning grid's setting with the fewest wrong commands (offline replay)",
        }
    summary = total.summary()
    result.update(
        streams={
            **describe_streams(streams, seeds, config.segments, config.min_s, config.max_s),
            "views": list(VIEWS),
            "fps": 30.0,
            "events_published": events,
        },
        settings={"control": control.model_dump(), "engine": settings.model_dump(mode="json")},
        result=summary,
        utility=round(utility(summary), 4),
        per_view={v: brief(s.summary()) for v, s in per_view.items()},
        per_view_gesture={v: s.summary()["latency_by_gesture"] for v, s in per_view.items()},
        stages={
            "method": "offline replay; named: the classifier's top label in filter_size "
            "recognitions running; passed: the decision rule passes it; "
            "commanded: its command. Figures over the gestures that were commanded",
            "all": stage_figures(stages),
            **{v: stage_figures([r for r in stages if r["view"] == v]) for v in VIEWS},
        },
        wrong_examples=total.wrong_examples,
        offline_check={
            "same_as_engine": brief(ours_offline) == brief(summary),
            "offline": brief(ours_offline),
        },
        paper_settings={
            "control": PAPER.model_dump(),
            **brief(paper_summary),
            "note": "filter of 3, no threshold, 10 s debounce (offline replay)",
        },
    )
    return LatencyReport(result, total.latencies, stages)
