"""Simulated vehicles as real `proxima sim-drone` processes on 127.0.0.1.

The scenarios and the demo fly the same simulator a user starts by hand: each vehicle is
its own process sending MAVLink 2 to a UDP port that Proxima listens on
(`udpin:127.0.0.1:PORT`). Processes are stopped by their PID (SIGTERM, then SIGKILL if
they do not exit), never by name; on Linux each also gets SIGTERM from the kernel if
the process that started it dies, so no simulator outlives a crashed parent.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from proxima.drone.link import DroneLink, Telemetry

PR_SET_PDEATHSIG = 1  # linux/prctl.h


def free_udp_port() -> int:
    """A UDP port on 127.0.0.1 that nobody uses right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def proxima_command() -> list[str]:
    """How to run the `proxima` command of this very environment."""
    script = Path(sys.executable).with_name("proxima")
    if script.is_file():
        return [str(script)]
    return [sys.executable, "-m", "proxima.cli"]


def _die_with_parent() -> None:  # runs in the child between fork and exec
    with contextlib.suppress(Exception):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


@dataclass
class SimProcess:
    """One `proxima sim-drone` process."""

    name: str
    port: int
    sysid: int
    proc: subprocess.Popen
    log_path: Path | None = None

    @property
    def pid(self) -> int:
        return self.proc.pid

    @property
    def connection(self) -> str:
        """The pymavlink connection string a ground station uses for this vehicle."""
        return f"udpin:127.0.0.1:{self.port}"

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self, timeout: float = 5.0, signal_first: bool = True) -> int:
        """SIGTERM by PID (once), wait, SIGKILL if it is still there; the exit code."""
        if signal_first and self.proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                self.proc.send_signal(signal.SIGTERM)
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


def start_sim(
    name: str,
    port: int,
    sysid: int,
    extra: Sequence[str] = (),
    log_path: Path | None = None,
    new_session: bool = False,
) -> SimProcess:
    """Start `proxima sim-drone --port PORT --sysid SYSID [extra]`; its output goes to
    `log_path` (or is discarded). `new_session` puts it in its own process group, so a
    Ctrl-C in the terminal reaches only the parent, which then stops it by PID.

    Raises:
        OSError: the process could not be started.
    """
    args = [*proxima_command(), "sim-drone", "--port", str(port), "--sysid", str(sysid), *extra]
    out: IO | int = subprocess.DEVNULL
    if log_path is not None:
        log_path.parent.mkdir(parents=True, exist_ok=True)
        out = open(log_path, "ab")  # noqa: SIM115 - handed to the child, closed below
    try:
        proc = subprocess.Popen(
            args,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=new_session,
            preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None,
        )
    finally:
        if not isinstance(out, int):
            out.close()
    return SimProcess(name, port, sysid, proc, log_path)


def stop_all(sims: Sequence[SimProcess], timeout: float = 5.0) -> dict[str, int]:
    """Stop every simulator by PID (SIGTERM to all first, then wait for each)."""
    for sim in sims:
        if sim.alive():
            with contextlib.suppress(ProcessLookupError):
                sim.proc.send_signal(signal.SIGTERM)
    return {sim.name: sim.stop(timeout, signal_first=False) for sim in sims}


def take_off(link: DroneLink, altitude_m: float, timeout: float = 20.0) -> Telemetry:
    """Guided mode, arm, take off and wait until the vehicle hovers at `altitude_m`
    (within 0.1 m, almost still): the pre-flight a pilot does before handing over to
    gesture control.

    Raises:
        RuntimeError: the vehicle refused a step or did not get there in time.
    """
    result = link.takeoff(altitude_m)
    if not result.ok:
        raise RuntimeError(f"{link.name}: takeoff refused: {result.ack} {result.detail}".strip())

    def there(t: Telemetry) -> bool:
        if t.altitude is None or t.velocity is None or t.landed != "in_air":
            return False
        still = math.hypot(*t.velocity) < 0.05
        return abs(t.altitude - altitude_m) < 0.1 and still

    tel = link.wait_for(there, timeout)
    if tel is None:
        raise RuntimeError(f"{link.name}: did not reach {altitude_m} m within {timeout:.0f} s")
    return tel


def pid_alive(pid: int) -> bool:
    """Whether a process with this PID exists and is not a zombie."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state != "Z"


def wait_gone(pids: Sequence[int], timeout: float) -> list[int]:
    """Wait until none of `pids` is alive; the ones still alive after `timeout`."""
    deadline = time.monotonic() + timeout
    while True:
        left = [p for p in pids if pid_alive(p)]
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.05)


def turn_to(link: DroneLink, yaw: float, timeout: float = 10.0) -> Telemetry:
    """Turn a hovering vehicle to heading `yaw` (radians, clockwise from north) where it
    is: a position target at its own position with that yaw; waits until within 1 degree.

    Raises:
        RuntimeError: the vehicle refused the target or did not turn in time.
    """
    tel = link.telemetry()
    if tel is None or tel.position is None:
        raise RuntimeError(f"{link.name}: no position to turn at")
    result = link.goto_local(*tel.position, yaw=yaw)
    if not result.ok:
        raise RuntimeError(f"{link.name}: turn refused: {result.ack} {result.detail}".strip())

    def there(t: Telemetry) -> bool:
        return abs((t.yaw - yaw + math.pi) % (2 * math.pi) - math.pi) < math.radians(1.0)

    out = link.wait_for(there, timeout)
    if out is None:
        raise RuntimeError(f"{link.name}: did not turn to {math.degrees(yaw):.0f} deg in time")
    return out
