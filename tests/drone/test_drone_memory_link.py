"""The in-memory link's own rules: its clock, its life cycle, a cut link, and the PX4
OFFBOARD stream it replays (what the simulated vehicle does without one)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from proxima.drone.link import LinkError
from proxima.drone.mavlink.protocol import PX4_MODES, mav
from proxima.drone.memory import ManualClock, MemoryLink
from proxima.types import LinkState

if TYPE_CHECKING:
    from conftest import MemoryLinks


def test_manual_clock_moves_only_forward() -> None:
    clock = ManualClock(start=5.0)
    assert clock() == clock.now() == 5.0
    assert clock.advance(1.5) == 6.5
    clock.sleep(0.5)
    assert clock.now() == 7.0
    with pytest.raises(ValueError, match="cannot advance"):
        clock.advance(-1.0)


def test_life_cycle(clock: ManualClock) -> None:
    link = MemoryLink("alpha", clock=clock)
    assert link.state == LinkState.CONNECTING and link.telemetry() is None
    assert link.arm().ack == "not_connected" and link.sent_count() == 0
    link.connect()
    tel = link.telemetry()
    assert link.state == LinkState.OK and tel.mode == "STABILIZE" and tel.landed == "on_ground"
    assert tel.battery_pct == 100.0 and tel.battery_voltage == 16.8
    link.close()
    closed = link.arm()
    assert closed.ack == "not_connected" and closed.detail == "closed"
    with pytest.raises(LinkError, match="closed"):
        link.connect()


def test_px4_offboard_needs_the_stream(memory_link: MemoryLinks, clock: ManualClock) -> None:
    link = memory_link(autopilot="px4")
    assert link.takeoff(2.0).ok
    clock.advance(3.0)
    # Straight into OFFBOARD without setpoints: PX4 refuses.
    refused = link.command_long("mode OFFBOARD", mav.MAV_CMD_DO_SET_MODE, PX4_MODES["OFFBOARD"])
    assert refused.ack == "denied" and link.telemetry().status_text.startswith("Offboard")
    # enter_guided starts the stream first; the stream keeps OFFBOARD.
    assert link.enter_guided().ok
    clock.advance(5.0)
    assert link.telemetry().mode == "OFFBOARD"
    # Cut: nothing goes out any more, telemetry stays as last heard, and the vehicle,
    # without setpoints, falls back to Hold after offboard_loss_s.
    streamed = link.sent_count()
    link.cut()
    clock.advance(1.0)
    assert link.sent_count() == streamed
    assert link.telemetry().mode == "OFFBOARD"  # frozen: the link hears nothing
    assert link.vehicle.mode == "LOITER"
    link.restore()
    assert link.telemetry().mode == "LOITER"
    assert link.goto_local(0.0, 0.0, -2.0).ack == "wrong_mode"
