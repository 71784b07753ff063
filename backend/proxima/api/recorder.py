"""Records labelled samples from a live stream: a countdown, then N consecutive poses of
that stream from the bus, stored as a pending sample for the stream's drone.

Each recording runs on its own thread reading a bus subscription, and reports progress
as RecordingEvents on the bus (the Labelling page shows them through the hub).
"""

from __future__ import annotations

import threading
import time
import uuid
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from sqlalchemy.orm import sessionmaker

from proxima.api.events import RecordingEvent
from proxima.events import EventBus, PoseEvent
from proxima.store.samples import add_sample

MAX_FRAMES = 900  # 30 s at 30 fps
MAX_COUNTDOWN_S = 30.0


@dataclass
class Recording:
    id: str
    stream: str
    drone: str
    frames_total: int
    countdown_s: float
    user: str
    label: str | None = None
    state: str = "countdown"  # countdown -> recording -> done | failed
    frames_done: int = 0
    sample_id: int | None = None
    detail: str = ""
    started: float = field(default_factory=time.time)

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "stream": self.stream,
            "drone": self.drone,
            "frames_total": self.frames_total,
            "frames_done": self.frames_done,
            "countdown_s": self.countdown_s,
            "state": self.state,
            "sample_id": self.sample_id,
            "label": self.label,
            "detail": self.detail,
        }


class SampleRecorder:
    """Starts recordings and remembers the recent ones."""

    def __init__(self, bus: EventBus, sessions: sessionmaker, pose_timeout_s: float = 5.0) -> None:
        self.bus = bus
        self.sessions = sessions
        self.pose_timeout_s = pose_timeout_s
        self._lock = threading.Lock()
        self._recordings: dict[str, Recording] = {}
        self._threads: list[threading.Thread] = []

    def start(
        self,
        *,
        stream: str,
        drone: str,
        frames: int,
        countdown_s: float,
        user: str,
        label: str | None = None,
    ) -> Recording:
        """Begin a recording in the background and return it at once.

        Raises:
            ValueError: a frame count or countdown out of range, or a recording already
                running on that stream.
        """
        if not 1 <= frames <= MAX_FRAMES:
            raise ValueError(f"frames must be 1..{MAX_FRAMES}, got {frames}")
        if not 0 <= countdown_s <= MAX_COUNTDOWN_S:
            raise ValueError(f"countdown_s must be 0..{MAX_COUNTDOWN_S}, got {countdown_s}")
        with self._lock:
            for rec in self._recordings.values():
                if rec.stream == stream and rec.state in ("countdown", "recording"):
                    raise ValueError(f"a recording is already running on stream {stream!r}")
            rec = Recording(
                id=uuid.uuid4().hex[:12],
                stream=stream,
                drone=drone,
                frames_total=frames,
                countdown_s=countdown_s,
                user=user,
                label=label,
            )
            self._recordings[rec.id] = rec
            # Forget old finished recordings.
            while len(self._recordings) > 100:
                self._recordings.pop(next(iter(self._recordings)))
        thread = threading.Thread(target=self._run, args=(rec,), daemon=True, name=f"rec-{rec.id}")
        self._threads = [t for t in self._threads if t.is_alive()] + [thread]
        thread.start()
        return rec

    def get(self, recording_id: str) -> Recording | None:
        with self._lock:
            return self._recordings.get(recording_id)

    def _emit(self, rec: Recording, t: float, remaining: float = 0.0) -> None:
        self.bus.publish(
            RecordingEvent(
                t=t,
                stream=rec.stream,
                recording=rec.id,
                state=rec.state,
                frames_done=rec.frames_done,
                frames_total=rec.frames_total,
                countdown_s=round(remaining, 2),
                sample_id=rec.sample_id,
                detail=rec.detail,
            )
        )

    def _run(self, rec: Recording) -> None:
        try:
            self._record(rec)
        except Exception as exc:  # report, never kill the server
            rec.state = "failed"
            rec.detail = f"{type(exc).__name__}: {exc}"
            self._emit(rec, 0.0)

    def _record(self, rec: Recording) -> None:
        end = time.monotonic() + rec.countdown_s
        while (remaining := end - time.monotonic()) > 0:
            self._emit(rec, 0.0, remaining)
            time.sleep(min(remaining, 0.5))
        rec.state = "recording"
        self._emit(rec, 0.0)
        xyz: list[np.ndarray] = []
        vis: list[np.ndarray] = []
        times: list[float] = []
        with self.bus.subscribe(maxsize=MAX_FRAMES * 2, types=["pose"]) as sub:
            last_pose = time.monotonic()
            while len(times) < rec.frames_total:
                event = sub.get(timeout=0.25)
                if not isinstance(event, PoseEvent) or event.stream != rec.stream:
                    if time.monotonic() - last_pose > self.pose_timeout_s:
                        rec.state = "failed"
                        rec.detail = (
                            f"no pose from stream {rec.stream!r} for {self.pose_timeout_s:g} s"
                            f" ({len(times)} of {rec.frames_total} frames recorded)"
                        )
                        self._emit(rec, times[-1] if times else 0.0)
                        return
                    continue
                last_pose = time.monotonic()
                xyz.append(np.asarray(event.xyz, dtype=np.float32))
                vis.append(np.asarray(event.visibility, dtype=np.float32))
                times.append(float(event.t))
                rec.frames_done = len(times)
                if rec.frames_done % 5 == 0 and rec.frames_done < rec.frames_total:
                    self._emit(rec, event.t)
        with self.sessions() as db:
            sample = add_sample(
                db,
                stream=rec.stream,
                drone=rec.drone,
                xyz=np.stack(xyz),
                visibility=np.stack(vis),
                times=np.asarray(times),
                created_by=rec.user,
                label=rec.label,
            )
            rec.sample_id = sample.id
        rec.state = "done"
        self._emit(rec, times[-1])

    def join(self, timeout: float = 5.0) -> None:
        """Wait for running recordings (used at shutdown and in tests)."""
        for t in list(self._threads):
            t.join(timeout)
