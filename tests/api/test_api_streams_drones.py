"""Streams and drones: configuration merged with live state from the bus."""

from __future__ import annotations

from api_helpers import Api

from proxima.drone.events import DroneStateEvent
from proxima.events import ArmingEvent, CommandEvent, GestureEvent, HandoverEvent, StreamEvent


def test_streams_show_live_state(api: Api) -> None:
    c, bus = api.client, api.bus
    streams = c.get("/api/streams", headers=api.viewer).json()
    assert [s["name"] for s in streams] == ["front", "left"]
    assert streams[0]["kind"] == "replay" and streams[0]["drone"] == "main"
    bus.publish(StreamEvent(t=0.0, stream="front", state="live"))
    bus.publish(GestureEvent(t=2.0, stream="front", gesture="hover", confidence=0.9, probs=[]))
    bus.publish(ArmingEvent(t=2.0, stream="front", armed=True, reason="have_command"))
    bus.publish(
        HandoverEvent(
            t=2.0,
            stream="left",
            from_stream="front",
            to_stream="left",
            reason="main lost the operator",
        )
    )
    front = c.get("/api/streams/front", headers=api.viewer).json()
    assert front["live"]["state"] == "live" and front["live"]["gesture"] == "hover"
    assert front["live"]["withheld"] == []
    thumb = ["all_clear", "not_clear"]
    bus.publish(GestureEvent(t=2.2, stream="left", gesture="all_clear", confidence=0.95,
                             probs=[], withheld=thumb))  # fmt: skip
    left = c.get("/api/streams/left", headers=api.viewer).json()
    assert left["live"]["gesture"] == "all_clear" and left["live"]["withheld"] == thumb
    assert front["live"]["armed"] is True and front["driving"] is False
    assert c.get("/api/streams/left", headers=api.viewer).json()["driving"] is True
    assert c.get("/api/streams/nope", headers=api.viewer).status_code == 404


def test_drones_and_command_history(api: Api) -> None:
    c, bus = api.client, api.bus
    bus.publish(
        DroneStateEvent(t=1.0, drone="main", link="ok", mode="GUIDED", position=[1.0, 2.0, -3.0])
    )
    bus.publish(
        HandoverEvent(t=2.0, stream="left", from_stream="front", to_stream="left", reason="x")
    )
    drones = {d["name"]: d for d in c.get("/api/drones", headers=api.viewer).json()}
    assert drones["main"]["state"]["link"] == "ok"
    assert drones["main"]["state"]["position"] == [1.0, 2.0, -3.0]
    assert drones["second"]["driving"] is True and drones["main"]["driving"] is False
    assert drones["main"]["streams"] == ["front"]
    bus.publish(CommandEvent(t=3.0, stream="left", command="move_to_left", drone="main"))
    bus.publish(CommandEvent(t=5.0, stream="left", command="land", drone="main"))
    live = c.get("/api/commands/live", headers=api.viewer).json()
    assert [x["command"] for x in live] == ["land", "move_to_left"]


def test_rtsp_credentials_are_hidden() -> None:
    from proxima.api.routers.streams import public_uri

    assert public_uri("rtsp://pilot:secret@10.0.0.5/live") == "rtsp://***@10.0.0.5/live"
    assert public_uri("replay:/a@b/c.csv@30") == "replay:/a@b/c.csv@30"
