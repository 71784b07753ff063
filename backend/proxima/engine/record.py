"""Record a session so it can be replayed: each stream's operator poses as a landmark CSV
(the LASER format `replay:` reads), the engine's events as JSON lines beside them, and a
`session.json` naming the replay URI of each stream.

    recorder = SessionRecorder(engine, "runs/field-1")   # before engine.start()
    engine.run()
    recorder.close()
    # proxima recognize --source replay:runs/field-1/main.csv@30 --events again.jsonl

The poses are the ones the stream's window received (after pose estimation and the
operator tracker, `StreamPipeline.last_pose`), taken by an update tap in the stream
thread. A frame without an operator is left out, which the replay reads as a frame
where nobody was detected. Stream time `t` becomes `counter_frame = round(t * fps) + 1`
(the replay's clock is `(counter_frame - 1) / fps`): exact for replayed streams recorded
at their own rate, within half a frame for a camera (a frame that would take the number
of the one before takes the next number). Replayed poses carry no image size and the
engine then assumes the LASER aspect (16:9); a camera pose of another aspect is stored
with x and z scaled by its aspect / (16/9), so the classifier's metric input (x and z
times the aspect, `geometry.to_metric`) is the same on replay.
"""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from proxima.control import StreamUpdate
from proxima.engine.jsonl import JsonlWriter
from proxima.engine.stream import DATASET_ASPECT
from proxima.ingest.replay import DEFAULT_REPLAY_FPS
from proxima.types import NUM_LANDMARKS, Frame, Pose

if TYPE_CHECKING:
    from proxima.engine.runner import Engine

HEADER = ",counter_frame,i,x,y,z,visibility\n"  # write_landmark_csv's header and columns
EVENTS = "events.jsonl"
SESSION = "session.json"


class PoseRecorder:
    """Appends one stream's operator poses to a landmark CSV as they arrive."""

    def __init__(self, path: str | Path, fps: float = DEFAULT_REPLAY_FPS) -> None:
        if not fps > 0:
            raise ValueError(f"recording fps must be > 0, got {fps}")
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.fps = float(fps)
        self.frames = 0
        self.last_frame = 0
        self.aspects: set[float] = set()
        self._file: IO[str] | None = self.path.open("w", encoding="ascii")
        self._file.write(HEADER)
        self._lock = threading.Lock()

    def add(self, pose: Pose) -> None:
        """Append `pose` (its `t` gives the frame number)."""
        number = max(round(pose.t * self.fps) + 1, self.last_frame + 1)
        xyz = np.asarray(pose.xyz, np.float32)
        if pose.image_size:
            aspect = pose.image_size[0] / pose.image_size[1]
            self.aspects.add(round(aspect, 4))
            if abs(aspect - DATASET_ASPECT) > 1e-9:
                xyz = xyz.copy()
                xyz[:, [0, 2]] *= np.float32(aspect / DATASET_ASPECT)
        vis = np.clip(np.asarray(pose.visibility, np.float32), 0.0, 1.0)
        row0 = self.frames * NUM_LANDMARKS
        lines = "".join(
            f"{row0 + i},{number},{i},{x:.9g},{y:.9g},{z:.9g},{v:.9g}\n"
            for i, ((x, y, z), v) in enumerate(zip(xyz.tolist(), vis.tolist(), strict=True))
        )
        with self._lock:
            if self._file is None:
                return
            self._file.write(lines)
        self.frames += 1
        self.last_frame = number

    def close(self) -> None:
        """Flush and close the CSV (safe to call twice)."""
        with self._lock:
            if self._file is not None:
                self._file.close()
                self._file = None


class SessionRecorder:
    """Records every stream of `engine` into `folder` (see the module). Make it before
    `engine.start()` so that no frame is missed; `close()` after the engine ended.

    `fps` is the recording rate of each stream (a number for all, or per stream name;
    missing names get `DEFAULT_REPLAY_FPS`)."""

    def __init__(
        self,
        engine: Engine,
        folder: str | Path,
        fps: float | dict[str, float] = DEFAULT_REPLAY_FPS,
        info: dict[str, Any] | None = None,
    ) -> None:
        self.engine = engine
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.info = dict(info or {})
        self.recorders: dict[str, PoseRecorder] = {}
        for spec in engine.specs:
            rate = fps.get(spec.name, DEFAULT_REPLAY_FPS) if isinstance(fps, dict) else fps
            recorder = PoseRecorder(self.folder / f"{spec.name}.csv", rate)
            self.recorders[spec.name] = recorder
            engine.add_tap(spec.name, on_update=self._tap(spec.name, recorder))
        self.events = JsonlWriter(self.folder / EVENTS, engine.bus)

    def _tap(self, name: str, recorder: PoseRecorder) -> Any:
        def on_update(frame: Frame, update: StreamUpdate) -> None:
            pose = self.engine.pipelines[name].last_pose
            if pose is not None:
                recorder.add(pose)

        return on_update

    def close(self) -> Path:
        """Finish the files and write `session.json`; returns its path."""
        self.events.close()
        streams = {}
        for spec in self.engine.specs:
            rec = self.recorders[spec.name]
            rec.close()
            streams[spec.name] = {
                "source": spec.uri,
                "replay": f"replay:{rec.path}@{rec.fps:g}",
                "csv": rec.path.name,
                "fps": rec.fps,
                "frames_with_operator": rec.frames,
                "image_aspects": sorted(rec.aspects),
                "drone": spec.drone,
                "priority": spec.priority,
            }
        path = self.folder / SESSION
        session = {**self.info, "events": EVENTS, "events_written": self.events.written,
                   "streams": streams}  # fmt: skip
        path.write_text(json.dumps(session, indent=1, default=str) + "\n")
        return path
