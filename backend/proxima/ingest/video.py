"""`file:PATH`: frames of a video file, decoded by OpenCV's FFmpeg backend.

A file is not live: it runs in the caller's thread at its own rate (`realtime`) or as
fast as it decodes, and nothing is dropped. Stream time is frame index / fps, or the
container's timestamps (CAP_PROP_POS_MSEC) when the file reports no frame rate.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from proxima.ingest.base import FrameSource, SourceError, StateListener
from proxima.ingest.pacing import Pacer
from proxima.types import Frame, StreamState


class VideoFileSource(FrameSource):
    """Every frame of a video file as BGR images.

    Raises:
        SourceError: (from the constructor) the file is missing, is not a video OpenCV
            can open, or has no decodable frame.
    """

    def __init__(
        self,
        uri: str,
        path: str | Path,
        *,
        realtime: bool = True,
        on_state: StateListener | None = None,
    ) -> None:
        super().__init__(uri, on_state)
        self.path = Path(path).expanduser()
        self.realtime = realtime
        self._stop = threading.Event()
        if not self.path.is_file():
            raise SourceError(f"{uri}: no such file: {self.path}")
        cap = cv2.VideoCapture(str(self.path), cv2.CAP_FFMPEG)
        if not cap.isOpened():
            cap.release()
            raise SourceError(f"{uri}: {self.path} is not a video that OpenCV/FFmpeg can open")
        ok, first = cap.read()
        if not ok or first is None:
            cap.release()
            raise SourceError(f"{uri}: {self.path} has no decodable video frame")
        fps = cap.get(cv2.CAP_PROP_FPS)
        self.fps: float | None = fps if math.isfinite(fps) and fps > 0 else None
        self._cap: cv2.VideoCapture | None = cap
        self._first: np.ndarray | None = first
        self._lock = threading.Lock()

    def _time(self, cap: cv2.VideoCapture, index: int) -> float:
        if self.fps is not None:
            return index / self.fps
        return max(cap.get(cv2.CAP_PROP_POS_MSEC), 0.0) / 1000.0

    def _frames(self) -> Iterator[Frame]:
        pacer = Pacer(self.realtime, self._stop)
        index = 0
        while True:
            with self._lock:
                cap = self._cap
                if cap is None:
                    break
                if self._first is not None:
                    ok, image = True, self._first
                    self._first = None
                else:
                    ok, image = cap.read()
                t = self._time(cap, index) if ok else 0.0
            if not ok or image is None:
                break
            if not pacer.wait(t):
                break
            if self.state == StreamState.CONNECTING:
                self._advance(StreamState.LIVE)
            yield Frame(t=t, index=index, image=image)
            index += 1
        self._release()
        self._end()

    def _release(self) -> None:
        with self._lock:
            if self._cap is not None:
                self._cap.release()
                self._cap = None

    def close(self) -> None:
        self._stop.set()
        self._release()
        super().close()
