"""The simulator speaks the MAVLink microservices standard tools use, over real UDP, to
a plain pymavlink station: AUTOPILOT_VERSION, HOME_POSITION, the parameter protocol,
the mission protocol (mission, fence, rally), MAVLink FTP refused, and the bugs third-
party clients found (a NaN param killed the process, one truncated datagram made it
deaf, OFFBOARD needed more than one setpoint, no DO_REPOSITION or DO_LAND_START)."""

from __future__ import annotations

import math
import socket
import struct
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest
from gcs import Gcs

from proxima.drone.mavlink.protocol import PX4_MODES, mav, mavutil

if TYPE_CHECKING:
    from conftest import InProcessSim, ServeSim, StartSim

AUTOPILOTS = ("ardupilot", "px4")
NAN = math.nan


@pytest.fixture
def station(
    serve_sim: ServeSim, request: pytest.FixtureRequest
) -> Iterator[tuple[Gcs, InProcessSim]]:
    sim = serve_sim(autopilot=getattr(request, "param", "ardupilot"))
    gcs = Gcs(sim.server.cfg.port)
    yield gcs, sim
    gcs.close()
    assert sim.server.handler_errors == 0


@pytest.mark.parametrize("station", AUTOPILOTS, indirect=True)
def test_autopilot_version(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, sim = station
    m = gcs.m
    px4 = sim.server.cfg.autopilot == "px4"
    assert gcs.command(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_AUTOPILOT_VERSION) == 0
    v = gcs.wait("AUTOPILOT_VERSION")
    assert bytes(v.flight_custom_version) == b"proxsim\0"
    major, minor = v.flight_sw_version >> 24, (v.flight_sw_version >> 16) & 0xFF
    assert (major, minor) == ((1, 15) if px4 else (4, 5))
    encoding = (
        m.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
        if px4
        else m.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
    )
    assert v.capabilities & encoding and v.capabilities & m.MAV_PROTOCOL_CAPABILITY_MISSION_INT
    assert not v.capabilities & m.MAV_PROTOCOL_CAPABILITY_FTP
    # The older command, and its MAV_BOOL checked.
    assert gcs.command(m.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1) == 0
    assert gcs.wait("AUTOPILOT_VERSION").uid == v.uid
    assert gcs.command(m.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0.5) == m.MAV_RESULT_DENIED
    assert gcs.command(m.MAV_CMD_REQUEST_MESSAGE, NAN) == m.MAV_RESULT_DENIED
    assert gcs.command(m.MAV_CMD_REQUEST_MESSAGE, 2.5e7) == m.MAV_RESULT_DENIED


def test_home_position_streamed_and_on_request(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, sim = station
    homes = gcs.collect("HOME_POSITION", 4.5)
    assert len(homes) >= 2  # streamed (0.5 Hz), so a client that waits for the next one gets it
    lat, _, alt = sim.server.cfg.home
    assert homes[0].latitude == round(lat * 1e7) and homes[0].altitude == round(alt * 1000)
    assert gcs.command(gcs.m.MAV_CMD_GET_HOME_POSITION) == 0


def test_sys_status_says_armable_and_fence(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, _ = station
    m = gcs.m
    s = gcs.wait("SYS_STATUS")
    fence, prearm, gps = (
        m.MAV_SYS_STATUS_GEOFENCE,
        m.MAV_SYS_STATUS_PREARM_CHECK,
        m.MAV_SYS_STATUS_SENSOR_GPS,
    )
    assert s.onboard_control_sensors_present & fence and s.onboard_control_sensors_health & fence
    assert not s.onboard_control_sensors_enabled & fence  # FENCE_ENABLE 0
    assert s.onboard_control_sensors_health & prearm and s.onboard_control_sensors_health & gps


def param_values(gcs: Gcs, count: int) -> dict[str, object]:
    got: dict[int, object] = {}
    deadline = time.monotonic() + 5.0
    while len(got) < count and time.monotonic() < deadline:
        msg = gcs.conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.2)
        if msg is not None:
            got[msg.param_index] = msg
    return {v.param_id: v for v in got.values()}


@pytest.mark.parametrize("station", AUTOPILOTS, indirect=True)
def test_parameter_protocol(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, sim = station
    m, vehicle = gcs.m, sim.server.vehicle
    px4 = sim.server.cfg.autopilot == "px4"
    gcs.conn.mav.param_request_list_send(1, 1)
    params = param_values(gcs, len(vehicle.params))
    assert set(params) == set(vehicle.params.order)
    assert {p.param_count for p in params.values()} == {len(vehicle.params)}
    cruise, fence_action = (
        ("MPC_XY_CRUISE", "GF_ACTION") if px4 else ("WPNAV_SPEED", "FENCE_ACTION")
    )
    assert params[cruise].param_value == (5.0 if px4 else 500.0)

    # Read by name and by index (the index wins); an unknown one: PARAM_ERROR.
    gcs.conn.mav.param_request_read_send(1, 1, cruise.encode(), -1)
    assert gcs.wait(
        "PARAM_VALUE", lambda p: p.param_id == cruise
    ).param_index == vehicle.params.index(cruise)
    gcs.conn.mav.param_request_read_send(1, 1, b"IGNORED", 0)
    assert gcs.wait("PARAM_VALUE").param_index == 0
    gcs.conn.mav.param_request_read_send(1, 1, b"NO_SUCH_PARAM", -1)
    assert gcs.wait("PARAM_ERROR").error == m.MAV_PARAM_ERROR_DOES_NOT_EXIST

    # A set is confirmed by the new value and obeyed: the cruise speed changes.
    gcs.conn.mav.param_set_send(
        1, 1, cruise.encode(), 2.0 if px4 else 200.0, m.MAV_PARAM_TYPE_REAL32
    )
    gcs.wait("PARAM_VALUE", lambda p: p.param_id == cruise and p.param_value in (2.0, 200.0))
    assert vehicle.limits.cruise == 2.0
    # An integer: PX4 carries its bytes in the float, ArduPilot the number itself.
    kind = m.MAV_PARAM_TYPE_INT32 if px4 else m.MAV_PARAM_TYPE_INT8
    wire = struct.unpack("<f", struct.pack("<i", 3))[0] if px4 else 3.0
    gcs.conn.mav.param_set_send(1, 1, fence_action.encode(), wire, kind)
    echo = gcs.wait("PARAM_VALUE", lambda p: p.param_id == fence_action)
    assert (
        echo.param_type == kind and echo.param_value == wire and vehicle.params[fence_action] == 3
    )

    # NaN, infinity, out of range: refused with PARAM_ERROR and a STATUSTEXT, unchanged.
    for bad in (NAN, math.inf, 1e9):
        gcs.conn.mav.param_set_send(1, 1, cruise.encode(), bad, m.MAV_PARAM_TYPE_REAL32)
        error = gcs.wait("PARAM_ERROR", lambda e: e.param_id == cruise)
        assert error.error == m.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE
    assert vehicle.limits.cruise == 2.0
    gcs.conn.mav.param_set_send(1, 1, cruise.encode(), NAN, m.MAV_PARAM_TYPE_REAL32)
    assert gcs.wait("STATUSTEXT", lambda t: t.text.startswith("Param refused")) is not None


def upload(
    gcs: Gcs, items: list[tuple[int, int, tuple[float, ...], int, int, float]], kind: int
) -> int:
    """MISSION_COUNT, then each MISSION_ITEM_INT the vehicle asks for; the MISSION_ACK."""
    gcs.conn.mav.mission_count_send(1, 1, len(items), kind)
    while True:
        msg = gcs.wait(["MISSION_REQUEST_INT", "MISSION_ACK"])
        if msg.get_type() == "MISSION_ACK":
            assert msg.mission_type == kind
            return msg.type
        frame, command, p, x, y, z = items[msg.seq]
        gcs.conn.mav.mission_item_int_send(1, 1, msg.seq, frame, command, 0, 1, *p, x, y, z, kind)


def download(gcs: Gcs, kind: int) -> list[object]:
    gcs.conn.mav.mission_request_list_send(1, 1, kind)
    count = gcs.wait("MISSION_COUNT", lambda c: c.mission_type == kind).count
    out = []
    for seq in range(count):
        gcs.conn.mav.mission_request_int_send(1, 1, seq, kind)
        out.append(gcs.wait("MISSION_ITEM_INT", lambda i, s=seq: i.seq == s))
    return out


REL = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
LAT, LON = 500_755_000, 144_378_000


@pytest.mark.parametrize("station", AUTOPILOTS, indirect=True)
def test_mission_protocol(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, sim = station
    m = gcs.m
    ardupilot = sim.server.cfg.autopilot == "ardupilot"
    mission = m.MAV_MISSION_TYPE_MISSION
    items = [
        (REL, m.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, NAN), LAT, LON, 5.0),
        (REL, m.MAV_CMD_NAV_WAYPOINT, (0, 0, 0, NAN), LAT + 1000, LON, 5.0),
        (REL, m.MAV_CMD_NAV_LAND, (0, 0, 0, NAN), LAT + 1000, LON, 0.0),
    ]
    assert upload(gcs, items, mission) == m.MAV_MISSION_ACCEPTED
    got = download(gcs, mission)
    assert [i.command for i in got[1:]] == [it[1] for it in items[1:]]
    assert got[2].x == LAT + 1000 and math.isnan(got[2].param4)
    # ArduPilot's item 0 is home; PX4 gives back what was sent.
    assert got[0].command == (m.MAV_CMD_NAV_WAYPOINT if ardupilot else m.MAV_CMD_NAV_TAKEOFF)
    # The legacy float request gets the float item.
    gcs.conn.mav.mission_request_send(1, 1, 1, mission)
    assert abs(gcs.wait("MISSION_ITEM").x - 50.0756) < 1e-6
    gcs.conn.mav.mission_request_int_send(1, 1, 99, mission)
    assert gcs.wait("MISSION_ACK").type == m.MAV_MISSION_INVALID_SEQUENCE

    # Geofence and rally points are their own lists.
    circle = [(REL, m.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, (50, 0, 0, 0), LAT, LON, 0.0)]
    assert upload(gcs, circle, m.MAV_MISSION_TYPE_FENCE) == m.MAV_MISSION_ACCEPTED
    assert [i.param1 for i in download(gcs, m.MAV_MISSION_TYPE_FENCE)] == [50.0]
    assert download(gcs, m.MAV_MISSION_TYPE_RALLY) == []
    assert upload(gcs, items[:1], m.MAV_MISSION_TYPE_RALLY) == m.MAV_MISSION_UNSUPPORTED

    # Bad items, bad types, too many: the right MAV_MISSION_RESULT, nothing stored.
    bad = [items[0], (REL, m.MAV_CMD_NAV_WAYPOINT, (0, 0, 0, 0), LAT, LON, NAN)]
    assert upload(gcs, bad, mission) == m.MAV_MISSION_INVALID_PARAM7
    assert len(download(gcs, mission)) == 3
    gcs.conn.mav.mission_request_list_send(1, 1, 7)
    assert gcs.wait("MISSION_ACK").type == m.MAV_MISSION_UNSUPPORTED
    gcs.conn.mav.mission_count_send(1, 1, 10_000, mission)
    assert gcs.wait("MISSION_ACK").type == m.MAV_MISSION_NO_SPACE

    # Clear all of every type.
    gcs.conn.mav.mission_clear_all_send(1, 1, m.MAV_MISSION_TYPE_ALL)
    assert gcs.wait("MISSION_ACK").type == m.MAV_MISSION_ACCEPTED
    assert len(download(gcs, mission)) == (1 if ardupilot else 0)
    assert download(gcs, m.MAV_MISSION_TYPE_FENCE) == []


def test_mavlink_ftp_is_refused_at_once(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, _ = station

    def ftp(opcode: int, data: bytes = b"") -> tuple[int, int, bytes]:
        header = struct.pack("<HBBBBBBI", 5, 1, opcode, len(data), 0, 0, 0, 0)
        gcs.conn.mav.file_transfer_protocol_send(0, 1, 1, list((header + data).ljust(251, b"\0")))
        raw = bytes(gcs.wait("FILE_TRANSFER_PROTOCOL").payload)
        seq, _, op, size, req, *_ = struct.unpack_from("<HBBBBBBI", raw)
        assert seq == 6 and req == opcode
        return op, size, raw[12 : 12 + size]

    assert ftp(4, b"@PARAM/param.pck") == (129, 1, bytes([10]))  # NAK FileNotFound
    assert ftp(99) == (129, 1, bytes([7]))  # NAK UnknownCommand
    assert ftp(1)[0] == 128  # TerminateSession: ACK


def test_commands_for_other_components_are_not_ours(station: tuple[Gcs, InProcessSim]) -> None:
    gcs, _ = station
    gcs.conn.mav.command_long_send(
        1, 100, gcs.m.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0
    )
    with pytest.raises(AssertionError, match="no COMMAND_ACK"):
        gcs.wait("COMMAND_ACK", timeout=0.5)


def test_nan_params_do_not_kill_the_simulator(start_sim: StartSim) -> None:
    """Found by MAVSDK against `--autopilot px4`: ARM_DISARM with NaN param2 (MAVSDK's
    "unset") killed the process on int(NaN)."""
    sim = start_sim("--autopilot", "px4")
    gcs = Gcs(sim.port)
    try:
        m = gcs.m
        assert gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1, *[NAN] * 6) == m.MAV_RESULT_ACCEPTED
        assert gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, NAN, *[NAN] * 6) == m.MAV_RESULT_DENIED
        assert gcs.command(m.MAV_CMD_NAV_TAKEOFF, *[NAN] * 7) == m.MAV_RESULT_ACCEPTED
        up = gcs.wait("GLOBAL_POSITION_INT", lambda p: abs(p.relative_alt - 2500) < 100, 6.0)
        assert up is not None and sim.proc.poll() is None  # MIS_TAKEOFF_ALT: 2.5 m
    finally:
        gcs.close()


def test_a_truncated_datagram_does_not_swallow_the_next(station: tuple[Gcs, InProcessSim]) -> None:
    """Found by the fuzz test: bytes left by a truncated datagram were glued to the next
    one, and the old parser, without robust parsing, then refused everything after."""
    gcs, sim = station
    m = gcs.m
    enc = mav.MAVLink(None, srcSystem=250, srcComponent=190)
    guided = mav.MAVLink_command_long_message(1, 1, m.MAV_CMD_DO_SET_MODE, 0, 1, 4, 0, 0, 0, 0, 0)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        addr = sim.server.sock.getsockname()
        tx.sendto(guided.pack(enc)[:9], addr)
        tx.sendto(guided.pack(enc), addr)
        time.sleep(0.3)
    assert sim.server.vehicle.mode == "GUIDED" and sim.server.bad_datagrams == 1


@pytest.mark.parametrize("station", ["px4"], indirect=True)
def test_px4_offboard_after_one_setpoint(station: tuple[Gcs, InProcessSim]) -> None:
    """MAVSDK's example: one setpoint, then offboard.start(). PX4 accepts OFFBOARD once a
    setpoint arrived within COM_OF_LOSS_T; the simulator refused it."""
    gcs, sim = station
    m = gcs.m
    base, main, sub = PX4_MODES["OFFBOARD"]
    assert gcs.command(m.MAV_CMD_DO_SET_MODE, base, main, sub) == m.MAV_RESULT_DENIED
    gcs.conn.mav.set_position_target_local_ned_send(
        0, 1, 1, m.MAV_FRAME_LOCAL_NED, 0b110111111000, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0
    )
    assert gcs.command(m.MAV_CMD_DO_SET_MODE, base, main, sub) == m.MAV_RESULT_ACCEPTED
    assert sim.server.vehicle.mode == "OFFBOARD"


@pytest.mark.parametrize("station", AUTOPILOTS, indirect=True)
def test_reposition_and_landing_sequence(station: tuple[Gcs, InProcessSim]) -> None:
    """MAVProxy's `guided LAT LON ALT` (DO_REPOSITION in COMMAND_INT, altitude above home)
    and `land` (DO_LAND_START: fly the mission's landing sequence)."""
    gcs, sim = station
    m, vehicle = gcs.m, sim.server.vehicle
    gcs.conn.mav.param_set_send(
        1, 1, b"MIS_TAKEOFF_ALT" if vehicle.params.bytewise else b"PILOT_TKOFF_ALT",
        3.0 if vehicle.params.bytewise else 300.0, m.MAV_PARAM_TYPE_REAL32,
    )  # fmt: skip
    gcs.wait("PARAM_VALUE")
    if not vehicle.params.bytewise:
        assert gcs.command(m.MAV_CMD_DO_SET_MODE, 1, 4) == 0  # GUIDED
    assert gcs.command(m.MAV_CMD_DO_LAND_START) == m.MAV_RESULT_FAILED  # no sequence yet
    assert gcs.command(m.MAV_CMD_COMPONENT_ARM_DISARM, 1) == 0
    assert gcs.command(m.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, NAN, NAN, NAN, NAN) == 0
    gcs.wait("GLOBAL_POSITION_INT", lambda p: abs(p.relative_alt - 3000) < 50, 6.0)
    north = LAT + 450  # 5 m north (1e-7 degree: 1.1 cm)
    assert gcs.command_int(m.MAV_CMD_DO_REPOSITION, REL, -1, 1, 0, 0, x=north, y=LON, z=4.0) == 0
    gcs.wait(
        "GLOBAL_POSITION_INT",
        lambda p: abs(p.lat - north) < 10 and abs(p.relative_alt - 4000) < 50,
        8.0,
    )
    sequence = [
        (REL, m.MAV_CMD_NAV_WAYPOINT, (0, 0, 0, 0), LAT, LON, 5.0),
        (m.MAV_FRAME_MISSION, m.MAV_CMD_DO_LAND_START, (0, 0, 0, 0), 0, 0, 0.0),
        (REL, m.MAV_CMD_NAV_LAND, (0, 0, 0, NAN), LAT - 450, LON, 0.0),
    ]
    assert upload(gcs, sequence, m.MAV_MISSION_TYPE_MISSION) == m.MAV_MISSION_ACCEPTED
    assert gcs.command(m.MAV_CMD_DO_LAND_START) == 0
    landed = gcs.wait("HEARTBEAT", lambda h: not h.base_mode & m.MAV_MODE_FLAG_SAFETY_ARMED, 15.0)
    assert mavutil.mode_string_v10(landed) == "LAND"
    assert abs(vehicle.pos[0] + 5.0) < 0.5 and vehicle.pos[2] == 0.0  # at the NAV_LAND point
