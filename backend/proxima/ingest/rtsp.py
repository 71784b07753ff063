"""`rtsp://...`: a network camera (e.g. the DJI's feed) through OpenCV's FFmpeg backend.

RTSP runs over TCP (`OPENCV_FFMPEG_CAPTURE_OPTIONS=rtsp_transport;tcp`: UDP loses packets
and smears H.264 frames on a busy link), with open and read timeouts so a dead server
never blocks the reader thread for long; the `LiveSource` base reconnects with backoff.
Opening happens in the reader thread, so an unreachable URL shows as state
`reconnecting` with a reason, then `ended` with an error, and never blocks other streams.
"""

from __future__ import annotations

import os
import threading

import cv2

from proxima.ingest.base import SourceError, StateListener
from proxima.ingest.live import LiveSource, ReconnectPolicy

_ENV = "OPENCV_FFMPEG_CAPTURE_OPTIONS"
_env_lock = threading.Lock()


def _ensure_tcp_transport() -> None:
    """Add `rtsp_transport;tcp` to FFmpeg's capture options, keeping any the user set."""
    with _env_lock:
        current = os.environ.get(_ENV, "")
        if "rtsp_transport" not in current:
            os.environ[_ENV] = f"{current}|rtsp_transport;tcp" if current else "rtsp_transport;tcp"


class RtspSource(LiveSource):
    """Frames of an RTSP stream; `t` is seconds since the first frame (wall clock),
    continuing across reconnects so stream time never goes backwards."""

    def __init__(
        self,
        uri: str,
        *,
        open_timeout_s: float = 5.0,
        read_timeout_s: float = 3.0,
        policy: ReconnectPolicy | None = None,
        stall_after_s: float = 1.0,
        max_age_s: float = 1.0,
        on_state: StateListener | None = None,
    ) -> None:
        super().__init__(
            uri,
            policy=policy,
            stall_after_s=stall_after_s,
            max_age_s=max_age_s,
            on_state=on_state,
        )
        self.open_timeout_s = open_timeout_s
        self.read_timeout_s = read_timeout_s

    def _open_capture(self) -> cv2.VideoCapture:
        _ensure_tcp_transport()
        params = [
            cv2.CAP_PROP_OPEN_TIMEOUT_MSEC,
            int(self.open_timeout_s * 1000),
            cv2.CAP_PROP_READ_TIMEOUT_MSEC,
            int(self.read_timeout_s * 1000),
        ]
        cap = cv2.VideoCapture(self.uri, cv2.CAP_FFMPEG, params)
        if not cap.isOpened():
            cap.release()
            raise SourceError(
                f"{self.uri}: cannot open RTSP stream (unreachable, refused, or no video "
                f"within {self.open_timeout_s:g} s)"
            )
        return cap

    def join_timeout_s(self) -> float:
        return self.open_timeout_s + self.read_timeout_s + 1.0
