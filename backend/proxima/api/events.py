"""Events the console itself puts on the bus: sample recording progress, JPEG
thumbnails of camera streams and the live model changing."""

from __future__ import annotations

from dataclasses import dataclass, field

from proxima.types import Event


@dataclass(frozen=True, kw_only=True)
class RecordingEvent(Event):
    """Progress of a sample recording: countdown -> recording -> done | failed."""

    recording: str
    state: str
    frames_done: int
    frames_total: int
    countdown_s: float = 0.0
    sample_id: int | None = None
    detail: str = ""
    type: str = field(default="recording", init=False)


@dataclass(frozen=True, kw_only=True)
class ThumbnailEvent(Event):
    """A small JPEG of a camera stream's newest frame, base64 encoded, sent at a modest
    rate so the Live page shows what the camera sees without streaming video."""

    jpeg_b64: str
    width: int
    height: int
    type: str = field(default="thumbnail", init=False)


@dataclass(frozen=True, kw_only=True)
class ModelEvent(Event):
    """The live engine's model changed: `action` is promote, rollback or restore (at
    start, the model promoted before the restart); `checkpoint` is its name in models/."""

    checkpoint: str
    previous: str = ""
    action: str
    by: str = ""
    type: str = field(default="model", init=False)
