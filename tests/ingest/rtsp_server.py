"""A real RTSP server for the ingest tests: GStreamer's RTSP server (Debian's
gir1.2-gst-rtsp-server-1.0) serving one H.264 MP4 file, bound to 127.0.0.1.

Run by the system Python (`/usr/bin/python3`, which has python3-gi), not the venv:
    /usr/bin/python3 tests/ingest/rtsp_server.py --port 8554 --file clip.mp4 --mount /test
Prints `READY rtsp://127.0.0.1:PORT/MOUNT` once it listens; stops on SIGTERM/SIGKILL.
Each client gets its own pipeline, so every connection plays the file from the start.
"""

from __future__ import annotations

import argparse
import signal
import sys

import gi

gi.require_version("Gst", "1.0")
gi.require_version("GstRtspServer", "1.0")
from gi.repository import GLib, Gst, GstRtspServer  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--file", required=True, help="H.264 video in an MP4 container")
    parser.add_argument("--mount", default="/test")
    args = parser.parse_args()

    Gst.init(None)
    server = GstRtspServer.RTSPServer()
    server.set_address("127.0.0.1")
    server.set_service(str(args.port))
    factory = GstRtspServer.RTSPMediaFactory()
    location = args.file.replace('"', '\\"')
    factory.set_launch(
        f'( filesrc location="{location}" ! qtdemux ! h264parse '
        "! rtph264pay name=pay0 pt=96 config-interval=1 )"
    )
    factory.set_shared(False)
    server.get_mount_points().add_factory(args.mount, factory)
    if server.attach(None) == 0:
        print(f"cannot listen on 127.0.0.1:{args.port}", file=sys.stderr, flush=True)
        return 1
    loop = GLib.MainLoop()
    signal.signal(signal.SIGTERM, lambda *_: loop.quit())
    print(f"READY rtsp://127.0.0.1:{args.port}{args.mount}", flush=True)
    loop.run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
