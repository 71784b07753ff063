"""Console benchmark: skeleton update rate per stream in a real browser, event -> browser
latency, and memory over a run.

A console server runs in a child process (uvicorn, WebSocket hub, SQLite) with N streams
whose poses are replayed in real time (30 fps) from N different LASER clips through the
project's replay source (`--engine` runs the full live engine with the gesture model
instead). Debian's Chromium, driven by Playwright, logs in and shows the Live page; the
page counts the pose messages of each stream and the delay from publication on the bus
(`ts`, wall clock, same machine) to arrival in the page. The child's resident memory and
the page's JS heap are sampled through the run.

    python -m bench.console_latency                  # 4 streams, 120 s
    python -m bench.console_latency --duration 600   # the 10-minute memory run

Writes bench/results/console_latency.json and console_latency.png (memory and latency).
Targets: >= 15 Hz per stream with 4 streams, median latency < 100 ms, memory flat.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shlex
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "bench" / "results"
CLIPS = (
    "move_to_left_f",
    "move_to_right_r",
    "have_command_l",
    "wave_off_f",
    "land_f",
    "hover_r",
    "move_upward_l",
    "slow_down_f",
)
ADMIN = ("bench", "bench-passphrase-1")
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-background-networking",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-component-update",
    "--disable-sync",
]
TARGET_HZ = 15.0
TARGET_MEDIAN_MS = 100.0
# "Flat": after warm-up, resident memory grows by less than this over the run.
FLAT_GROWTH_MB = 20.0


def _streams(n: int) -> list[dict[str, Any]]:
    from proxima.gesture.data_source import resolve_laser_dir

    root = Path(resolve_laser_dir(None))
    out = []
    for i in range(n):
        clip = sorted(root.glob(f"DJI_*_{CLIPS[i % len(CLIPS)]}.MP4.csv"))[0]
        out.append({"name": f"s{i}", "uri": f"replay:{clip}@30", "drone": f"d{i}", "priority": i})
    return out


# -- child: the console server ---------------------------------------------------------
def run_child(args: argparse.Namespace) -> None:
    """The server under test: console app + pose feed (or the live engine)."""
    from proxima.api.feed import ReplayPoseFeed
    from proxima.api.runtime import build_runtime
    from proxima.settings import Settings

    streams = _streams(args.streams)
    settings = Settings.load(
        config=None,
        admin_user=ADMIN[0],
        admin_password=ADMIN[1],
        streams=streams,
        server={"db_path": args.db, "port": args.port, "viser_enabled": False},
    )
    runtime = build_runtime(settings, engine=args.engine, drones=False, view=False)
    feed = None
    if not args.engine:
        feed = ReplayPoseFeed(runtime.bus, {s["name"]: s["uri"] for s in streams}).start()
    import uvicorn

    config = uvicorn.Config(runtime.app, host="127.0.0.1", port=args.port, log_level="warning")
    server = uvicorn.Server(config)
    print("READY", flush=True)
    try:
        server.run()
    except KeyboardInterrupt:  # the parent's SIGINT: uvicorn has shut down already
        pass
    finally:
        if feed is not None:
            feed.stop()
        runtime.close()


# -- parent: browser and measurements ---------------------------------------------------
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError(f"no VmRSS for pid {pid}")


def _wait_health(url: str, proc: subprocess.Popen, timeout: float = 120.0) -> None:
    import httpx

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"console child exited with {proc.returncode}")
        try:
            if httpx.get(f"{url}/api/health", timeout=1).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    raise RuntimeError("console child did not answer /api/health")


STATS_JS = """() => {
  const s = window.__proximaStats;
  const out = {poses: s.poses, first: s.firstPose, last: s.lastPose, now: performance.now(),
               heap: performance.memory ? performance.memory.usedJSHeapSize : null,
               latencies: s.latencies.slice()};
  s.latencies.length = 0;
  return out;
}"""


def measure(args: argparse.Namespace) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright
    from rich.progress import Progress

    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    tmp = tempfile.mkdtemp(prefix="proxima-bench-")
    child_cmd = [
        sys.executable,
        "-m",
        "bench.console_latency",
        "--child",
        "--port",
        str(port),
        "--db",
        str(Path(tmp) / "bench.db"),
        "--streams",
        str(args.streams),
    ]
    if args.engine:
        child_cmd.append("--engine")
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    env.pop("PROXIMA_CONFIG", None)
    child = subprocess.Popen(child_cmd, cwd=REPO, env=env)
    samples: list[dict[str, float]] = []
    latencies: list[float] = []
    try:
        _wait_health(url, child)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(
                executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS
            )
            page = browser.new_page(viewport={"width": 1600, "height": 1000})
            page.goto(url + "/")
            page.fill("#login-form input[name=username]", ADMIN[0])
            page.fill("#login-form input[name=password]", ADMIN[1])
            page.click("#login-form button[type=submit]")
            page.wait_for_selector("#conn.ok", timeout=30000)
            page.wait_for_selector(f"article.tile[data-stream=s{args.streams - 1}]")
            time.sleep(args.warmup)
            page.evaluate("() => window.__proximaStats.reset()")
            t0 = time.monotonic()
            with Progress(transient=True) as progress:
                task = progress.add_task("console benchmark", total=args.duration)
                while (elapsed := time.monotonic() - t0) < args.duration:
                    time.sleep(min(args.sample_every, args.duration - elapsed))
                    stats = page.evaluate(STATS_JS)
                    latencies += stats["latencies"]
                    samples.append(
                        {
                            "t_s": round(time.monotonic() - t0, 2),
                            "server_rss_mb": round(_rss_mb(child.pid), 1),
                            "page_heap_mb": round((stats["heap"] or 0) / 2**20, 1),
                        }
                    )
                    progress.update(task, completed=min(args.duration, time.monotonic() - t0))
            final = page.evaluate(STATS_JS)
            latencies += final["latencies"]
            browser.close()
    finally:
        child.send_signal(signal.SIGINT)
        try:
            child.wait(20)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()

    per_stream = {}
    for name, count in sorted(final["poses"].items()):
        span_s = (final["last"][name] - final["first"][name]) / 1000
        per_stream[name] = round((count - 1) / span_s, 2) if span_s > 0 else 0.0
    lat_ms = np.asarray(latencies) * 1000
    rss = np.array([s["server_rss_mb"] for s in samples])
    ts = np.array([s["t_s"] for s in samples])
    half = len(rss) // 2
    growth = float(rss[half:].max() - rss[: max(half, 1)].min()) if len(rss) > 1 else 0.0
    slope = float(np.polyfit(ts / 60, rss, 1)[0]) if len(rss) > 2 else 0.0
    heap = np.array([s["page_heap_mb"] for s in samples])
    result = {
        "streams": args.streams,
        "source": "live engine (replay + gesture model)"
        if args.engine
        else "replayed LASER poses (ReplayPoseFeed), 30 fps per stream",
        "duration_s": args.duration,
        "per_stream_hz": per_stream,
        "min_stream_hz": min(per_stream.values()) if per_stream else 0.0,
        "pose_messages": int(sum(final["poses"].values())),
        "latency_ms": {
            "n": int(lat_ms.size),
            "median": round(float(np.median(lat_ms)), 2),
            "p95": round(float(np.percentile(lat_ms, 95)), 2),
            "p99": round(float(np.percentile(lat_ms, 99)), 2),
            "max": round(float(lat_ms.max()), 2),
        },
        "server_rss_mb": {
            "first": float(rss[0]),
            "last": float(rss[-1]),
            "max": float(rss.max()),
            "growth_second_half_vs_first_mb": round(growth, 1),
            "slope_mb_per_min": round(slope, 3),
        },
        "page_heap_mb": {
            "first": float(heap[0]),
            "last": float(heap[-1]),
            "max": float(heap.max()),
        },
        "samples": samples,
        "targets": {
            "min_stream_hz": TARGET_HZ,
            "median_latency_ms": TARGET_MEDIAN_MS,
            "memory_growth_mb_below": FLAT_GROWTH_MB,
        },
    }
    result["passed"] = {
        "rate": result["min_stream_hz"] >= TARGET_HZ and len(per_stream) == args.streams,
        "latency": result["latency_ms"]["median"] < TARGET_MEDIAN_MS,
        "memory_flat": growth < FLAT_GROWTH_MB,
    }
    result["machine"] = {
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
    }
    result["command"] = "python -m bench.console_latency " + shlex.join(sys.argv[1:])
    return result


def plot(result: dict[str, Any], path: Path) -> None:
    """Memory over the run, with the rate and latency figures in the title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = result["samples"]
    fig, ax = plt.subplots(1, 1, figsize=(7, 3.5))
    ax.plot([x["t_s"] for x in s], [x["server_rss_mb"] for x in s], label="server RSS")
    ax.plot([x["t_s"] for x in s], [x["page_heap_mb"] for x in s], label="page JS heap")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("MB")
    lat = result["latency_ms"]
    ax.set_title(
        f"{result['streams']} streams: min {result['min_stream_hz']:.1f} Hz/stream, "
        f"latency median {lat['median']:.1f} ms, p95 {lat['p95']:.1f} ms",
        fontsize=9,
    )
    ax.set_ylim(bottom=0)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--streams", type=int, default=4)
    parser.add_argument("--duration", type=float, default=120.0, help="seconds measured")
    parser.add_argument("--warmup", type=float, default=5.0)
    parser.add_argument("--sample-every", type=float, default=5.0)
    parser.add_argument(
        "--engine", action="store_true", help="run the live engine (needs the gesture checkpoint)"
    )
    parser.add_argument("--out", type=Path, default=RESULTS / "console_latency.json")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--port", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument("--db", default="", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        run_child(args)
        return
    result = measure(args)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    plot(result, args.out.with_suffix(".png"))
    lat = result["latency_ms"]
    print(
        f"{result['streams']} streams for {result['duration_s']:.0f} s: "
        f"per-stream rate {result['per_stream_hz']} Hz; latency median {lat['median']} ms, "
        f"p95 {lat['p95']} ms; server RSS {result['server_rss_mb']['first']} -> "
        f"{result['server_rss_mb']['last']} MB; passed {result['passed']}"
    )
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
