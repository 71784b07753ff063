"""`replay:PATH[@FPS]`: a landmark CSV replayed as if it came live from a camera.

Each frame carries a ready `Pose` and no image, so pose estimation is skipped (demos,
tests and benchmarks without video). Stream time is `(counter_frame - 1) / fps`, so gaps
in `counter_frame` (frames where no person was detected) show as gaps in time.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

from proxima.ingest.base import FrameSource, StateListener
from proxima.ingest.landmark_csv import LandmarkTrack, read_landmark_csv
from proxima.ingest.pacing import Pacer
from proxima.types import Frame, Pose, StreamState

DEFAULT_REPLAY_FPS = 30.0


class ReplaySource(FrameSource):
    """Frames with poses from a validated `LandmarkTrack`, at `fps` frames a second of
    stream time; paced to the wall clock when `realtime`, else as fast as possible."""

    def __init__(
        self,
        uri: str,
        track: LandmarkTrack,
        fps: float = DEFAULT_REPLAY_FPS,
        *,
        realtime: bool = True,
        on_state: StateListener | None = None,
    ) -> None:
        super().__init__(uri, on_state)
        if not fps > 0:
            raise ValueError(f"{uri}: replay fps must be > 0, got {fps}")
        self.track = track
        self.fps = float(fps)
        self.realtime = realtime
        self._stop = threading.Event()

    @classmethod
    def from_path(
        cls,
        uri: str,
        path: str | Path,
        fps: float = DEFAULT_REPLAY_FPS,
        *,
        realtime: bool = True,
        on_state: StateListener | None = None,
    ) -> ReplaySource:
        """Read and validate the CSV, then make the source.

        Raises:
            LandmarkCsvError: the CSV is missing or malformed (names file and line).
        """
        return cls(uri, read_landmark_csv(path), fps, realtime=realtime, on_state=on_state)

    def _frames(self) -> Iterator[Frame]:
        pacer = Pacer(self.realtime, self._stop)
        track = self.track
        for k in range(len(track)):
            index = int(track.frames[k]) - 1
            t = index / self.fps
            if not pacer.wait(t):
                break
            if self.state == StreamState.CONNECTING:
                self._advance(StreamState.LIVE)
            elif self.state == StreamState.ENDED:
                break
            pose = Pose(t=t, xyz=track.xyz[k], visibility=track.visibility[k])
            yield Frame(t=t, index=index, image=None, pose=pose)
        self._end()

    def close(self) -> None:
        self._stop.set()
        super().close()
