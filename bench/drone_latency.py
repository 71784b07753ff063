"""Drone link speed against `proxima sim-drone` over real UDP on 127.0.0.1.

    .venv/bin/python -m bench.drone_latency [--commands 200] [--steps 10]

Measures
- command -> COMMAND_ACK latency of the MAVLink link (DO_CHANGE_SPEED, DO_SET_MODE),
  median and p95 over many commands;
- gesture -> vehicle answer through the whole controller (mapping, safety, link, SQLite
  command log): `slow_down` / `all_clear` alternating;
- position convergence time of a 1 m step (move_to_left / move_to_right through the
  controller) with the simulator's ArduCopter-like default limits (5 m/s, 2.5 m/s^2),
  LOCAL_POSITION_NED asked at 50 Hz: from the command to within 0.10 m and 0.05 m of
  the target, plus a step-response PNG;
- link-loss detection: simulator killed by PID -> link state LOST.

Writes bench/results/drone_latency.json and bench/results/drone_step.png. The simulator
flies at real time, so convergence times are the vehicle model's, not the machine's; the
latencies include this shared machine's scheduling noise (load average recorded).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from rich.progress import Progress

from proxima.drone.controller import DroneController
from proxima.drone.link import Telemetry
from proxima.drone.mavlink import MavlinkLink
from proxima.drone.mavlink.protocol import mav
from proxima.drone.safety import SafetyConfig
from proxima.events import CommandEvent
from proxima.store.command_log import CommandLog
from proxima.types import LinkState

RESULTS = Path(__file__).parent / "results"
PROXIMA = str(Path(sys.executable).with_name("proxima"))


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_sim(sysid: int = 1) -> tuple[subprocess.Popen, int]:
    port = free_port()
    proc = subprocess.Popen(
        [PROXIMA, "sim-drone", "--port", str(port), "--sysid", str(sysid)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return proc, port


def stats_ms(samples: Sequence[float]) -> dict:
    a = np.asarray(samples) * 1000.0
    return {
        "n": len(a),
        "median_ms": round(float(np.median(a)), 3),
        "p95_ms": round(float(np.percentile(a, 95)), 3),
        "max_ms": round(float(a.max()), 3),
    }


def stats_s(samples: Sequence[float]) -> dict:
    a = np.asarray(samples)
    return {
        "n": len(a),
        "median_s": round(float(np.median(a)), 3),
        "p95_s": round(float(np.percentile(a, 95)), 3),
        "max_s": round(float(a.max()), 3),
    }


def ack_latencies(link: MavlinkLink, n: int, progress: Progress) -> dict:
    """Per command: `vehicle_round_trip` is first send -> COMMAND_ACK inside the link
    thread; `caller` is what a caller of the blocking method waits (queue hand-off,
    round trip, future)."""
    task = progress.add_task("command -> ack", total=2 * n)
    out = {}
    for name in ("do_change_speed", "do_set_mode"):
        trip, caller = [], []
        for i in range(n):
            t0 = time.perf_counter()
            if name == "do_change_speed":
                r = link.change_speed(2.0 + (i % 5) * 0.5)
            else:
                r = link.set_mode("GUIDED" if i % 2 else "LOITER")
            caller.append(time.perf_counter() - t0)
            assert r.ok and r.latency_s is not None, r
            trip.append(r.latency_s)
            progress.advance(task)
        out[name] = {"vehicle_round_trip": stats_ms(trip), "caller": stats_ms(caller)}
    return out


def gesture_latencies(ctl: DroneController, n: int, progress: Progress) -> dict:
    task = progress.add_task("gesture -> answer", total=n)
    times = []
    for i in range(n):
        event = CommandEvent(t=float(i), stream="bench", command="slow_down", drone="bench")
        if i % 2:
            event = CommandEvent(t=float(i), stream="bench", command="all_clear", drone="bench")
        t0 = time.perf_counter()
        out = ctl.handle(event)
        times.append(time.perf_counter() - t0)
        assert out.status == "sent", out
        progress.advance(task)
    return stats_ms(times)


def now_at(link: MavlinkLink) -> tuple[Telemetry, tuple[float, float, float]]:
    """The newest telemetry and its position (the bench needs both)."""
    tel = link.telemetry()
    assert tel is not None and tel.position is not None, "no telemetry from the simulator"
    return tel, tel.position


def step_responses(
    link: MavlinkLink, ctl: DroneController, steps: int, progress: Progress
) -> tuple[dict, list]:
    task = progress.add_task("1 m steps", total=steps)
    to_10cm, to_5cm, overshoot, traces = [], [], [], []
    for i in range(steps):
        link.wait_for(lambda t: math.hypot(*(t.velocity or (0, 0, 0))) < 0.01, 10.0)
        _, start = now_at(link)
        gesture = "move_to_left" if i % 2 == 0 else "move_to_right"
        t0 = time.monotonic()
        out = ctl.handle(CommandEvent(t=float(i), stream="bench", command=gesture, drone="bench"))
        assert out.status == "sent" and out.target is not None, out
        target = out.target
        trace, t10, t5, worst = [], None, None, 0.0
        while time.monotonic() - t0 < 8.0:
            tel, pos = now_at(link)
            now = time.monotonic() - t0
            d = tel.distance_to(target)
            trace.append((now, abs(pos[1] - start[1])))
            past = (pos[1] - target[1]) * (1 if target[1] > start[1] else -1)
            worst = max(worst, past)
            if t10 is None and d < 0.10:
                t10 = now
            if t5 is None and d < 0.05:
                t5 = now
            if t5 is not None and now > t5 + 0.5:
                break
            time.sleep(0.01)
        assert t10 is not None and t5 is not None, f"step {i} did not converge"
        to_10cm.append(t10)
        to_5cm.append(t5)
        overshoot.append(worst)
        traces.append(trace)
        progress.advance(task)
    return (
        {
            "within_0.10_m": stats_s(to_10cm),
            "within_0.05_m": stats_s(to_5cm),
            "overshoot_max_m": round(float(max(overshoot)), 4),
        },
        traces,
    )


def link_loss(samples: int, progress: Progress) -> dict:
    task = progress.add_task("link loss", total=samples)
    times = []
    for _ in range(samples):
        proc, port = start_sim(sysid=2)
        link = MavlinkLink(f"udpin:127.0.0.1:{port}", "loss")
        try:
            link.connect(20.0)
            time.sleep(0.3 + np.random.default_rng().uniform(0, 1.0))  # random heartbeat phase
            proc.send_signal(signal.SIGKILL)
            t0 = time.monotonic()
            while link.state != LinkState.LOST and time.monotonic() - t0 < 10:
                time.sleep(0.005)
            times.append(time.monotonic() - t0)
        finally:
            link.close()
            proc.kill()
            proc.wait()
        progress.advance(task)
    return stats_s(times)


def plot(traces: list, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    for trace in traces:
        t, y = zip(*trace, strict=True)
        ax.plot(t, y, color="tab:blue", alpha=0.5, lw=1)
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.axhspan(0.95, 1.05, color="tab:green", alpha=0.15, label="within 0.05 m")
    ax.set_xlabel("time since the gesture command (s)")
    ax.set_ylabel("lateral displacement (m)")
    ax.set_title("1 m move_to_left / move_to_right, proxima sim-drone defaults")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--commands", type=int, default=200, help="commands per latency series")
    ap.add_argument("--steps", type=int, default=10, help="1 m steps for convergence")
    ap.add_argument("--loss-samples", type=int, default=3, help="link-loss detections")
    ap.add_argument("--out", type=Path, default=RESULTS / "drone_latency.json")
    args = ap.parse_args(argv)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    results: dict = {
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "load_average_at_start": round(os.getloadavg()[0], 2),
        "transport": "MAVLink 2 over UDP on 127.0.0.1, proxima sim-drone subprocess",
        "sim_limits": {"max_speed_m_s": 5.0, "max_accel_m_s2": 2.5, "telemetry_hz": 10},
        "step_position_rate_hz": 50,
    }
    proc, port = start_sim()
    link = MavlinkLink(f"udpin:127.0.0.1:{port}", "bench")
    with tempfile.TemporaryDirectory() as tmp, Progress() as progress:
        log = CommandLog(Path(tmp) / "bench.db")
        ctl = DroneController(
            {"bench": link}, log=log, safety=SafetyConfig(min_interval_s=0.0, max_step_m=2.0)
        )
        try:
            link.connect(20.0)
            results["command_ack"] = ack_latencies(link, args.commands, progress)
            assert link.takeoff(3.0).ok
            link.wait_for(lambda t: t.landed == "in_air" and abs((t.altitude or 0) - 3) < 0.05, 15)
            ctl.safety.arm_control("bench")
            results["gesture_to_answer"] = gesture_latencies(ctl, args.commands, progress)
            assert link.change_speed(5.0).ok
            # Position at 50 Hz so the convergence time is not quantised to 0.1 s.
            assert link.set_message_interval(mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 50.0).ok
            results["step_1m"], traces = step_responses(link, ctl, args.steps, progress)
            assert ctl.handle(CommandEvent(t=0, stream="b", command="land", drone="bench")).sent
            results["link_loss_detection"] = link_loss(args.loss_samples, progress)
        finally:
            ctl.close()
            link.close()
            proc.send_signal(signal.SIGTERM)
            proc.wait(10)
    png = args.out.with_name("drone_step.png")
    plot(traces, png)
    results["step_plot"] = str(
        png.relative_to(Path.cwd()) if png.is_relative_to(Path.cwd()) else png
    )
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    print(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
