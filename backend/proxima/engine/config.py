"""Settings of the per-stream recognition pipeline and the multi-stream runner."""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field


class StreamSpec(BaseModel):
    """One camera stream: its name, where frames come from and which drone carries it.

    Streams are ranked by their order in the engine's list (main first)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = Field(min_length=1)
    uri: str = Field(min_length=1, description="webcam:N, file:PATH, rtsp://..., replay:PATH[@FPS]")
    drone: str = Field("", description="drone whose camera this is (default: the stream name)")
    checkpoint: Path | None = Field(None, description="gesture model (default: the engine's)")

    @property
    def drone_name(self) -> str:
        return self.drone or self.name


class EngineSettings(BaseModel):
    """How each stream turns frames into recognitions."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    stride: int = Field(
        5, ge=1, description="classify the window every `stride` frames (tuned at 30 fps)"
    )
    max_gap_s: float = Field(
        0.25,
        gt=0.0,
        description="a pause between poses longer than this restarts the window "
        "(training windows never bridge more than 5 missing frames at 30 fps)",
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
