"""Fusion across drones: one camera against two and three, fusion off and on.

(a) Stitched multi-view streams: random scripts from the LASER clips' temporal test parts,
seen at once by views f, l and r (`stitch_views`), clean and through the capture model's
`field` condition (each view its own frame rate, losses and jitter), through the real
engine; camera sets f, l, r, f+l, f+r, l+r, f+l+r (main first), with the default decision
settings and with `rearm_on_handover = false` (handovers do not disarm).
(b) The closed-loop simulator: the synthetic operator performing a random script, seen
by fixed `sim:` cameras 5 m away at 2.5 m (front, 45 degrees right, 45 degrees left) on
one scene, through the real engine.

    python -m bench.fusion --checkpoint /tmp/fusion/temporal.pt [--only stitched|sim]

Writes bench/results/fusion.json (a part run alone keeps the other part's results).
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"
SETS = (("f",), ("l",), ("r",), ("f", "l"), ("f", "r"), ("l", "r"), ("f", "l", "r"))
BRIEF = ("expected_commands", "hit_rate", "on_time_rate", "latency_median_s", "latency_p95_s",
         "wrong", "re_arms", "wrong_arming", "wrong_acting", "repeats",
         "wrong_or_spurious_per_hour", "stream_hours")  # fmt: skip
Log = Callable[[str], None]


class Tally:
    """Scores and window counts of one cell (camera count or set, fusion, condition)."""

    def __init__(self) -> None:
        from proxima.evaluation.scoring import Score

        self.score = Score()
        self.windows = {"own": [0, 0], "fused": [0, 0]}  # right, total
        self.handovers = 0
        self.runs = 0

    def add(self, score: Any, acc: dict[str, Any], handovers: int) -> None:
        self.score.merge(score)
        for kind in ("own", "fused"):
            total = acc[f"{kind}_windows"]
            if total:
                self.windows[kind][0] += round(acc[kind] * total)
                self.windows[kind][1] += total
        self.handovers += handovers
        self.runs += 1

    def summary(self, fused: bool) -> dict[str, Any]:
        s = self.score.summary()
        right, total = self.windows["fused" if fused else "own"]
        return {
            **{k: s[k] for k in BRIEF},
            "window_accuracy": round(right / total, 4) if total else None,
            "windows": total,
            "handovers": self.handovers,
            "runs": self.runs,
            "missed_by_gesture": s["missed_by_gesture"],
            "wrong_by_pair": s["wrong_by_pair"],
        }


def fusion_figures(settings: Any) -> dict[str, Any]:
    """The fusion settings a part ran with, for its JSON."""
    return {k: getattr(settings, k) for k in ("fusion_overrule_below", "fusion_arms")}


def stitched(
    checkpoint: Path,
    seeds: Sequence[int],
    segments: int,
    conditions: Sequence[str],
    settings: Any,
    control_names: Sequence[str],
    log: Log,
) -> dict[str, Any]:
    from proxima.control import ControlSettings
    from proxima.evaluation.fusion import captured, engine_run_views
    from proxima.evaluation.replay import MemoClassifier
    from proxima.evaluation.stitch import random_plan, stitch_views
    from proxima.gesture.capture import condition
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.ensemble import load_checkpoint
    from proxima.gesture.laser import load_laser_dir

    clips = load_laser_dir(resolve_dataset(None))
    clf = MemoClassifier(load_checkpoint(checkpoint))
    every = {"default": ControlSettings(), "no_rearm": ControlSettings(rearm_on_handover=False)}
    controls = {k: every[k] for k in control_names}
    cells: dict[tuple[str, str, str, str], Tally] = {}
    for cond in conditions:
        for seed in seeds:
            plan = random_plan(np.random.default_rng(seed), segments)
            views = stitch_views(clips, plan, ("f", "l", "r"), "test", seed=seed)
            if cond != "clean":
                model = condition(cond)
                views = {
                    v: captured(s, model, np.random.default_rng([seed, k]))
                    for k, (v, s) in enumerate(views.items())
                }
            for cname, control in controls.items():
                for cams in SETS:
                    if cname != "default" and len(cams) == 1:
                        continue  # one camera: no handover, the same as the default
                    for fusion in ("off", "on") if len(cams) > 1 else ("off",):
                        # one camera decides the same with fusion on (tests/engine/test_fusion.py)
                        run = engine_run_views(
                            [views[v] for v in cams],
                            control,
                            settings.model_copy(update={"fusion": fusion}),
                            clf,
                        )
                        score = run.score(views[cams[0]])
                        acc = run.window_accuracy(views)
                        for key in ("+".join(cams), f"{len(cams)} camera(s)"):
                            cell = cells.setdefault((cond, cname, key, fusion), Tally())
                            cell.add(score, acc, run.handovers)
            log(f"  stitched {cond} seed {seed}: {len(clf)} windows classified so far")
    out: dict[str, Any] = {}
    for (cond, cname, key, fusion), cell in sorted(cells.items()):
        out.setdefault(cond, {}).setdefault(cname, {}).setdefault(key, {})[fusion] = cell.summary(
            fusion == "on"
        )
    return {
        "method": "random scripts of the LASER temporal test parts, views f, l, r seen at "
        "once (stitch_views), through the real engine; commands scored against the main "
        "(first) stream's truth; window accuracy over every stream's windows wholly inside "
        "one gesture (own: the classifier's, fused: after fusion)",
        "seeds": list(seeds),
        "segments_per_stream": segments,
        "conditions": list(conditions),
        **fusion_figures(settings),
        "controls": {k: v.model_dump() for k, v in controls.items()},
        "results": out,
    }


# -- the closed-loop simulator ---------------------------------------------------------
SIM_CAMERAS = {"front": 0.0, "right45": 45.0, "left45": -45.0}
SIM_SETS = (("front",), ("right45",), ("left45",), ("front", "right45"),
            ("front", "left45"), ("front", "right45", "left45"))  # fmt: skip


def sim_uri(scene: str, bearing_deg: float, depth_noise: float) -> str:
    """A fixed camera 5 m from the operator (at the origin facing south) at
    `bearing_deg` from their facing, 2.5 m up, looking at their chest."""
    side = math.radians(180.0 + bearing_deg)
    north, east = 5 * math.cos(side), 5 * math.sin(side)
    return f"sim:{scene}?at={north:.3f},{east:.3f},2.5&zjitter={depth_noise:g}"


def sim(
    checkpoint: Path,
    seeds: Sequence[int],
    segments: int,
    depth_noises: Sequence[float],
    settings: Any,
    log: Log,
) -> dict[str, Any]:
    from proxima.control import ControlSettings
    from proxima.engine.config import StreamSpec
    from proxima.engine.runner import Engine
    from proxima.evaluation.fusion import ViewsRun
    from proxima.evaluation.replay import MemoClassifier
    from proxima.evaluation.scoring import score_commands
    from proxima.evaluation.stitch import random_plan
    from proxima.events import EventBus
    from proxima.gesture.ensemble import load_checkpoint
    from proxima.sim import registry
    from proxima.sim.config import OperatorConfig, SceneConfig, build_scene

    clf = MemoClassifier(load_checkpoint(checkpoint))
    cells: dict[tuple[str, str, str], Tally] = {}
    for depth in depth_noises:
        for seed in seeds:
            plan = random_plan(np.random.default_rng(seed), segments)
            script = ",".join(f"{g}:{s:.1f}" for g, s in plan)
            for cams in SIM_SETS:
                for fusion in ("off", "on"):
                    name = f"fusion-bench-{seed}"
                    cfg = SceneConfig(
                        seed=seed,
                        loop=False,
                        operator=OperatorConfig(heading_deg=180.0, script=script),
                        bystanders=[],
                    )
                    scene = build_scene(cfg, name)
                    registry.register_scene(name, scene)
                    specs = [
                        StreamSpec(
                            name=c, uri=sim_uri(name, SIM_CAMERAS[c], depth), priority=k,
                            drone="main",
                        )
                        for k, c in enumerate(cams)
                    ]  # fmt: skip
                    run = ViewsRun(clf.labels)
                    bus = EventBus()
                    bus.add_listener(run.add)
                    engine = Engine(
                        specs, bus, control=ControlSettings(),
                        settings=settings.model_copy(update={"fusion": fusion}), realtime=False,
                        classifier=clf,
                    )  # fmt: skip
                    if engine.fusion is not None:
                        engine.fusion.listener = run.on_fused
                    engine.run()
                    registry.unregister_scene(name)
                    fps = cfg.fps
                    op = scene.operator
                    truth = [{"gesture": g, "onset_t": on / fps} for g, _, on, _ in op.segments]
                    duration = len(op.labels) / fps
                    score = score_commands(truth, run.commands, duration, run.arming)
                    acc = sim_window_accuracy(run, op.segments, fps)
                    for key in ("+".join(cams), f"{len(cams)} camera(s)"):
                        cell = cells.setdefault((f"zjitter {depth:g}", key, fusion), Tally())
                        cell.add(score, acc, run.handovers)
            log(f"  sim zjitter {depth:g} seed {seed} done")
    out: dict[str, Any] = {}
    for (cond, key, fusion), cell in sorted(cells.items()):
        out.setdefault(cond, {}).setdefault(key, {})[fusion] = cell.summary(fusion == "on")
    return {
        "method": "the synthetic operator (no bystanders) performs a random script; fixed "
        "sim: cameras 5 m away at 2.5 m looking at the chest (front, 45 degrees right, 45 "
        "left), x/y jitter and visibility noise as measured, z jitter as given; the real "
        "engine, commands scored against the script's onsets",
        "cameras": {c: sim_uri("SCENE", b, 0.0) for c, b in SIM_CAMERAS.items()},
        "seeds": list(seeds),
        "segments_per_stream": segments,
        **fusion_figures(settings),
        "results": out,
    }


def sim_window_accuracy(
    run: Any, segments: Sequence[tuple[str, int, int, int]], fps: float, window: int = 60
) -> dict[str, Any]:
    """`ViewsRun.window_accuracy` for a sim scene: windows wholly inside a step's own
    frames (its entry transition excluded)."""
    out: dict[str, Any] = {}
    for kind, per_stream in (("own", run.own), ("fused", run.fused)):
        right = total = 0
        for rows in per_stream.values():
            for t, probs in rows:
                k = round(t * fps)
                seg = next((s for s in segments if s[2] <= k - window + 1 and k < s[3]), None)
                if seg is None or not seg[0]:
                    continue
                total += 1
                right += run.labels[int(np.argmax(probs))] == seg[0]
        out[kind] = right / total if total else None
        out[f"{kind}_windows"] = total
    return out


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument(
        "--checkpoint",
        type=Path,
        required=True,
        help="a --split temporal model: one file, an ensemble file or comma-joined files",
    )
    ap.add_argument("--only", choices=("stitched", "sim"), default=None)
    ap.add_argument("--seeds", type=int, default=6, help="stitched scripts (seeds 2000...)")
    ap.add_argument("--segments", type=int, default=30)
    ap.add_argument("--conditions", nargs="+", default=["clean", "field"])
    ap.add_argument(
        "--controls", nargs="+", default=["default"], choices=("default", "no_rearm"),
        help="decision settings: the defaults; no_rearm = rearm_on_handover false",
    )  # fmt: skip
    ap.add_argument("--sim-seeds", type=int, default=3, help="sim scripts (seeds 0...)")
    ap.add_argument("--sim-segments", type=int, default=12)
    ap.add_argument("--depth-noise", type=float, nargs="+", default=[0.0, 1.0])
    ap.add_argument(
        "--overrule-below",
        type=float,
        default=None,
        help="EngineSettings.fusion_overrule_below (default: its default)",
    )
    ap.add_argument(
        "--no-fusion-arms",
        dest="fusion_arms",
        action="store_false",
        help="EngineSettings.fusion_arms = false: only a stream's own decision arms control",
    )
    ap.add_argument("--out", type=Path, default=RESULTS / "fusion.json")
    args = ap.parse_args(argv)

    import torch

    from proxima.engine.config import EngineSettings

    torch.set_num_threads(1)
    fusion: dict[str, Any] = {"fusion_arms": args.fusion_arms}
    if args.overrule_below is not None:
        fusion["fusion_overrule_below"] = args.overrule_below
    settings = EngineSettings(**fusion)  # fusion off or on per run (model_copy)
    t0 = time.perf_counter()

    def log(msg: str) -> None:
        print(f"[{time.perf_counter() - t0:6.0f}s] {msg}", flush=True)

    result: dict[str, Any] = json.loads(args.out.read_text()) if args.out.is_file() else {}
    result.update(
        benchmark="fusion",
        checkpoint=str(args.checkpoint),
        date=time.strftime("%Y-%m-%d"),
    )
    cmd = "python -m bench.fusion " + shlex.join(argv if argv is not None else sys.argv[1:])
    if args.only in (None, "stitched"):
        seeds = range(2000, 2000 + args.seeds)
        part = stitched(
            args.checkpoint, seeds, args.segments, args.conditions, settings, args.controls, log
        )
        result["stitched"] = {"command": cmd, **part, "seconds": round(time.perf_counter() - t0)}
    if args.only in (None, "sim"):
        t1 = time.perf_counter()
        part = sim(
            args.checkpoint, range(args.sim_seeds), args.sim_segments, args.depth_noise,
            settings, log,
        )  # fmt: skip
        result["sim"] = {"command": cmd, **part, "seconds": round(time.perf_counter() - t1)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    log(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
