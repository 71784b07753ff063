"""MAVSDK-Python (PyPI `mavsdk` 3.x, whose wheel embeds mavsdk_server) flies
`proxima sim-drone` in both autopilot modes with its standard flow: connect, health,
version, home, takeoff altitude (PX4: the MIS_TAKEOFF_ALT parameter), arm, takeoff,
offboard move (one setpoint, then `offboard.start()`, as MAVSDK's example does), goto
(DO_REPOSITION), land, disarm; plus the parameter plugin and a raw mission upload and
download. Each step's result is printed (`pytest -s`) and must be a success."""

from __future__ import annotations

import asyncio
import socket
import time
import warnings
from collections.abc import AsyncIterator, Awaitable, Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

import pytest

with warnings.catch_warnings():  # 3.17's notice that the name moves to `mavsdk-grpc`
    warnings.simplefilter("ignore", FutureWarning)
    mavsdk = pytest.importorskip("mavsdk", reason="MAVSDK-Python is in the dev extra")
from mavsdk import System
from mavsdk.mission_raw import MissionItem
from mavsdk.offboard import PositionNedYaw

if TYPE_CHECKING:
    from conftest import StartSim

pytestmark = pytest.mark.timeout(180)


def free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def first(stream: AsyncIterator[Any], predicate: Callable[[Any], bool] = bool) -> Any:
    async for value in stream:
        if predicate(value):
            return value
    raise AssertionError("stream ended")


class Steps:
    """Runs the flow's steps with a timeout each and keeps what each answered."""

    def __init__(self, label: str) -> None:
        self.label = label
        self.results: list[tuple[str, str, float]] = []

    async def __call__(self, name: str, step: Awaitable[Any], timeout: float = 20.0) -> Any:
        t0 = time.monotonic()
        try:
            value = await asyncio.wait_for(step, timeout)
        except Exception as exc:  # the step's failure is the test's result, reported below
            self.results.append(
                (name, f"FAILED {type(exc).__name__}: {exc}", time.monotonic() - t0)
            )
            raise AssertionError(self.report()) from exc
        self.results.append((name, "ok", time.monotonic() - t0))
        return value

    def report(self) -> str:
        lines = [f"MAVSDK {mavsdk_version()} against sim-drone ({self.label}):"]
        lines += [
            f"  {name:<24} {result} ({seconds:.2f} s)" for name, result, seconds in self.results
        ]
        return "\n".join(lines)


def mavsdk_version() -> str:
    from importlib.metadata import version

    return version("mavsdk")


async def flow(port: int, px4: bool, step: Steps) -> None:
    drone = System(port=free_tcp_port())  # its own gRPC port: tests may run side by side
    try:
        await drone.connect(system_address=f"udpin://127.0.0.1:{port}")
        await step("connect", first(drone.core.connection_state(), lambda s: s.is_connected))
        await step(
            "health",
            first(
                drone.telemetry.health(),
                lambda h: h.is_global_position_ok and h.is_home_position_ok and h.is_armable,
            ),
        )
        version = await step("info.get_version", drone.info.get_version())
        assert (version.flight_sw_major, version.flight_sw_minor) == ((1, 15) if px4 else (4, 5))
        home = await step("telemetry.home", first(drone.telemetry.home(), lambda _: True))
        assert abs(home.absolute_altitude_m - 300.0) < 0.01
        await step("telemetry.home again", first(drone.telemetry.home(), lambda _: True), 6.0)

        name = "MIS_TAKEOFF_ALT" if px4 else "PILOT_TKOFF_ALT"
        await step("param.get_param_float", drone.param.get_param_float(name))
        await step("set_takeoff_altitude", drone.action.set_takeoff_altitude(3.0))
        assert await step("get_takeoff_altitude", drone.action.get_takeoff_altitude()) == 3.0
        if px4:  # MAVSDK keeps ArduPilot's takeoff altitude itself; PX4's is a parameter
            assert await drone.param.get_param_float("MIS_TAKEOFF_ALT") == 3.0

        items = [
            MissionItem(i, 6, 16, int(i == 0), 1, 0.0, 0.0, 0.0, float("nan"),
                        int(home.latitude_deg * 1e7) + 100 * i, int(home.longitude_deg * 1e7),
                        5.0, 0)
            for i in range(3)
        ]  # fmt: skip
        await step("mission_raw.upload", drone.mission_raw.upload_mission(items))
        back = await step("mission_raw.download", drone.mission_raw.download_mission())
        assert [i.x for i in back][-2:] == [i.x for i in items][-2:]
        await step("mission_raw.clear", drone.mission_raw.clear_mission())

        await step("arm", drone.action.arm())
        await step("takeoff", drone.action.takeoff())
        await step(
            "reached 3 m",
            first(drone.telemetry.position(), lambda p: abs(p.relative_altitude_m - 3.0) < 0.2),
        )
        await step(
            "offboard.set_position", drone.offboard.set_position_ned(PositionNedYaw(0, 0, -3, 0))
        )
        await step("offboard.start", drone.offboard.start())
        await step(
            "offboard.set_position 2", drone.offboard.set_position_ned(PositionNedYaw(2, 0, -3, 0))
        )
        ned = drone.telemetry.position_velocity_ned()
        await step("moved 2 m north", first(ned, lambda p: abs(p.position.north_m - 2.0) < 0.1))
        await step("offboard.stop", drone.offboard.stop())

        north = home.latitude_deg + 5.0 / 111_320.0  # 5 m north of home
        goto = drone.action.goto_location(
            north, home.longitude_deg, home.absolute_altitude_m + 4, 0
        )
        await step("goto_location", goto)
        ned = drone.telemetry.position_velocity_ned()
        await step(
            "reached the goto",
            first(
                ned,
                lambda p: abs(p.position.north_m - 5) < 0.2 and abs(p.position.down_m + 4) < 0.2,
            ),
        )
        await step("land", drone.action.land())
        await step("landed", first(drone.telemetry.in_air(), lambda a: not a), 40.0)
        await step("disarmed", first(drone.telemetry.armed(), lambda a: not a), 10.0)
    finally:
        drone._stop_mavsdk_server()  # the embedded mavsdk_server process, by its handle


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_mavsdk_standard_flow(start_sim: StartSim, autopilot: str) -> None:
    flags = ("--autopilot", "px4") if autopilot == "px4" else ()  # ArduPilot: the default
    sim = start_sim(*flags, sysid=1)
    step = Steps(" ".join(flags) or "default: ArduPilot")
    # On its own thread: Playwright's sync API (the browser tests, when they ran earlier
    # on this pytest-xdist worker) leaves an event loop running on the main thread.
    with ThreadPoolExecutor(1) as pool:
        pool.submit(asyncio.run, flow(sim.port, autopilot == "px4", step)).result()
    print(step.report())
    assert sim.proc.poll() is None
