"""rtsp:// against a real GStreamer RTSP server (tests/ingest/rtsp_server.py run by the
system Python) serving an H.264 file made here: live frames, a server killed and
restarted (reconnecting -> live), and an unreachable URL that ends with a clear error
while another stream keeps running."""

from __future__ import annotations

import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from proxima.ingest import SourceError, StateChange, open_source
from proxima.ingest.live import ReconnectPolicy
from proxima.types import StreamState

SYSTEM_PYTHON = "/usr/bin/python3"
SERVER = Path(__file__).with_name("rtsp_server.py")
LASER_CLIP = (
    Path(__file__).resolve().parents[2].parent
    / "shared/datasets/laser-uav-gesture/DJI_0146_have_command_f.MP4.csv"
)


def _gstreamer_ready() -> str | None:
    if shutil.which("gst-launch-1.0") is None:
        return "gst-launch-1.0 missing (apt-get install gstreamer1.0-tools)"
    probe = subprocess.run(
        [
            SYSTEM_PYTHON,
            "-c",
            "import gi; gi.require_version('GstRtspServer', '1.0'); "
            "from gi.repository import GstRtspServer",
        ],
        capture_output=True,
    )
    if probe.returncode != 0:
        return (
            "GStreamer RTSP server missing (apt-get install python3-gi gir1.2-gst-rtsp-server-1.0)"
        )
    return None


_missing = _gstreamer_ready() if Path(SYSTEM_PYTHON).exists() else "no /usr/bin/python3"
pytestmark = pytest.mark.skipif(_missing is not None, reason=_missing or "")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait(cond: Callable[[], bool], timeout: float, what: str) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


@pytest.fixture(scope="module")
def h264_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """30 s of 320x240 H.264 at 15 fps in MP4, encoded by GStreamer's x264enc."""
    path = tmp_path_factory.mktemp("rtsp") / "ball.mp4"
    subprocess.run(
        [
            "gst-launch-1.0", "-q", "videotestsrc", "num-buffers=450", "pattern=ball", "!",
            "video/x-raw,width=320,height=240,framerate=15/1", "!",
            "x264enc", "tune=zerolatency", "speed-preset=ultrafast", "key-int-max=15", "!",
            "h264parse", "!", "mp4mux", "!", "filesink", f"location={path}",
        ],
        check=True,
        timeout=60,
    )  # fmt: skip
    assert path.stat().st_size > 10_000
    return path


class RtspServer:
    """The server subprocess; `start()` waits for its READY line, `kill()` SIGKILLs it."""

    def __init__(self, port: int, video: Path) -> None:
        self.port = port
        self.video = video
        self.proc: subprocess.Popen[str] | None = None

    def start(self) -> None:
        self.proc = subprocess.Popen(
            [SYSTEM_PYTHON, str(SERVER), "--port", str(self.port), "--file", str(self.video)],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        assert line.startswith("READY"), f"RTSP server did not start: {line!r}"

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
            self.proc.wait(timeout=5)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.kill()


@pytest.fixture
def server(h264_file: Path) -> Iterator[RtspServer]:
    srv = RtspServer(_free_port(), h264_file)
    srv.start()
    yield srv
    srv.stop()


class Consumer:
    """Iterates a source in a thread, like the engine does, recording what it gets."""

    def __init__(self, src) -> None:
        self.src = src
        self.frames: list[tuple[float, int, tuple[int, ...]]] = []
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            for f in self.src:
                self.frames.append((f.t, f.index, f.image.shape))
        except BaseException as exc:
            self.error = exc


@pytest.mark.slow
def test_rtsp_live_then_server_killed_and_restarted_reconnects(server: RtspServer) -> None:
    changes: list[StateChange] = []
    src = open_source(
        f"rtsp://127.0.0.1:{server.port}/test",
        on_state=changes.append,
        open_timeout_s=3,
        read_timeout_s=2,
        policy=ReconnectPolicy(backoff_s=0.2, backoff_max_s=1.0, give_up_after_s=30),
    )
    consumer = Consumer(src)
    try:
        _wait(lambda: len(consumer.frames) >= 20, 15, "20 live frames")
        assert src.state is StreamState.LIVE
        assert consumer.frames[-1][2] == (240, 320, 3)
        ts = [f[0] for f in consumer.frames]
        assert ts == sorted(ts) and ts[0] >= 0.0

        server.kill()
        _wait(lambda: src.state is StreamState.RECONNECTING, 10, "state reconnecting")
        n_before = len(consumer.frames)
        t_before = consumer.frames[-1][0]
        time.sleep(1.0)  # a few refused reconnects with backoff
        assert src.state is StreamState.RECONNECTING

        server.start()  # same port
        _wait(lambda: src.state is StreamState.LIVE, 15, "live again after restart")
        _wait(lambda: len(consumer.frames) >= n_before + 10, 10, "frames after reconnect")
        assert consumer.frames[n_before][0] > t_before  # stream time goes on, never back
        assert consumer.frames[n_before][1] > consumer.frames[n_before - 1][1]
        assert src.reconnects >= 1
    finally:
        src.close()
        consumer.thread.join(timeout=10)
    assert not consumer.thread.is_alive() and consumer.error is None
    assert src.state is StreamState.ENDED
    states = [c.state for c in changes]
    assert states[0] is StreamState.LIVE and states[-1] is StreamState.ENDED
    k = states.index(StreamState.RECONNECTING)
    assert StreamState.LIVE in states[k:]
    for c in changes:  # every reported change is an allowed one
        assert c.uri == src.uri and c.previous != c.state


@pytest.mark.slow
def test_slow_consumer_gets_newest_frames_and_a_paused_server_shows_stalled(
    server: RtspServer,
) -> None:
    changes: list[StateChange] = []
    src = open_source(
        f"rtsp://127.0.0.1:{server.port}/test",
        on_state=changes.append,
        open_timeout_s=3,
        read_timeout_s=8,  # longer than the pause below: stalled, not reconnecting
        stall_after_s=0.8,
    )
    try:
        got = []
        lag = []
        start = time.monotonic()
        for frame in src:
            got.append(frame.index)
            lag.append((time.monotonic() - start) - frame.t)
            time.sleep(0.25)  # a consumer slower than the 15 fps stream
            if len(got) == 12:
                break
        steps = np.diff(got)
        assert (steps >= 1).all() and steps[3:].mean() > 2  # older frames were skipped
        assert src.frames_dropped > 0
        # Newest-only: the delay between a frame's capture and its use does not grow.
        assert max(lag[3:]) - min(lag[3:]) < 0.5

        assert server.proc is not None
        server.proc.send_signal(signal.SIGSTOP)  # server alive but silent
        try:  # nobody consumes now: the state must show the silence anyway
            _wait(lambda: src.state is StreamState.STALLED, 6, "state stalled")
        finally:
            server.proc.send_signal(signal.SIGCONT)
        _wait(lambda: src.state is StreamState.LIVE, 6, "live after the pause")
    finally:
        src.close()
    states = [c.state for c in changes]
    assert StreamState.STALLED in states
    assert StreamState.LIVE in states[states.index(StreamState.STALLED) :]
    assert StreamState.RECONNECTING not in states


def test_unreachable_rtsp_ends_with_clear_error_and_other_streams_go_on() -> None:
    port = _free_port()  # nothing listens here
    url = f"rtsp://127.0.0.1:{port}/nothing"
    changes: list[StateChange] = []
    src = open_source(
        url,
        on_state=changes.append,
        open_timeout_s=2,
        policy=ReconnectPolicy(backoff_s=0.1, backoff_max_s=0.2, connect_attempts=3),
    )
    replay = open_source(f"replay:{LASER_CLIP}@120")  # another stream, paced, ~6 s
    replayed: list[int] = []
    other = threading.Thread(target=lambda: replayed.extend(f.index for f in replay))
    other.start()
    try:
        with pytest.raises(SourceError) as info:
            for _ in src:
                pass
    finally:
        src.close()
    assert url in str(info.value) and "cannot open RTSP stream" in str(info.value)
    assert "gave up after 3 attempts" in str(info.value)
    assert src.state is StreamState.ENDED and src.error == str(info.value)
    assert [c.state for c in changes] == [StreamState.RECONNECTING, StreamState.ENDED]
    assert changes[0].detail.startswith(url)
    assert other.is_alive() and replay.state is StreamState.LIVE  # unaffected
    replay.close()
    other.join(timeout=5)
    assert len(replayed) > 0


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
