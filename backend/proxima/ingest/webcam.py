"""`webcam:N`: a local camera (V4L2 device N) read by its own thread, newest frame only.

The device is probed when the source is made, so a missing camera is a clear error at
once; later failures (unplugged) show as `reconnecting` like any live source.
"""

from __future__ import annotations

import threading

import cv2

from proxima.ingest.base import SourceError, StateListener
from proxima.ingest.live import LiveSource, ReconnectPolicy

_in_use: set[int] = set()  # camera numbers held by an open source (one reader each)
_in_use_lock = threading.Lock()


class WebcamSource(LiveSource):
    """Frames of camera `index`; `t` is seconds since the first frame (wall clock).

    Raises:
        SourceError: (from the constructor) the camera cannot be opened, or another
            open source already reads it (one reader thread per device).
    """

    def __init__(
        self,
        uri: str,
        index: int,
        *,
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
        self.index = index
        with _in_use_lock:
            if index in _in_use:
                raise SourceError(f"{uri}: camera {index} is already open in another source")
            _in_use.add(index)
        self._holds_device = True
        try:
            self._probed: cv2.VideoCapture | None = self._open_capture()
        except BaseException:
            self._release_device()
            raise

    def _release_device(self) -> None:
        with _in_use_lock:
            if getattr(self, "_holds_device", False):
                _in_use.discard(self.index)
                self._holds_device = False

    def _open_capture(self) -> cv2.VideoCapture:
        probed, self._probed = getattr(self, "_probed", None), None
        if probed is not None:
            return probed
        cap = cv2.VideoCapture(self.index)
        if not cap.isOpened():
            cap.release()
            raise SourceError(f"{self.uri}: cannot open camera {self.index} (no such device?)")
        return cap

    def close(self) -> None:
        probed, self._probed = self._probed, None
        if probed is not None:
            probed.release()
        super().close()
        self._release_device()
