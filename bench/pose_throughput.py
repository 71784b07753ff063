"""Pose estimation speed: time per 640x480 frame, and how many 15 fps streams one
machine sustains.

    .venv/bin/python bench/pose_throughput.py [--seconds 8] [--max-streams 6]

Frames: scikit-image's astronaut photo resized to 480x480 and padded to 640x480, shifted
2 px each frame so no two consecutive frames are identical; MediaPipe runs in VIDEO mode
(tracking), as in live use. Measured for `num_poses` 1 and 2: with 2 and one person in
view, MediaPipe runs its person detector on every frame looking for the second one.

Streams: K estimators run at once (threads in one process, as the engine runs them, and
separate processes), each fed a new frame every 1/15 s and, like a live source, skipping
frames it is too slow for. K is sustained when every stream processes >= 95% of 15 fps;
K grows until the first K that is not.

The machine is shared with other work, so the load average before and after is
recorded, with `cpu_ms` (this process's CPU time per frame) and the estimate derived
from it, cores x 1000 / (cpu_ms x 15): what an otherwise idle machine would sustain.
Writes bench/results/pose_throughput.json.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import platform
import statistics
import threading
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import cv2
import numpy as np

FPS = 15.0
SUSTAIN = 0.95  # fraction of FPS every stream must reach
RESULTS = Path(__file__).resolve().parent / "results" / "pose_throughput.json"


def make_frames(n: int = 30) -> list[np.ndarray]:
    """640x480 BGR frames of a real photo of a person, shifted 2 px per frame."""
    from skimage.data import astronaut

    photo = cv2.resize(np.ascontiguousarray(astronaut()[:, :, ::-1]), (480, 480))
    frames = []
    for k in range(n):
        canvas = np.full((480, 640, 3), 40, np.uint8)
        x = 40 + 2 * k
        canvas[:, x : x + 480] = photo
        frames.append(canvas)
    return frames


def time_per_frame(n: int, num_poses: int) -> dict:
    """Median and p95 milliseconds per `estimate` call over `n` frames (after warm-up),
    and the process CPU time per frame."""
    from proxima.pose import PoseEstimator

    frames = make_frames()
    times = []
    with PoseEstimator(num_poses=num_poses) as est:
        for k in range(10):
            est.estimate(frames[k % len(frames)], k / FPS)
        found = 0
        cpu_start = time.process_time()
        for k in range(10, 10 + n):
            start = time.perf_counter()
            poses = est.estimate(frames[k % len(frames)], k / FPS)
            times.append((time.perf_counter() - start) * 1000.0)
            found += bool(poses)
        cpu_ms = 1000.0 * (time.process_time() - cpu_start) / n
    times.sort()
    return {
        "frames": n,
        "median_ms": round(statistics.median(times), 2),
        "p95_ms": round(times[int(0.95 * (len(times) - 1))], 2),
        "min_ms": round(times[0], 2),
        "cpu_ms": round(cpu_ms, 2),
        "idle_machine_estimate_streams": int((os.cpu_count() or 1) * 1000.0 / (cpu_ms * FPS)),
        "frames_with_a_pose": found,
    }


def run_stream(
    seconds: float, num_poses: int, ready: Any, results: list | None = None, slot: int = 0
) -> dict[str, float]:
    """One live-like stream: a new frame each 1/FPS s; frames missed while busy are
    skipped. Returns processed frames per second (and puts it in `results[slot]`)."""
    from proxima.pose import PoseEstimator

    frames = make_frames()
    period = 1.0 / FPS
    with PoseEstimator(num_poses=num_poses) as est:
        for k in range(5):
            est.estimate(frames[k], k * period)
        ready.wait()
        start = time.monotonic()
        done = 0
        busy = 0.0
        while (now := time.monotonic()) < start + seconds:
            tick = int((now - start) / period)
            t0 = time.perf_counter()
            est.estimate(frames[(tick + done) % len(frames)], 1.0 + (now - start))
            busy += time.perf_counter() - t0
            done += 1
            delay = start + (tick + 1) * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)
    out = {"fps": done / seconds, "mean_ms": 1000.0 * busy / max(done, 1)}
    if results is not None:
        results[slot] = out
    return out


def _process_entry(seconds: float, num_poses: int, barrier: Any, queue: Any) -> None:
    queue.put(run_stream(seconds, num_poses, barrier))


def run_k_streams(k: int, seconds: float, num_poses: int, mode: str) -> list[dict]:
    """Run `k` streams at once as threads or processes; returns each stream's result."""
    if mode == "threads":
        barrier = threading.Barrier(k)
        results: list = [None] * k
        threads = [
            threading.Thread(target=run_stream, args=(seconds, num_poses, barrier, results, i))
            for i in range(k)
        ]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        return results
    ctx = mp.get_context("spawn")
    barrier = ctx.Barrier(k)
    queue = ctx.Queue()
    procs = [
        ctx.Process(target=_process_entry, args=(seconds, num_poses, barrier, queue))
        for _ in range(k)
    ]
    for p in procs:
        p.start()
    out = [queue.get(timeout=seconds + 120) for _ in procs]
    for p in procs:
        p.join(timeout=30)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=300, help="frames for the per-frame time")
    parser.add_argument("--seconds", type=float, default=8.0, help="duration of each K run")
    parser.add_argument("--max-streams", type=int, default=6)
    parser.add_argument("--num-poses", default="1,2")
    parser.add_argument("--modes", default="threads,processes")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()

    import mediapipe
    from rich.console import Console
    from rich.progress import Progress

    from proxima.pose import resolve_pose_model

    console = Console()
    load_before = os.getloadavg()
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    pose_counts = [int(n) for n in args.num_poses.split(",")]
    result: dict = {
        "benchmark": "pose_throughput",
        "command": "python bench/pose_throughput.py "
        f"--frames {args.frames} --seconds {args.seconds} --max-streams {args.max_streams} "
        f"--num-poses {args.num_poses} --modes {args.modes}",
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": {
            "cpus": os.cpu_count(),
            "platform": platform.platform(),
            "python": platform.python_version(),
            "loadavg_before_1_5_15min": [round(x, 2) for x in load_before],
        },
        "mediapipe": mediapipe.__version__,
        "model": str(resolve_pose_model()),
        "frame": "640x480 BGR, skimage astronaut resized to 480x480 and padded, VIDEO mode",
        "target": {"fps_per_stream": FPS, "sustained_if_every_stream_reaches": SUSTAIN * FPS},
        "per_frame": {},
        "streams_at_15fps": {},
    }
    total = len(pose_counts) * (1 + len(modes) * args.max_streams)
    with Progress(console=console, transient=True) as bar:
        task = bar.add_task("pose benchmark", total=total)
        for n in pose_counts:
            bar.update(task, description=f"per-frame time, num_poses={n}")
            result["per_frame"][f"num_poses={n}"] = time_per_frame(args.frames, n)
            bar.advance(task)
            for mode in modes:
                per_k: dict = {}
                for k in range(1, args.max_streams + 1):
                    bar.update(task, description=f"{k} stream(s), {mode}, num_poses={n}")
                    runs = run_k_streams(k, args.seconds, n, mode)
                    fps = [r["fps"] for r in runs]
                    per_k[str(k)] = {
                        "fps_per_stream": [round(f, 2) for f in fps],
                        "min_fps": round(min(fps), 2),
                        "mean_ms_per_frame": round(statistics.mean(r["mean_ms"] for r in runs), 2),
                        "sustained": min(fps) >= SUSTAIN * FPS,
                        "loadavg_1min_after": round(os.getloadavg()[0], 2),
                    }
                    bar.advance(task)
                    if not per_k[str(k)]["sustained"]:
                        bar.advance(task, args.max_streams - k)
                        break
                ok = [int(k) for k, v in per_k.items() if v["sustained"]]
                result["streams_at_15fps"][f"{mode}, num_poses={n}"] = {
                    "by_streams": per_k,
                    "max_sustained_streams": max(ok) if ok else 0,
                }
    result["machine"]["loadavg_after_1_5_15min"] = [round(x, 2) for x in os.getloadavg()]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    for name, pf in result["per_frame"].items():
        console.print(
            f"{name}: median {pf['median_ms']} ms, p95 {pf['p95_ms']} ms, cpu {pf['cpu_ms']} ms "
            f"per 640x480 frame (idle-machine estimate {pf['idle_machine_estimate_streams']} "
            "streams)"
        )
    for name, v in result["streams_at_15fps"].items():
        mins = {k: r["min_fps"] for k, r in v["by_streams"].items()}
        console.print(
            f"{name}: max sustained 15 fps streams = {v['max_sustained_streams']} "
            f"(slowest stream's fps by K: {mins})"
        )
    console.print(f"load average before {load_before}, after {os.getloadavg()}")
    console.print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
