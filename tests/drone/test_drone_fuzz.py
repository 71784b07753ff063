"""Fuzz: thousands of random and mutated MAVLink datagrams (`mavfuzz`: pymavlink's
encoders of the common dialect with random fields, NaN, infinities and extremes, MAVLink
2 and 1, truncated, bad CRC, wrong length, flipped bytes, garbage) at a running
simulator and at the project's link, after which both fly a scripted mission (takeoff,
move, land) as if nothing had happened.

Seeded: PROXIMA_FUZZ_SEED picks another seed, PROXIMA_FUZZ_COUNT another size; every
failure names its seed, so `PROXIMA_FUZZ_SEED=N pytest tests/drone/test_drone_fuzz.py`
replays it.
"""

from __future__ import annotations

import math
import os
import socket
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest
from mavfuzz import Fuzzer

from proxima.drone.link import DroneLink, Telemetry
from proxima.drone.mavlink.protocol import mav

if TYPE_CHECKING:
    from conftest import Connect, ServeSim

SEED = int(os.environ.get("PROXIMA_FUZZ_SEED", "25"))
COUNT = int(os.environ.get("PROXIMA_FUZZ_COUNT", "5000"))
AUTOPILOTS = ("ardupilot", "px4")

pytestmark = pytest.mark.timeout(120)


def blast(
    fuzzer: Fuzzer,
    addr: tuple[str, int],
    count: int,
    received: Callable[[], int],
    every: int = 10,
    lag: int = 20,
) -> None:
    """Send `count` datagrams in bursts of `every`; after each, wait (up to 10 s) until the
    receiver has taken all but `lag` of them, so a busy machine's receiver never falls so
    far behind that its socket buffer drops some (the kernel counts a loopback datagram
    at a few KB whatever its size; 200 behind still lost 65 of 5,000 on a loaded
    machine): the test is about what the simulator does with them."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for i in range(count):
            tx.sendto(fuzzer.datagram(), addr)
            if i % every == every - 1:
                deadline = time.monotonic() + 10.0
                while i + 1 - received() > lag and time.monotonic() < deadline:
                    time.sleep(0.001)


def fly_mission(link: DroneLink, why: str) -> None:
    """Takeoff to 2 m, 1 m north, land: each step answered and flown."""
    takeoff = link.takeoff(2.0)
    assert takeoff.ok, f"{why}: {takeoff}"
    up = link.wait_for(
        lambda t: t.landed == "in_air" and abs(t.altitude - 2.0) < 0.1 and t.mode != "TAKEOFF",
        10.0,
    )
    assert up is not None, f"{why}: never reached 2 m"
    assert link.enter_guided().ok, why
    target = (up.position[0] + 1.0, up.position[1], -2.0)
    assert link.goto_local(*target).ok, why
    assert link.wait_for(lambda t: t.distance_to(target) < 0.1, 10.0), f"{why}: move"
    assert link.land().ok, why
    assert link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 15.0), f"{why}: land"


@pytest.mark.parametrize("autopilot", AUTOPILOTS)
def test_fuzzed_simulator_keeps_flying(
    serve_sim: ServeSim, connect: Connect, autopilot: str
) -> None:
    sim = serve_sim(autopilot=autopilot)
    server, vehicle = sim.server, sim.server.vehicle
    why = f"seed {SEED}, {COUNT} datagrams, {autopilot}"
    print(f"fuzzing the simulator: {why}")
    params = dict(vehicle.params.values)
    fuzzer = Fuzzer(
        SEED, server.cfg.sysid, param_names=tuple(vehicle.params.order), senders=(255, 250, 7, 1)
    )
    t0 = time.monotonic()
    blast(fuzzer, server.sock.getsockname(), COUNT, lambda: server.packets_in)
    while server.packets_in < COUNT and time.monotonic() - t0 < 30.0:
        time.sleep(0.05)
    seconds = time.monotonic() - t0
    handled = sum(server.handled.values())
    print(
        f"  {seconds:.1f} s; sent {dict(fuzzer.kinds)}; handled {handled} messages of "
        f"{len(server.handled)} kinds; {server.bad_datagrams} broken datagrams"
    )
    assert sim.thread.is_alive(), why
    assert server.handler_errors == 0, why
    assert server.packets_in >= COUNT, why
    assert sum(server.handled.values()) > COUNT // 10, why  # the fuzz reached the handlers
    assert server.bad_datagrams > COUNT // 10, why
    # A safe fuzz asks for nothing the vehicle may do: it is as it was.
    assert not vehicle.armed and vehicle.landed == mav.MAV_LANDED_STATE_ON_GROUND, why
    assert vehicle.params.values == params, why
    fly_mission(connect(sim), why)
    assert server.handler_errors == 0, why


def finite(tel: Telemetry) -> bool:
    fields = (tel.position, tel.velocity, tel.attitude, tel.global_position, tel.home)
    return all(math.isfinite(x) for f in fields if f for x in f)


@pytest.mark.parametrize("autopilot", AUTOPILOTS)
def test_fuzzed_link_keeps_flying(serve_sim: ServeSim, connect: Connect, autopilot: str) -> None:
    """A second endpoint sends fuzz at the link's port, half of it claiming to be the
    vehicle (its system id): the link keeps its vehicle, its telemetry stays numbers."""
    sim = serve_sim(autopilot=autopilot)
    link = connect(sim)
    why = f"seed {SEED + 1}, {COUNT} datagrams, {autopilot}"
    print(f"fuzzing the link: {why}")
    fuzzer = Fuzzer(SEED + 1, sim.server.cfg.sysid, senders=(1, 1, 255, 42), safe=False)
    t0 = time.monotonic()
    samples: list[Telemetry] = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for i in range(COUNT):
            tx.sendto(fuzzer.datagram(), ("127.0.0.1", sim.server.cfg.port))
            if i % 50 == 49:
                time.sleep(0.005)
                samples.append(link.telemetry())
    print(f"  {time.monotonic() - t0:.1f} s; sent {dict(fuzzer.kinds)}; faults {dict(link.faults)}")
    assert link.running, why
    assert link.faults["decode_error"] == 0 and link.faults["reopened"] == 0, why
    assert link.faults["BAD_DATA"] > COUNT // 10, why
    assert all(finite(tel) for tel in samples), why
    time.sleep(2.5)  # the vehicle's own heartbeat and telemetry again
    assert link.telemetry().autopilot == autopilot, why
    fly_mission(link, why)
