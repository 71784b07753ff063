"""Alarms derived from telemetry (issue 26, finding 4): low battery as a warning and
then a critical alarm at the configured thresholds, a landing the console did not
command as a critical failsafe alarm, none for a commanded one; each in the server log,
the audit trail and the WebSocket's hello."""

from __future__ import annotations

import logging

import pytest
from api_helpers import Api

from proxima.drone.events import CommandResultEvent, DroneAlarmEvent, DroneStateEvent


def _state(drone: str, pct: float, mode: str = "GUIDED", landed: str = "in_air") -> DroneStateEvent:
    return DroneStateEvent(t=0.0, stream=drone, drone=drone, link="ok", mode=mode,
                           landed=landed, battery_pct=pct)  # fmt: skip


def test_battery_and_failsafe_alarms(api: Api, caplog: pytest.LogCaptureFixture) -> None:
    alarms: list[DroneAlarmEvent] = []
    api.bus.add_listener(lambda e: alarms.append(e) if isinstance(e, DroneAlarmEvent) else None)
    caplog.set_level(logging.WARNING, logger="proxima.api.alarms")
    for pct in (35.0, 21.0, 20.0, 19.0, 12.0, 10.0, 9.0):
        api.bus.publish(_state("main", pct))
    assert [(a.kind, a.severity, a.active) for a in alarms] == [
        ("battery_low", "warning", True),
        ("battery_low", "critical", True),
    ]
    assert "battery 20%" in alarms[0].message and "battery 10%" in alarms[1].message
    # The autopilot lands on its own: a failsafe, critical (as the simulator reports it:
    # "landing" a message before the mode says LAND).
    api.bus.publish(_state("main", 9.0, landed="landing"))
    api.bus.publish(_state("main", 9.0, mode="LAND", landed="landing"))
    assert alarms[-1].kind == "failsafe_landing" and alarms[-1].severity == "critical"
    assert "LAND on its own" in alarms[-1].message
    # A landing commanded through the console is no failsafe.
    api.bus.publish(_state("second", 80.0))
    api.bus.publish(CommandResultEvent(t=0.0, stream="left", drone="second", command="land",
                                       action="land", status="sent"))  # fmt: skip
    api.bus.publish(_state("second", 80.0, mode="LAND"))
    assert not [a for a in alarms if a.drone == "second"]
    assert sum("alarm battery_low" in r.getMessage() for r in caplog.records) == 2

    audit = api.client.get("/api/audit?action=alarm", headers=api.admin).json()["entries"]
    assert [(e["target"], e["detail"]["kind"]) for e in audit] == [
        ("main", "failsafe_landing"),
        ("main", "battery_low"),
        ("main", "battery_low"),
    ]
    token = api.admin["Authorization"].split()[1]
    with api.client.websocket_connect("/api/ws", subprotocols=["proxima", token]) as ws:
        hello = ws.receive_json()
    assert [a["kind"] for a in hello["alarms"]][:2] == ["failsafe_landing", "battery_low"]


def test_geofence_alarms_follow_the_drones_position(api: Api) -> None:
    alarms: list[DroneAlarmEvent] = []
    api.bus.add_listener(lambda e: alarms.append(e) if isinstance(e, DroneAlarmEvent) else None)

    def at(north: float, down: float) -> None:
        api.bus.publish(DroneStateEvent(t=0.0, stream="main", drone="main", link="ok",
                                        position=[north, 0.0, down], battery_pct=90.0))  # fmt: skip

    # The default fence: 30 m around home, 20 m ceiling; a warning beyond 90 % of either.
    for north, down in ((5, -5), (26, -5), (28, -5), (29, -5), (31, -5), (32, -5), (10, -5),
                        (0, -19)):  # fmt: skip
        at(north, down)
    assert [(a.kind, a.severity, a.active) for a in alarms] == [
        ("geofence", "warning", True),
        ("geofence", "critical", True),
        ("geofence", "warning", False),
        ("geofence", "warning", True),
    ]
    assert "near the geofence, 28.0 m from home (fence radius 30 m)" in alarms[0].message
    assert "outside the geofence, 31.0 m from home" in alarms[1].message
    assert "back inside" in alarms[2].message
    assert "19.0 m up (ceiling 20 m)" in alarms[3].message
