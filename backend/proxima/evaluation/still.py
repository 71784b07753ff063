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
arms crossed low in front), so a command can be the right reading of a stance.
`bench/still_operator.py` runs it and draws each stance beside what it was read as.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings
from proxima.evaluation.replay import engine_run
from proxima.evaluation.stitch import StitchedStream, smoothstep, stitch_views
from proxima.gesture.clip import Clip
from proxima.gesture.idle import STILL_SPEED, still_prefix

MIN_FRAMES = 15  # half a second at 30 fps
STILL_S = 10.0
ARM_S = 6.0  # long enough for have_command to arm in every view
FPS = 30.0


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


def still_operator(checkpoint: str | Path, clips: Sequence[Clip]) -> dict[str, Any]:
    """Every still stance of the LASER `clips`, played after arming through the engine
    with `checkpoint` and the default settings; the JSON-ready result.

    Raises:
        FileNotFoundError, ValueError: the checkpoint is missing or not a checkpoint.
    """
    from proxima.gesture.ensemble import load_checkpoint

    clf = load_checkpoint(checkpoint)
    control, settings = ControlSettings(), EngineSettings()
    stances = []
    for clip in clips:
        rows = still_prefix(clip.xyz)
        if rows < MIN_FRAMES:
            continue
        arm = stitch_views(clips, [("have_command", ARM_S)], (clip.view,), "test")[clip.view]
        stream, start = stance_stream(arm, clip, rows)
        result = engine_run(stream, control, settings, clf)
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
