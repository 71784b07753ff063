"""Judging a scenario from what it recorded: pure functions over the timeline and the
vehicles' final states, so the rules can be read (and tested) on their own.

Terms used in the reasons:
- a *gesture command* is a `command` entry from a stream (the operator's gesture); the
  engine's own safety hover when every stream lost the operator has stream "";
- a *handover* is a change of the driving stream between two streams; the first
  acquisition of the operator ("" -> main) and the end of the replays (reason
  `stream_ended`) are listed in the timeline but are not handovers between drones;
- *armed* follows the engine's `arming` entries.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from proxima.drone.mapping import CommandMapping, load_mapping


@dataclass
class Verdict:
    """`passed` only when every check passed; `reasons` says what each check found."""

    passed: bool = True
    reasons: list[str] = field(default_factory=list)

    def check(self, ok: bool, good: str, bad: str) -> bool:
        """Record one check: `good` when it holds, `bad` (and a failure) otherwise."""
        self.reasons.append(good if ok else f"FAILED: {bad}")
        self.passed = self.passed and ok
        return ok

    def note(self, text: str) -> None:
        """An observation that decides nothing."""
        self.reasons.append(text)

    def to_dict(self) -> dict[str, Any]:
        return {"passed": self.passed, "reasons": list(self.reasons)}


def expected_position(
    start: Sequence[float],
    yaw: float,
    gestures: Sequence[str],
    mapping: CommandMapping | None = None,
) -> tuple[float, float, float]:
    """Where a vehicle at local NED `start` heading `yaw` ends after the `gestures`' moves
    (the mapping's body-frame steps rotated into NED; other actions move nothing)."""
    mapping = mapping or load_mapping()
    n, e, d = (float(v) for v in start)
    for gesture in gestures:
        action = mapping.lookup(gesture)
        if action.action != "move" or action.direction is None:
            continue
        step = action.step_m or mapping.step_m
        f, r, dd = (c * step for c in action.direction)
        n += f * math.cos(yaw) - r * math.sin(yaw)
        e += f * math.sin(yaw) + r * math.cos(yaw)
        d += dd
    return (n, e, d)


def entries(timeline: Sequence[dict[str, Any]], kind: str) -> list[dict[str, Any]]:
    return [e for e in timeline if e.get("kind") == kind]


def gesture_commands(timeline: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Commands that came from the operator's gestures (not the engine's safety hover)."""
    return [c for c in entries(timeline, "command") if c.get("stream")]


def drone_handovers(timeline: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Changes of the driving stream from one stream to another while the replays run
    (not the hand-downs when a replay ends)."""
    return [
        h
        for h in entries(timeline, "handover")
        if h["from_stream"] and h["to_stream"] and h["reason"] != "stream_ended"
    ]


def commands_before_arming(timeline: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Gesture commands other than `have_command` decided while control was disarmed,
    plus any command the drone controller refused because control was not armed."""
    armed = False
    bad: list[dict[str, Any]] = []
    for e in timeline:
        kind = e.get("kind")
        if kind == "arming":
            armed = bool(e["armed"])
        elif kind == "command" and e.get("stream") and e["command"] != "have_command":
            if not armed:
                bad.append(e)
        elif kind == "ack" and "not armed" in (e.get("reason") or ""):
            bad.append(e)
    return bad


ARMING = "have_command"


def collapse_rearms(
    commands: Sequence[dict[str, Any]],
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Split gesture commands into the sequence and the repeats of `have_command` that
    follow a `have_command` from the same stream (the operator still performing it after
    the debounce's release time: arming again sends nothing to a vehicle)."""
    kept: list[dict[str, Any]] = []
    repeats: list[dict[str, Any]] = []
    for c in commands:
        prev = kept[-1] if kept else None
        if (
            prev is not None
            and c["command"] == ARMING
            and prev["command"] == ARMING
            and prev["stream"] == c["stream"]
        ):
            repeats.append(c)
        else:
            kept.append(c)
    return kept, repeats


def performed_at(segments: Sequence[dict[str, Any]], t: float, latency_s: float) -> set[str]:
    """Gestures the operator performed at stream time `t`, or finished at most
    `latency_s` before it (a command follows its gesture by the recognition latency)."""
    return {s["gesture"] for s in segments if s["transition_t"] <= t <= s["end_t"] + latency_s}


def check_sequence(
    verdict: Verdict,
    timeline: Sequence[dict[str, Any]],
    expected: Sequence[tuple[str, str]],
    drone: str,
    truth: dict[str, Sequence[dict[str, Any]]] | None = None,
    latency_s: float = 3.0,
    label: str = "",
) -> None:
    """No wrong command: exactly the `expected` (command, stream) gesture commands in
    order (a repeated `have_command` during the same performance is noted, not counted),
    each one the gesture the operator was performing (per the stitched `truth`), all to
    `drone`, none before arming, every one carried out by the vehicle side."""
    commands = gesture_commands(timeline)
    kept, repeats = collapse_rearms(commands)
    got = [(c["command"], c["stream"]) for c in kept]
    shown = ", ".join(f"{c}@{s}" for c, s in got) or "none"
    want = ", ".join(f"{c}@{s}" for c, s in expected)
    verdict.check(
        got == list(expected),
        f"{label}gesture commands as performed: {shown}",
        f"{label}gesture commands {shown}; expected exactly {want}",
    )
    for r in repeats:
        verdict.note(
            f"{label}have_command repeated at t={r['t']} s by {r['stream']} while the operator "
            "still performed it (after the debounce's release time): it re-arms, nothing "
            "is sent to a vehicle"
        )
    if truth is not None:
        wrong = []
        for c in commands:
            segments = truth.get(c["stream"])
            if segments is not None and c["command"] not in performed_at(
                segments, c["t"], latency_s
            ):
                wrong.append(f"{c['command']}@{c['stream']} t={c['t']}")
        verdict.check(
            not wrong,
            f"{label}every command is the gesture the operator was performing",
            f"{label}commands the operator did not perform: {', '.join(wrong)}",
        )
    wrong_drone = [c for c in commands if c["drone"] != drone]
    verdict.check(
        not wrong_drone,
        f"{label}every command went to {drone}",
        f"{label}commands sent to another drone than {drone}: {wrong_drone}",
    )
    early = commands_before_arming(timeline)
    verdict.check(
        not early,
        f"{label}no command before arming (have_command came first)",
        f"{label}commands before arming: {early}",
    )
    acks = [a for a in entries(timeline, "ack") if a.get("stream")]
    failed = [
        f"{a['command']}: {a['status']} ({a['reason']})"
        for a in acks
        if a["status"] not in ("sent", "done")
    ]
    missing = len(commands) - len(acks)
    verdict.check(
        not failed and missing == 0,
        f"{label}every gesture command was carried out by the vehicle side",
        f"{label}commands not carried out: {'; '.join(failed) or f'{missing} unanswered'}",
    )


def check_landed_at(
    verdict: Verdict,
    name: str,
    state: dict[str, Any],
    expected_ne: Sequence[float],
    tolerance_m: float,
) -> None:
    """On the ground, motors disarmed, within `tolerance_m` of `expected_ne` (north, east)."""
    pos = state.get("position_ned")
    if not pos:
        verdict.check(False, "", f"{name}: no final position known")
        return
    off = math.hypot(pos[0] - expected_ne[0], pos[1] - expected_ne[1])
    landed = state.get("landed") == "on_ground" and not state.get("armed")
    where = f"N {pos[0]:+.2f} E {pos[1]:+.2f} m, alt {state.get('altitude_m')} m"
    verdict.check(
        landed and off <= tolerance_m,
        f"{name} landed and disarmed at {where}, {off:.2f} m from the expected place",
        f"{name} at {where} ({state.get('landed')}, armed {state.get('armed')}), "
        f"{off:.2f} m from the expected N {expected_ne[0]:+.2f} E {expected_ne[1]:+.2f} "
        f"(tolerance {tolerance_m} m)",
    )


def check_hovering_at(
    verdict: Verdict,
    name: str,
    state: dict[str, Any],
    expected: Sequence[float],
    tolerance_m: float,
) -> None:
    """In the air within `tolerance_m` of local NED `expected`."""
    pos = state.get("position_ned")
    if not pos:
        verdict.check(False, "", f"{name}: no final position known")
        return
    off = math.dist(pos, expected)
    where = f"N {pos[0]:+.2f} E {pos[1]:+.2f} D {pos[2]:+.2f} m"
    verdict.check(
        state.get("landed") == "in_air" and off <= tolerance_m,
        f"{name} hovers at {where}, {off:.2f} m from its expected final position",
        f"{name} at {where} ({state.get('landed')}), {off:.2f} m from the expected "
        f"N {expected[0]:+.2f} E {expected[1]:+.2f} D {expected[2]:+.2f} "
        f"(tolerance {tolerance_m} m)",
    )


def check_geometric_loss(
    verdict: Verdict,
    timeline: Sequence[dict[str, Any]],
    main: str,
    secondary: str,
    move: str,
    altitude_m: float,
    rise_m: float = 0.5,
) -> None:
    """The closed loop's handover came from geometry: the main camera saw the whole
    operator until `move` was commanded, then lost the feet (a `view` entry, not FULL)
    with its camera at least `rise_m` above the take-off `altitude_m`, before the
    handover to `secondary`; and the secondary's camera saw the whole operator when it
    took over."""
    cmd = next((c for c in gesture_commands(timeline) if c["command"] == move), None)
    hand = next((h for h in drone_handovers(timeline) if h["from_stream"] == main), None)
    views = [e for e in entries(timeline, "view") if e.get("stream") == main]
    if cmd is None or hand is None:
        verdict.check(False, "", f"no {move} command or no handover from {main}: nothing to judge")
        return
    early = [v for v in views if not v["framed"] and v["t"] < cmd["t"]]
    lost = next((v for v in views if not v["framed"] and v["t"] >= cmd["t"]), None)
    height = None if lost is None else lost.get("camera_height_m")
    verdict.check(
        not early
        and lost is not None
        and height is not None
        and height >= altitude_m + rise_m
        and lost["t"] <= hand["t"],
        f"{main}'s camera framed the operator until {move} (t={cmd['t']} s); it lost the "
        f"feet at t={lost and lost['t']} s with the camera {height} m up (take-off "
        f"{altitude_m} m), before the handover at t={hand['t']} s",
        f"the feet were not lost by geometry: views before {move} {early}, first loss "
        f"after it {lost}, handover at t={hand['t']} s",
    )
    side = [
        e for e in entries(timeline, "view") if e.get("stream") == secondary and e["t"] <= hand["t"]
    ]
    sees = bool(side) and side[-1]["framed"]
    verdict.check(
        sees,
        f"{secondary}'s camera saw the whole operator when it took over",
        f"{secondary}'s camera did not frame the operator at the handover: {side[-1:]}",
    )


def judge_paper_flight(
    timeline: Sequence[dict[str, Any]],
    main_state: dict[str, Any],
    expected_ne: Sequence[float],
    expected: Sequence[tuple[str, str]],
    main: str = "main",
    secondary: str = "secondary",
    tolerance_m: float = 0.3,
    problems: Sequence[str] = (),
    truth: dict[str, Sequence[dict[str, Any]]] | None = None,
) -> Verdict:
    """The paper-flight verdict: the main drone landed at the expected place, exactly one
    handover (main -> secondary) happened, no command came before arming and no wrong
    command was sent (the exact gesture sequence, all to the main drone, all carried
    out; the engine's safety hover only after the landing, when the replays end)."""
    v = Verdict()
    check_landed_at(v, main, main_state, expected_ne, tolerance_m)
    hands = drone_handovers(timeline)
    shown = ", ".join(
        f"{h['from_stream']}->{h['to_stream']} ({h['reason']}) t={h['t']}" for h in hands
    )
    v.check(
        len(hands) == 1 and hands[0]["from_stream"] == main and hands[0]["to_stream"] == secondary,
        f"exactly one handover: {shown}",
        f"expected exactly one handover {main}->{secondary}, got {len(hands)}: {shown or 'none'}",
    )
    check_sequence(v, timeline, expected, main, truth)
    landed_t = next(
        (o["t"] for o in entries(timeline, "outcome") if o.get("outcome") == "landed"), None
    )
    safety = [c for c in entries(timeline, "command") if not c.get("stream")]
    early_safety = [c for c in safety if landed_t is None or c["t"] < landed_t]
    v.check(
        not early_safety,
        "no safety hover in flight"
        + (
            f"; after the landing the replays ended and the engine's operator-lost hover "
            f"reached the landed drone ({len(safety)}x, nothing to hold on the ground)"
            if safety
            else ""
        ),
        f"the engine hovered the drone in flight (operator lost everywhere): {early_safety}",
    )
    for problem in problems:
        v.check(False, "", f"time coordination: {problem}")
    firsts = entries(timeline, "gesture")
    hover = [g for g in firsts if g["gesture"] == "hover" and g["stream"] == main]
    if hover:
        v.note(
            f"hover recognised by {main} at t={hover[0]['t']} s before arming: "
            "not sent (gesture control not armed)"
        )
    return v
