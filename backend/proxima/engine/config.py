"""Settings of the per-stream recognition pipeline and the multi-stream runner.

Both models are sections of `proxima.settings.Settings` as they are (`[[streams]]` and
`[engine]` in a console's TOML file), so every field here can be set from there.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from proxima.engine.window import DEFAULT_CLOCK, ClockSetting
from proxima.gesture.capture.model import MAX_GAP_S

# The stream URIs `proxima.ingest.open_source` opens (what a spec may name).
URI_SCHEMES = ("webcam:", "file:", "rtsp://", "rtsps://", "replay:", "sim:")
NAME_PATTERN = r"^[A-Za-z0-9_.-]+$"


class StreamSpec(BaseModel):
    """One camera stream: its name, where frames come from and which drone carries it.

    Streams are ranked by `priority` (0 = the main drone's camera, 1 = secondary, ...),
    ties by their order in the engine's list."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = Field(min_length=1, pattern=NAME_PATTERN)
    uri: str = Field(
        description="webcam:N, file:PATH, rtsp://..., replay:PATH[@FPS], sim:SCENE[?...][#DRONE]"
    )
    drone: str = Field("", description="drone whose camera this is (default: the name)")
    priority: int = Field(0, ge=0, description="0 = main drone, 1 = secondary, ...")
    checkpoint: Path | None = Field(
        None,
        description="gesture model, or comma-joined models (an ensemble; default: the engine's)",
    )

    @model_validator(mode="before")
    @classmethod
    def _default_drone(cls, data: Any) -> Any:
        if isinstance(data, dict) and not data.get("drone"):
            return {**data, "drone": data.get("name", "")}
        return data

    @model_validator(mode="after")
    def _check_uri(self) -> StreamSpec:
        if not self.uri.startswith(URI_SCHEMES):
            raise ValueError(
                f"stream {self.name!r}: uri {self.uri!r} must start with one of "
                + ", ".join(URI_SCHEMES)
            )
        return self

    @property
    def kind(self) -> str:
        """`replay` for landmark replays (no pixels), `sim` for simulated cameras (no
        pixels: the people they see), `camera` for everything else."""
        if self.uri.startswith("replay:"):
            return "replay"
        return "sim" if self.uri.startswith("sim:") else "camera"


class EngineSettings(BaseModel):
    """How each stream turns frames into recognitions."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    checkpoint: Path | None = Field(
        None,
        description="gesture model of the streams that name none (default: the shipped "
        "one, `proxima.gesture.classifier.default_checkpoint()`)",
    )
    stride: int = Field(
        5, ge=1, description="classify the window every `stride` frames (tuned at 30 fps)"
    )
    max_gap_s: float = Field(
        MAX_GAP_S,
        gt=0.0,
        description="a pause between poses longer than this restarts the window and "
        "empties the decision rule; a shorter one is bridged (the window holds the poses "
        "on both sides), as a field camera loses the operator for a moment",
    )
    window_clock: ClockSetting = Field(
        DEFAULT_CLOCK,
        description="`model`: the clock the checkpoint's training windows had (`proxima "
        "train --window-clock`; older checkpoints: poses); `poses`: the last N poses "
        "received, whatever their times (a 15 fps camera's 30-pose window spans 2 s); "
        "`time`: the last (N - 1) / 30 s resampled to N poses and classified every "
        "stride / 30 s, whatever the camera's rate (`proxima.engine.window`)",
    )
    smooth_replays: bool = Field(
        True,
        description="replayed landmark streams pass the One Euro filter the camera path's "
        "tracker applies (`proxima.pose.LIVE_ONE_EURO`), the one training windows pass: "
        "one smoothing rule for live, replay and training",
    )
    pose_every: int = Field(1, ge=1, description="publish a PoseEvent every N frames")
    num_poses: int = Field(2, ge=1, description="people the pose estimator looks for")
    pose_model: Path | None = Field(None, description="MediaPipe pose model (default: resolved)")
    stale_after_s: float = Field(
        1.0,
        gt=0.0,
        description="wall seconds after which a silent live stream no longer holds back "
        "the time-ordered decisions of the others",
    )
    torch_threads: int = Field(1, ge=1, description="torch threads for inference")
    fusion: Literal["off", "on"] = Field(
        "off",
        description="combine the classified windows of every stream that sees the operator "
        "(visibility-weighted calibrated log-probabilities; `proxima.engine.fusion`) before "
        "each stream's filter; the priority arbiter still picks the driving stream",
    )
    fusion_max_age_s: float = Field(
        0.4,
        gt=0.0,
        description="another stream's window counts if it ended at most this long before "
        "(stride 5 is 0.17 s at 30 fps, 0.33 s at 15)",
    )
    fusion_min_visibility: float = Field(
        0.5,
        ge=0.0,
        le=1.0,
        description="a window whose arms (shoulders, elbows, wrists) are seen less than this "
        "on average contributes nothing",
    )
    fusion_overrule_below: float = Field(
        0.0,
        ge=0.0,
        le=1.0,
        description="the other streams may disagree with a stream's window only while its own "
        "top probability is below this (1: always, 0: never); agreeing ones always count",
    )
    fusion_arms: bool = Field(
        True,
        description="fused evidence may arm control; false: while disarmed, `have_command` is "
        "each stream's own decision (the other cameras speed up commands, not the arming)",
    )
