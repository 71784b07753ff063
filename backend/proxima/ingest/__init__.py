"""Camera and replay streams behind one interface, chosen by a URI.

    from proxima.ingest import open_source
    with open_source("replay:clip.csv@30", realtime=False) as src:
        for frame in src:        # proxima.types.Frame
            ...

URIs: `webcam:N`, `file:PATH` (video), `rtsp://...`, `replay:PATH[@FPS]` (landmark CSV
in the LASER format, frames carry a `pose` and no image), `sim:SCENE[?...][#DRONE]` (a
simulated camera, frames carry every person it sees as `poses`; docs/sim.md). See
docs/ingest-and-pose.md.
"""

from __future__ import annotations

from typing import Any

from proxima.ingest.base import (
    ALLOWED_TRANSITIONS,
    FrameSource,
    InvalidTransition,
    SourceError,
    StateChange,
    StateListener,
)
from proxima.ingest.landmark_csv import (
    LandmarkCsvError,
    LandmarkTrack,
    read_landmark_csv,
    write_landmark_csv,
)
from proxima.ingest.replay import DEFAULT_REPLAY_FPS, ReplaySource

__all__ = [
    "ALLOWED_TRANSITIONS",
    "DEFAULT_REPLAY_FPS",
    "FrameSource",
    "InvalidTransition",
    "LandmarkCsvError",
    "LandmarkTrack",
    "ReplaySource",
    "SourceError",
    "StateChange",
    "StateListener",
    "open_source",
    "parse_replay_uri",
    "read_landmark_csv",
    "write_landmark_csv",
]

URI_HELP = (
    "expected webcam:N, file:PATH, rtsp://HOST/PATH, replay:PATH[@FPS] or "
    "sim:SCENE[?KEY=VALUE&...][#DRONE]"
)


def parse_replay_uri(spec: str) -> tuple[str, float]:
    """Split `PATH[@FPS]` (the part after `replay:`) into path and fps.

    The suffix counts as a rate only when it is a positive number, so a path that merely
    contains `@` still works.

    Raises:
        SourceError: the rate is given but is not > 0.
    """
    path, sep, rate = spec.rpartition("@")
    if sep:
        try:
            fps = float(rate)
        except ValueError:
            return spec, DEFAULT_REPLAY_FPS
        if not fps > 0:
            raise SourceError(f"replay:{spec}: FPS must be a number > 0, got {rate!r}")
        return path, fps
    return spec, DEFAULT_REPLAY_FPS


def open_source(
    uri: str,
    *,
    realtime: bool = True,
    on_state: StateListener | None = None,
    **options: Any,
) -> FrameSource:
    """Open the stream `uri` names and return its `FrameSource`.

    `realtime` paces file, replay and sim sources to their timestamps (False: as fast
    as possible); live sources are always real time. `on_state` receives every
    `StateChange`. `options` go to the source class (e.g. `open_timeout_s`,
    `read_timeout_s`, `policy` for RTSP).

    Raises:
        SourceError: unknown URI, missing or non-video file, camera that cannot be
            opened, a malformed replay CSV (`LandmarkCsvError`, naming file and line), or
            a bad sim URI, scene file or unregistered drone (naming the key or file).
            An unreachable RTSP URL is not raised here: it shows as state `reconnecting`
            and then `ended` with `error` set, and iterating raises `SourceError`.
    """
    scheme, sep, rest = uri.partition(":")
    if not sep or not rest:
        raise SourceError(f"unknown source {uri!r}: {URI_HELP}")
    scheme = scheme.lower()
    if scheme == "replay":
        path, fps = parse_replay_uri(rest)
        return ReplaySource.from_path(uri, path, fps, realtime=realtime, on_state=on_state)
    if scheme == "sim":
        from proxima.sim.source import SimSource

        return SimSource(uri, realtime=realtime, on_state=on_state)
    if scheme == "file":
        from proxima.ingest.video import VideoFileSource

        return VideoFileSource(uri, rest, realtime=realtime, on_state=on_state, **options)
    if scheme in ("rtsp", "rtsps"):
        from proxima.ingest.rtsp import RtspSource

        if not rest.startswith("//"):
            raise SourceError(f"bad RTSP URL {uri!r}: expected rtsp://HOST[:PORT]/PATH")
        return RtspSource(uri, on_state=on_state, **options).start()
    if scheme == "webcam":
        from proxima.ingest.webcam import WebcamSource

        try:
            index = int(rest)
        except ValueError:
            raise SourceError(f"bad webcam URI {uri!r}: N must be a camera number") from None
        if index < 0:
            raise SourceError(f"bad webcam URI {uri!r}: N must be >= 0")
        return WebcamSource(uri, index, on_state=on_state, **options).start()
    raise SourceError(f"unknown source scheme {scheme!r} in {uri!r}: {URI_HELP}")
