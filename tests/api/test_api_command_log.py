"""The durable command log through the API (issue 26, finding 3): filtered by drone and
status, exported as CSV with every column, and in the WebSocket's `hello` with times,
statuses and reasons, so the browser's log is the same after a reload."""

from __future__ import annotations

import csv
import io

from api_helpers import Api


def _fill(api: Api) -> None:
    log = api.console.command_log
    log.add(drone="main", source="gesture", command="move_upward", stream="front",
            gesture_t=12.5, action="move", status="refused",
            reason="gesture control not armed (have_command first): nothing sent")  # fmt: skip
    log.add(drone="main", source="api", command="emergency_stop", action="land",
            status="sent", ack="accepted", outcome="landed")  # fmt: skip
    log.add(drone="second", source="gesture", command="hover", stream="left",
            gesture_t=3.0, action="hold", status="sent", ack="accepted")  # fmt: skip


def test_filters_and_csv(api: Api) -> None:
    _fill(api)
    r = api.client.get("/api/commands?drone=main&status=refused", headers=api.admin)
    assert [row["command"] for row in r.json()] == ["move_upward"]
    r = api.client.get("/api/commands/export.csv?drone=main", headers=api.viewer)
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
    assert "command-log.csv" in r.headers["content-disposition"]
    rows = list(csv.DictReader(io.StringIO(r.text)))
    assert [x["command"] for x in rows] == ["emergency_stop", "move_upward"]
    assert rows[1]["reason"].startswith("gesture control not armed")
    assert rows[0]["outcome"] == "landed" and rows[0]["created_at"]
    assert api.client.get("/api/commands/export.csv").status_code == 401


def test_hello_carries_the_durable_log(api: Api) -> None:
    _fill(api)
    token = api.admin["Authorization"].split()[1]
    with api.client.websocket_connect("/api/ws", subprotocols=["proxima", token]) as ws:
        hello = ws.receive_json()
    assert hello["type"] == "hello"
    log = hello["command_log"]
    assert [r["command"] for r in log] == ["hover", "emergency_stop", "move_upward"]
    assert all(r["created_at"] for r in log)
    assert log[2]["status"] == "refused" and "not armed" in log[2]["reason"]
