"""Fixtures for the drone tests: `proxima sim-drone` as a real subprocess on a free UDP
port of 127.0.0.1 and MAVLink links to it (everything started is stopped by PID), and
in-memory links to the same simulated vehicle on a manual clock."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from drone_helpers import FAST, FAST_SIM

from proxima.drone.mavlink import LinkConfig, MavlinkLink
from proxima.drone.memory import ManualClock, MemoryLink
from proxima.drone.sim import SimConfig, VehicleServer
from proxima.events import EventBus

PROXIMA = str(Path(sys.executable).with_name("proxima"))


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Sim:
    port: int
    sysid: int
    proc: subprocess.Popen

    @property
    def connection(self) -> str:
        return f"udpin:127.0.0.1:{self.port}"

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 5.0) -> int:
        """Signal the simulator by PID and wait; its exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


@dataclass
class InProcessSim:
    """A `VehicleServer` (what `proxima sim-drone` runs) on a thread of the test."""

    server: VehicleServer
    thread: threading.Thread
    stop: threading.Event

    @property
    def connection(self) -> str:
        return f"udpin:127.0.0.1:{self.server.cfg.port}"


StartSim = Callable[..., Sim]
ServeSim = Callable[..., InProcessSim]
Connect = Callable[..., MavlinkLink]


@pytest.fixture
def proxima_cli() -> str:
    """The installed `proxima` command of this environment."""
    return PROXIMA


@pytest.fixture
def udp_port() -> int:
    """A free UDP port on 127.0.0.1."""
    return free_udp_port()


@pytest.fixture
def start_sim() -> Iterator[Callable[..., Sim]]:
    sims: list[Sim] = []

    def start(*extra: str, sysid: int = 1, fast: bool = True, port: int | None = None) -> Sim:
        port = port or free_udp_port()
        args = [PROXIMA, "sim-drone", "--port", str(port), "--sysid", str(sysid)]
        args += [*(FAST if fast else ()), *extra]
        proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        sim = Sim(port, sysid, proc)
        sims.append(sim)
        return sim

    yield start
    codes = {}
    for sim in sims:
        killed = sim.proc.poll() is not None  # a test cut it on purpose
        code = sim.stop()
        if not killed:
            codes[sim.port] = code
        for pipe in (sim.proc.stdout, sim.proc.stderr):
            if pipe is not None:
                pipe.close()
    # Every simulator a test left running must stop cleanly on SIGTERM.
    assert all(code == 0 for code in codes.values()), codes


@pytest.fixture
def serve_sim() -> Iterator[Callable[..., InProcessSim]]:
    """Simulated vehicles over real UDP without a process start: the same server as
    `proxima sim-drone`, on a thread, with the FAST_SIM limits by default."""
    sims: list[InProcessSim] = []

    def serve(sysid: int = 1, **sim: Any) -> InProcessSim:
        cfg = SimConfig(port=free_udp_port(), sysid=sysid, **{**FAST_SIM, **sim})
        server, stop = VehicleServer(cfg), threading.Event()
        thread = threading.Thread(target=server.run, args=(stop,), daemon=True)
        thread.start()
        sims.append(InProcessSim(server, thread, stop))
        return sims[-1]

    yield serve
    for sim in sims:
        sim.stop.set()
        sim.thread.join(timeout=5.0)
    assert not any(sim.thread.is_alive() for sim in sims)


@pytest.fixture
def connect() -> Iterator[Callable[..., MavlinkLink]]:
    links: list[MavlinkLink] = []

    def open_link(
        sim: Sim | InProcessSim,
        name: str = "alpha",
        bus: EventBus | None = None,
        config: LinkConfig | None = None,
    ) -> MavlinkLink:
        link = MavlinkLink(sim.connection, name, bus=bus, config=config)
        links.append(link)
        link.connect(timeout=15.0)
        assert link.wait_for(lambda t: t.position is not None and t.landed != "unknown", 5.0)
        return link

    yield open_link
    for link in links:
        link.close()


MemoryLinks = Callable[..., MemoryLink]


@pytest.fixture
def clock() -> ManualClock:
    """Time that passes only when the test says so."""
    return ManualClock()


@pytest.fixture
def memory_link(clock: ManualClock) -> Callable[..., MemoryLink]:
    """Connected in-memory links on the test's clock (with FAST_SIM limits by default)."""

    def make(name: str = "alpha", autopilot: str = "ardupilot", **sim: Any) -> MemoryLink:
        cfg = SimConfig(autopilot=autopilot, **{**FAST_SIM, **sim})
        link = MemoryLink(name, cfg, clock=clock)
        link.connect()
        return link

    return make
