"""The mapping table, the safety rules and the command log on their own (real files,
a controllable clock)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from proxima.drone.mapping import DEFAULT_MAPPING, MappingError, load_mapping
from proxima.drone.safety import EmergencyStopError, SafetyConfig, SafetyGate
from proxima.store.command_log import CommandLog
from proxima.types import GESTURES


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_default_mapping_covers_every_gesture() -> None:
    m = load_mapping()
    assert set(m.actions) == set(GESTURES)
    assert m.lookup("have_command").action == "arm_control"
    assert m.lookup("wave_off").action == "abort"
    assert m.lookup("hover").action == "hold"
    assert m.lookup("land").action == "land"
    assert m.lookup("slow_down").action == "change_speed" and m.lookup("slow_down").factor == 0.5
    assert m.lookup("move_to_left").direction == (0.0, -1.0, 0.0)  # the drone's own left
    assert m.lookup("move_upward").direction == (0.0, 0.0, -1.0)
    assert {m.lookup(g).action for g in ("land_direction", "not_clear")} == {"hold"}
    assert m.lookup("all_clear").action == "resume_speed"


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("[gestures.not_clear]", "[gestures.not_clr]", "line {line}: unknown gesture 'not_clr'"),
        ('action = "land"', 'action = "crash"', "gestures.land.action is 'crash'"),
        ("factor = 0.5", "factor = 2", "factor must be below 1"),
        ("direction = [0.0, -1.0, 0.0]", "direction = [0, 0]", "must be [forward, right, down]"),
        ("step_m = 1.0 ", "step_m = -1.0 ", "settings.step_m must be a positive number"),
        ('[gestures.wave_off]\naction = "abort"\n', "", "no entry for gesture(s) wave_off"),
        ("[settings]", "[settings", "line {line}"),
    ],
)
def test_bad_mapping_names_file_line_and_field(
    tmp_path: Path, old: str, new: str, message: str
) -> None:
    text = DEFAULT_MAPPING.read_text()
    assert old in text
    if "{line}" in message:  # the error must point at the edited line
        message = message.format(line=text.splitlines().index(old) + 1)
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(old, new, 1))
    with pytest.raises(MappingError) as err:
        load_mapping(bad)
    assert str(bad) in str(err.value) and message in str(err.value)


def test_geofence_step_and_altitude() -> None:
    gate = SafetyGate(
        SafetyConfig(geofence_radius_m=10, min_altitude_m=1, max_altitude_m=5, max_step_m=2)
    )
    assert gate.check_move((0, -1, 0), (0, -1, -2)).ok
    assert "max_step_m" in gate.check_move((0, 3, 0), (0, 3, -2)).reason
    assert "radius" in gate.check_move((1, 0, 0), (9, 5, -2)).reason
    assert "max_altitude_m" in gate.check_move((0, 0, -1), (0, 0, -5.5)).reason
    assert "min_altitude_m" in gate.check_move((0, 0, 1), (0, 0, -0.5)).reason
    with pytest.raises(ValueError, match="min_altitude_m"):
        SafetyConfig(min_altitude_m=5, max_altitude_m=2)


def test_rate_limit_arming_and_operator_watchdog() -> None:
    clock = Clock()
    gate = SafetyGate(SafetyConfig(min_interval_s=1.0, operator_lost_s=2.0), clock)
    assert not gate.is_armed("a")
    gate.arm_control("a")
    assert gate.is_armed("a") and not gate.is_armed("b")
    gate.note_sent("a")
    clock.now += 0.5
    assert not gate.check_rate("a", "move").ok
    assert gate.check_rate("a", "hold").ok and gate.check_rate("a", "land").ok  # never limited
    assert gate.check_rate("b", "move").ok
    clock.now += 0.6
    assert gate.check_rate("a", "move").ok

    assert not gate.operator_lost()  # no stream yet: nothing to judge
    gate.note_operator("front", True)
    gate.note_operator("left", False)
    clock.now += 1.9
    assert not gate.operator_lost()
    clock.now += 0.2
    assert gate.operator_lost()
    gate.note_operator("left", True)
    assert not gate.operator_lost()


def test_emergency_stop_tokens_expire_and_are_single_use() -> None:
    clock = Clock()
    gate = SafetyGate(SafetyConfig(estop_confirm_s=5.0), clock)
    req = gate.request_emergency_stop("a")
    with pytest.raises(EmergencyStopError, match="issued for 'a'"):
        gate.confirm_emergency_stop(req.token, drone="b")
    assert gate.confirm_emergency_stop(req.token, drone="a").drone == "a"
    with pytest.raises(EmergencyStopError, match="already used"):
        gate.confirm_emergency_stop(req.token)
    late = gate.request_emergency_stop("a", "kill")
    clock.now += 5.1
    with pytest.raises(EmergencyStopError, match="after 5 s"):
        gate.confirm_emergency_stop(late.token)
    with pytest.raises(ValueError, match="kind"):
        gate.request_emergency_stop("a", "explode")


def test_command_log_round_trip(tmp_path: Path) -> None:
    log = CommandLog(tmp_path / "sub" / "log.db")
    row = log.add(
        drone="a",
        source="gesture",
        command="land",
        stream="front",
        gesture_t=12.5,
        confidence=0.91,
        action="land",
        status="sent",
        sent={"msg": "COMMAND_LONG", "params": [0.0, math.nan]},
    )
    log.update(row, ack="accepted", outcome="landed", ack_latency_ms=1.5)
    again = CommandLog(tmp_path / "sub" / "log.db")  # a new process would see the same
    got = again.get(row)
    assert got["ack"] == "accepted" and got["outcome"] == "landed" and got["confidence"] == 0.91
    assert got["sent"] == {"msg": "COMMAND_LONG", "params": [0.0, None]}  # NaN -> null
    assert got["created_at"].endswith("+00:00")
    assert again.recent(drone="b") == [] and len(again.recent(drone="a")) == 1
    with pytest.raises(TypeError, match="no field"):
        log.add(drone="a", source="x", command="y", colour="red")
    with pytest.raises(KeyError):
        log.update(999, ack="x")


def test_docs_table_matches_the_shipped_mapping() -> None:
    doc = Path(__file__).parents[2] / "docs" / "drone.md"
    rows = {}
    for line in doc.read_text().splitlines():
        m = re.match(r"\| `(\w+)` \| (\w+)( \[([-\d, ]+)\])?", line)
        if m and m.group(1) in GESTURES:
            direction = tuple(float(v) for v in m.group(4).split(",")) if m.group(4) else None
            rows[m.group(1)] = (m.group(2), direction)
    mapping = load_mapping()
    assert set(rows) == set(GESTURES)
    for gesture, (action, direction) in rows.items():
        entry = mapping.lookup(gesture)
        assert entry.action == action, gesture
        assert direction is None or entry.direction == direction, gesture
