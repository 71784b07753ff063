"""State that is never stale after an emergency stop (issue 26, finding 2): a stopped
drone's gesture control is off and stays off (neither the engine's arming nor a
have_command re-arms it) until a supervisor resumes it through the API; the link's
state says so (`emergency_stopped`, published as `drone_state.stopped`); stop and
resume are in the command log and the audit trail."""

from __future__ import annotations

from pathlib import Path

from api_helpers import ADMIN, VIEWER, login, make_settings
from fastapi.testclient import TestClient

from proxima.api import create_app
from proxima.drone.controller import DroneController, EmergencyStopService
from proxima.drone.events import CommandResultEvent
from proxima.drone.memory import MemoryLink
from proxima.events import ArmingEvent, CommandEvent, EventBus
from proxima.store.command_log import CommandLog
from proxima.store.users import Role, create_user


def test_a_stopped_drone_cannot_be_rearmed_until_resumed(tmp_path: Path) -> None:
    settings = make_settings(tmp_path)
    bus = EventBus()
    links = {d.name: MemoryLink(d.name) for d in settings.drones}
    for link in links.values():
        link.connect()
    results: list[CommandResultEvent] = []
    bus.add_listener(lambda e: results.append(e) if isinstance(e, CommandResultEvent) else None)
    app = create_app(settings, bus)
    controller = DroneController(
        links, safety=settings.safety, bus=bus, log=CommandLog(app.state.console.db_engine)
    )
    app.state.console.estop = EmergencyStopService(controller)
    with app.state.console.sessions() as db:
        create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
    main = links["main"]
    try:
        with TestClient(app) as client:
            admin, viewer = login(client, ADMIN), login(client, VIEWER)
            controller.on_event(ArmingEvent(t=1.0, stream="front", armed=True, reason="test"))
            assert controller.gesture_control_armed("main") and main.gesture_control

            r = client.post("/api/drones/main/resume", headers=admin)
            assert r.status_code == 409 and "not emergency-stopped" in r.json()["detail"]
            cid = client.post("/api/drones/main/emergency-stop", headers=admin).json()
            r = client.post(
                "/api/drones/main/emergency-stop/confirm",
                headers=admin,
                json={"confirmation_id": cid["confirmation_id"]},
            )
            assert r.status_code == 200, r.text
            assert not controller.gesture_control_armed("main")
            assert main.emergency_stopped and not main.gesture_control
            # The other drone is not stopped.
            assert controller.gesture_control_armed("second")

            # Neither the engine's arming nor a have_command re-arms the stopped drone.
            controller.on_event(ArmingEvent(t=2.0, stream="front", armed=True, reason="again"))
            assert not controller.gesture_control_armed("main")
            out = controller.handle(
                CommandEvent(t=3.0, stream="front", command="have_command", drone="main")
            )
            assert out.status == "refused" and "resume" in out.reason
            assert results[-1].status == "refused" and "emergency-stopped" in results[-1].reason

            assert client.post("/api/drones/main/resume", headers=viewer).status_code == 403
            r = client.post("/api/drones/main/resume", headers=admin)
            assert r.status_code == 200, r.text
            assert not main.emergency_stopped
            assert not controller.gesture_control_armed("main")  # until have_command
            out = controller.handle(
                CommandEvent(t=4.0, stream="front", command="have_command", drone="main")
            )
            assert out.status == "done" and controller.gesture_control_armed("main")

            audit = client.get("/api/audit?action=drone", headers=admin).json()["entries"]
            assert [(e["action"], e["outcome"]) for e in audit] == [
                ("drone.resume", "ok"),
                ("drone.stop", "ok"),
                ("drone.stop_request", "ok"),
                ("drone.resume", "refused"),
            ]
            rows = CommandLog(app.state.console.db_engine).recent(limit=20)
            assert [r["command"] for r in rows if r["command"] in ("resume", "emergency_stop")][
                :2
            ] == ["resume", "emergency_stop"]
    finally:
        controller.close()
        for link in links.values():
            link.close()
