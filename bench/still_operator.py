"""What an armed operator who stands still is commanded to do.

The latency benchmark's streams run one gesture into the next; a real operator also
pauses. The LASER clips that begin with the operator standing still (elbows and wrists
moving less than STILL_SPEED per frame, smoothed over 5 frames, for at least MIN_FRAMES
frames) give real still stances in every view. Each is played after its view's
`have_command` (which arms control), going back and forth through its recorded frames
for STILL_S seconds so the pose keeps its own small movements, through the real engine
(replay source, stream pipeline, controller) with the default settings. A command after
the stance begins is what standing still that way means to the drone.

Static marshalling signals are stances too (`hover`: arms held out sideways; `land`:
arms crossed low in front), so a command can be the right reading of a stance; the
picture shows each stance beside what it was read as.

    python -m bench.still_operator [--checkpoint models/gesture-default.pt]

Writes bench/results/still_operator.json and still_operator.png.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bench.command_latency import engine_run
from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings
from proxima.engine.stitch import StitchedStream, smoothstep, stitch_views
from proxima.gesture.clip import Clip

RESULTS = Path(__file__).resolve().parent / "results"
ROOT = Path(__file__).resolve().parent.parent
ARMS = [13, 14, 15, 16]  # MediaPipe elbows and wrists
STILL_SPEED = 0.006  # normalised image units per frame (x and y each run 0..1)
MIN_FRAMES = 15  # half a second at 30 fps
STILL_S = 10.0
ARM_S = 6.0  # long enough for have_command to arm in every view
FPS = 30.0


def still_prefix(xyz: np.ndarray) -> int:
    """Frames from the start of a clip (T, 33, 3) during which the elbows and wrists stay
    still: their largest 2D step, averaged over 5 frames, at most STILL_SPEED."""
    step = np.linalg.norm(np.diff(xyz[:, ARMS, :2], axis=0), axis=-1).max(axis=1)
    smooth = np.convolve(step, np.ones(5) / 5, mode="same")
    moving = np.flatnonzero(smooth > STILL_SPEED)
    return int(moving[0]) if len(moving) else len(xyz)


def back_and_forth(n: int, frames: int) -> np.ndarray:
    """Row indices 0, 1, ..., n-1, n-2, ..., 1, 0, 1, ... (`frames` of them)."""
    cycle = np.concatenate([np.arange(n), np.arange(n - 2, 0, -1)]) if n > 1 else np.zeros(1)
    return np.resize(cycle.astype(np.int64), frames)


def stance_stream(arm: StitchedStream, clip: Clip, rows: int) -> tuple[StitchedStream, float]:
    """`arm`, then a 0.5 s move to the clip's first pose (eased as the stitched streams'
    transitions are), then its first `rows` rows back and forth for STILL_S; returns the
    stream and the stance's start time."""
    move = round(0.5 * FPS)
    idx = back_and_forth(rows, round(STILL_S * FPS))
    frac = smoothstep(np.arange(1, move + 1) / (move + 1))[:, None, None]
    a, b = arm.xyz[-1], clip.xyz[0]
    xyz = np.concatenate([arm.xyz, a + frac * (b - a), clip.xyz[idx]]).astype(np.float32)
    vis_move = np.repeat(np.minimum(arm.visibility[-1], clip.visibility[0])[None], move, 0)
    vis = np.concatenate([arm.visibility, vis_move, clip.visibility[idx]]).astype(np.float32)
    first = int(arm.frames[-1]) + 1
    frames = np.concatenate([arm.frames, np.arange(first, first + move + len(idx))])
    stream = StitchedStream(
        view=arm.view, fps=FPS, frames=frames, xyz=xyz, visibility=vis, segments=arm.segments
    )
    return stream, (first + move - 1) / FPS


def run(checkpoint: Path, clips: Sequence[Clip]) -> dict[str, Any]:
    """Every still stance of the LASER `clips`, played after arming through the engine
    with `checkpoint` and the default settings; the JSON-ready result."""
    from proxima.gesture.classifier import GestureClassifier

    clf = GestureClassifier.load(checkpoint)
    control, settings = ControlSettings(), EngineSettings()
    stances = []
    with tempfile.TemporaryDirectory(prefix="proxima-still-") as tmp:
        for clip in clips:
            rows = still_prefix(clip.xyz)
            if rows < MIN_FRAMES:
                continue
            arm = stitch_views(clips, [("have_command", ARM_S)], (clip.view,), "test")[clip.view]
            stream, start = stance_stream(arm, clip, rows)
            path = Path(tmp) / f"{clip.name}.csv"
            stream.write(path)
            result = engine_run(path, control, settings, clf)
            armed = [a for t, a in result.arming if t <= start]
            stances.append(
                {
                    "clip": clip.name,
                    "view": clip.view,
                    "still_frames": rows,
                    "armed_at_start": bool(armed and armed[-1]),
                    "commands": [
                        {"t_after_start_s": round(c["t"] - start, 3), "command": c["command"]}
                        for c in result.commands
                        if c["t"] > start and c["stream"]
                    ],
                }
            )
    return {
        "benchmark": "still_operator",
        "checkpoint": str(checkpoint),
        "settings": {"control": control.model_dump(), "engine": settings.model_dump(mode="json")},
        "still_speed": STILL_SPEED,
        "min_frames": MIN_FRAMES,
        "still_s": STILL_S,
        "stances": stances,
        "stances_with_a_command": sum(bool(s["commands"]) for s in stances),
    }


def plot(result: dict, clips: dict[str, Clip], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from proxima.gesture.skeleton import BONES

    stances = result["stances"]
    cols = min(len(stances), 7)
    rows = -(-len(stances) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(1.9 * cols, 3.2 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, s in zip(axes.flat, stances, strict=False):
        clip = clips[s["clip"]]
        x = clip.xyz[: s["still_frames"]].mean(axis=0)
        px, py = x[:, 0] * clip.aspect, x[:, 1]
        for a, b in BONES:
            ax.plot([px[a], px[b]], [py[a], py[b]], color="#4477aa", lw=1.5)
        ax.set_aspect("equal")
        ax.invert_yaxis()
        said = ", ".join(c["command"] for c in s["commands"]) or "no command"
        ax.set_title(f"from {clip.gesture} ({clip.view})\n-> {said}", fontsize=7)
    fig.suptitle(f"armed operator standing still for {STILL_S:.0f} s", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--checkpoint", type=Path, default=ROOT / "models" / "gesture-default.pt")
    ap.add_argument("--data", default=None, help="LASER folder (default: resolved)")
    ap.add_argument("--out", type=Path, default=RESULTS / "still_operator.json")
    args = ap.parse_args(argv)

    import torch

    torch.set_num_threads(1)
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    started = time.perf_counter()
    clips = load_laser_dir(resolve_dataset(args.data))
    result = run(args.checkpoint, clips)
    result["command"] = "python -m bench.still_operator " + shlex.join(argv or sys.argv[1:])
    result["date"] = time.strftime("%Y-%m-%d")
    result["seconds"] = round(time.perf_counter() - started, 1)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    plot(result, {c.name: c for c in clips}, args.out.with_suffix(".png"))
    for s in result["stances"]:
        said = ", ".join(f"{c['command']} at {c['t_after_start_s']} s" for c in s["commands"])
        print(f"{s['clip']:28s} armed={s['armed_at_start']!s:5s} {said or 'no command'}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
