"""A plain pymavlink ground station, written here and sharing no code with Proxima's
link, flies `proxima sim-drone`: the simulator speaks MAVLink as other tools expect."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from pymavlink import mavutil

if TYPE_CHECKING:
    from conftest import StartSim


def test_plain_pymavlink_client_flies_the_simulator(start_sim: StartSim) -> None:
    sim = start_sim(sysid=9)
    gcs = mavutil.mavlink_connection(f"udpin:127.0.0.1:{sim.port}", source_system=250)
    try:
        hb = gcs.wait_heartbeat(timeout=15)
        assert hb is not None and gcs.target_system == 9
        m = mavutil.mavlink  # the dialect module pymavlink chose
        # It answers whoever talks to it: a second station sending to the address the
        # heartbeat came from starts receiving telemetry too.
        (sim_addr,) = gcs.clients
        second = mavutil.mavlink_connection(f"udpout:{sim_addr[0]}:{sim_addr[1]}")
        try:
            second.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            assert second.wait_heartbeat(timeout=3) is not None
        finally:
            second.close()
        assert hb.type == m.MAV_TYPE_QUADROTOR and hb.autopilot == m.MAV_AUTOPILOT_ARDUPILOTMEGA
        assert hb.get_msgbuf()[0] == 0xFD  # a MAVLink 2 packet

        def command(cmd: int, *params: float) -> int:
            p = [*params, *([0.0] * (7 - len(params)))]
            gcs.mav.command_long_send(9, 1, cmd, 0, *p)
            deadline = time.monotonic() + 3.0
            while time.monotonic() < deadline:
                ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=0.5)
                if ack is not None and ack.command == cmd:
                    return ack.result
            raise AssertionError(f"no COMMAND_ACK for {cmd}")

        def wait(kind: str, predicate: Callable[[Any], bool], timeout: float) -> Any:
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline:
                msg = gcs.recv_match(type=kind, blocking=True, timeout=0.5)
                if msg is not None and predicate(msg):
                    return msg
            raise AssertionError(f"no {kind} matching in {timeout} s")

        # SET_MESSAGE_INTERVAL: ATTITUDE at 4 Hz instead of 10.
        assert command(m.MAV_CMD_SET_MESSAGE_INTERVAL, m.MAVLINK_MSG_ID_ATTITUDE, 250_000) == 0
        wait("ATTITUDE", lambda _: True, 2.0)
        count, t0 = 0, time.monotonic()
        while time.monotonic() - t0 < 1.0:
            if gcs.recv_match(type="ATTITUDE", blocking=True, timeout=0.1) is not None:
                count += 1
        assert 3 <= count <= 5, count

        modes = {name: number for number, name in mavutil.mode_mapping_acm.items()}
        assert (
            command(m.MAV_CMD_DO_SET_MODE, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, modes["GUIDED"])
            == m.MAV_RESULT_ACCEPTED
        )
        assert command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == m.MAV_RESULT_ACCEPTED
        assert command(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 1.5) == m.MAV_RESULT_ACCEPTED
        wait("LOCAL_POSITION_NED", lambda p: abs(p.z + 1.5) < 0.05, 6.0)

        # Move 1 m to the left in the body frame (the vehicle faces north: 1 m west).
        gcs.mav.set_position_target_local_ned_send(
            0,
            9,
            1,
            m.MAV_FRAME_BODY_OFFSET_NED,
            0b110111111000,
            0.0,
            -1.0,
            0.0,
            0,
            0,
            0,
            0,
            0,
            0,
            0,
            0,
        )
        pos = wait("LOCAL_POSITION_NED", lambda p: abs(p.y + 1.0) < 0.05 and abs(p.vy) < 0.05, 6.0)
        assert abs(pos.x) < 0.05 and abs(pos.z + 1.5) < 0.1

        assert command(m.MAV_CMD_NAV_LAND) == m.MAV_RESULT_ACCEPTED
        wait("EXTENDED_SYS_STATE", lambda s: s.landed_state == m.MAV_LANDED_STATE_ON_GROUND, 6.0)
        hb = wait("HEARTBEAT", lambda h: not h.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED, 4.0)
        assert mavutil.mode_string_v10(hb) == "LAND"
    finally:
        gcs.close()
