"""JPEG thumbnails of camera streams for the Live page, at a modest rate.

Camera frames never travel to the browser as video: at most `hz` times a second a frame
is shrunk to `width` pixels, JPEG-encoded and published as a ThumbnailEvent. Replayed
streams have no pixels and send none (their tiles show the skeleton only).
"""

from __future__ import annotations

import base64
import time

import cv2
import numpy as np

from proxima.api.events import ThumbnailEvent
from proxima.events import EventBus
from proxima.types import Frame


class ThumbnailTap:
    """Call `offer(frame)` for every frame of one stream; it publishes a thumbnail when
    the last one is older than 1/hz seconds (wall clock) and returns whether it did.
    An instance is also a frame tap (`Engine.add_tap(stream, on_frame=tap)`)."""

    def __init__(
        self, bus: EventBus, stream: str, hz: float = 2.0, width: int = 320, quality: int = 70
    ) -> None:
        if hz <= 0:
            raise ValueError(f"thumbnail rate must be > 0, got {hz}")
        self.bus = bus
        self.stream = stream
        self.period = 1.0 / hz
        self.width = width
        self.quality = quality
        self._last = -float("inf")
        self.sent = 0

    def offer(self, frame: Frame) -> bool:
        image = frame.image
        if image is None:
            return False
        now = time.monotonic()
        if now - self._last < self.period:
            return False
        self._last = now
        self.bus.publish(self.encode(image, frame.t))
        self.sent += 1
        return True

    def __call__(self, frame: Frame) -> None:
        """The frame-tap form of `offer` (the frame goes on to recognition unchanged)."""
        self.offer(frame)

    def encode(self, image: np.ndarray, t: float) -> ThumbnailEvent:
        """A ThumbnailEvent of a BGR uint8 image, shrunk to `width` (never enlarged).

        Raises:
            ValueError: not an HxWx3 uint8 image, or encoding failed.
        """
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"expected an HxWx3 uint8 BGR image, got {image.shape} {image.dtype}")
        h, w = image.shape[:2]
        if w > self.width:
            h = max(1, round(h * self.width / w))
            w = self.width
            image = cv2.resize(image, (w, h), interpolation=cv2.INTER_AREA)
        ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.quality])
        if not ok:
            raise ValueError("JPEG encoding failed")
        return ThumbnailEvent(
            t=t,
            stream=self.stream,
            jpeg_b64=base64.b64encode(buf.tobytes()).decode("ascii"),
            width=w,
            height=h,
        )
