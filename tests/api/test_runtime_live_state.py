"""The console's snapshot of stream states (what a browser gets on connecting) holds the
states the engine published while the console was still being built."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from api_helpers import laser_clip

from proxima.api.live import StreamLive
from proxima.api.runtime import build_runtime
from proxima.events import EventBus, StreamEvent
from proxima.settings import Settings
from proxima.types import Event


def test_a_stream_state_sent_before_the_app_existed_is_in_the_snapshot(
    tmp_path: Path, checkpoint_path: Path
) -> None:
    # A stream announces `live` once, as it opens, and the engine starts before the app
    # is built. To make that order certain, a listener holds the `live` event on the
    # stream's thread until build_runtime has returned.
    settings = Settings.load(
        config=None,
        streams=[{"name": "front", "uri": f"replay:{laser_clip('hover_f')}@30", "drone": "main"}],
        engine={"checkpoint": str(checkpoint_path)},
        server={"db_path": str(tmp_path / "c.db")},
    )
    bus = EventBus()
    built = threading.Event()

    def hold_live(event: Event) -> None:
        if isinstance(event, StreamEvent) and event.state == "live":
            built.wait(timeout=10)

    bus.add_listener(hold_live)
    runtime = build_runtime(settings, bus=bus, engine=True, drones=False, view=False)
    built.set()
    try:
        assert runtime.engine is not None, runtime.notes
        live = runtime.app.state.console.live
        end = time.monotonic() + 30

        def front() -> StreamLive:
            return live.streams().get("front", StreamLive())

        while front().pose_t is None and time.monotonic() < end:
            time.sleep(0.05)
        assert front().pose_t is not None, "no pose from the replayed stream"
        assert front().state == "live"
    finally:
        runtime.close()
