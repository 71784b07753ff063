"""The gesture -> drone command table, loaded from TOML (`mapping.toml` beside this file
is the shipped, documented default; users edit a copy and pass `--mapping PATH`).

Left and right are the drone's own: directions are [forward, right, down] in the body
frame of the drone that receives the command, i.e. the pilot's point of view that
aircraft-marshalling signals use. A drone facing the operator therefore moves to the
operator's right on `move_to_left`. Swap the two directions in the table for the
operator's frame.
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from proxima.types import GESTURES

DEFAULT_MAPPING = Path(__file__).with_name("mapping.toml")
ACTIONS = (
    "hold",
    "move",
    "change_speed",
    "resume_speed",
    "land",
    "arm_control",
    "abort",
    "none",
)
_KEYS = {
    "hold": set(),
    "move": {"direction", "step_m"},
    "change_speed": {"factor"},
    "resume_speed": set(),
    "land": set(),
    "arm_control": set(),
    "abort": set(),
    "none": set(),
}


class MappingError(ValueError):
    """A mapping file that cannot be used; the message names file, line and field."""


_Fail = Callable[[str, str], MappingError]


@dataclass(frozen=True)
class MappedAction:
    """What one gesture does. `direction` is a unit vector [forward, right, down] in the
    drone's body frame; `step_m` the move length; `factor` the speed multiplier."""

    gesture: str
    action: str
    direction: tuple[float, float, float] | None = None
    step_m: float | None = None
    factor: float | None = None


@dataclass(frozen=True)
class CommandMapping:
    """The loaded table plus its settings."""

    actions: dict[str, MappedAction]
    step_m: float
    cruise_speed_m_s: float
    min_speed_m_s: float
    source: str

    def lookup(self, gesture: str) -> MappedAction:
        """The action for `gesture`.

        Raises:
            MappingError: the gesture is not in the table.
        """
        try:
            return self.actions[gesture]
        except KeyError:
            raise MappingError(f"{self.source}: no entry for gesture {gesture!r}") from None

    def table(self) -> list[dict]:
        """The table as rows (for the console and the docs)."""
        rows = []
        for gesture in GESTURES:
            a = self.actions[gesture]
            rows.append(
                {
                    "gesture": gesture,
                    "action": a.action,
                    "direction": a.direction,
                    "step_m": a.step_m,
                    "factor": a.factor,
                }
            )
        return rows


def load_mapping(path: str | Path | None = None) -> CommandMapping:
    """Read and validate a mapping file (the shipped default when `path` is None).

    Raises:
        MappingError: unreadable TOML, an unknown gesture or action, a missing gesture,
            a bad field; the message names the file, the line and the field.
    """
    path = Path(path) if path is not None else DEFAULT_MAPPING
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise MappingError(f"{path}: cannot read mapping: {exc.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MappingError(f"{path}: {exc}") from None

    def fail(where: str, message: str) -> MappingError:
        return MappingError(f"{path}, line {_line_of(text, where)}: {message}")

    settings = data.get("settings", {})
    if not isinstance(settings, dict):
        raise fail("settings", "[settings] must be a table")
    for key in settings:
        if key not in ("step_m", "cruise_speed_m_s", "min_speed_m_s"):
            raise fail("settings", f"unknown field settings.{key}")
    step = _positive(settings.get("step_m", 1.0), "settings.step_m", fail, "settings")
    cruise = _positive(
        settings.get("cruise_speed_m_s", 5.0), "settings.cruise_speed_m_s", fail, "settings"
    )
    min_speed = _positive(
        settings.get("min_speed_m_s", 0.5), "settings.min_speed_m_s", fail, "settings"
    )
    for key in data:
        if key not in ("settings", "gestures"):
            raise fail(key, f"unknown table [{key}] (expected [settings] and [gestures.*])")
    gestures = data.get("gestures", {})
    actions: dict[str, MappedAction] = {}
    for gesture, entry in gestures.items():
        where = f"gestures.{gesture}"
        if gesture not in GESTURES:
            raise fail(where, f"unknown gesture {gesture!r} (known: {', '.join(GESTURES)})")
        if not isinstance(entry, dict):
            raise fail(where, f"[{where}] must be a table")
        action = entry.get("action")
        if action not in ACTIONS:
            raise fail(where, f"{where}.action is {action!r}; expected one of {ACTIONS}")
        extra = set(entry) - {"action"} - _KEYS[action]
        if extra:
            raise fail(where, f"{where}: field(s) {sorted(extra)} do not apply to {action!r}")
        direction = step_m = factor = None
        if action == "move":
            direction = _direction(entry.get("direction"), f"{where}.direction", fail, where)
            if "step_m" in entry:
                step_m = _positive(entry["step_m"], f"{where}.step_m", fail, where)
        if action == "change_speed":
            factor = _positive(entry.get("factor"), f"{where}.factor", fail, where)
            if factor >= 1.0:
                raise fail(where, f"{where}.factor must be below 1 (it lowers the speed)")
        actions[gesture] = MappedAction(gesture, action, direction, step_m, factor)
    missing = [g for g in GESTURES if g not in actions]
    if missing:
        raise MappingError(
            f"{path}: no entry for gesture(s) {', '.join(missing)}; "
            'every gesture must be mapped (use action = "none")'
        )
    return CommandMapping(actions, step, cruise, min_speed, str(path))


def _positive(value: object, name: str, fail: _Fail, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise fail(where, f"{name} must be a positive number, got {value!r}")
    if not math.isfinite(value):
        raise fail(where, f"{name} must be finite, got {value!r}")
    return float(value)


def _direction(value: object, name: str, fail: _Fail, where: str) -> tuple[float, float, float]:
    if not isinstance(value, list) or len(value) != 3:
        raise fail(where, f"{name} must be [forward, right, down], got {value!r}")
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        raise fail(where, f"{name} must hold three numbers, got {value!r}")
    norm = math.sqrt(sum(float(v) ** 2 for v in value))
    if not math.isfinite(norm) or norm == 0.0:
        raise fail(where, f"{name} must not be zero, got {value!r}")
    return (value[0] / norm, value[1] / norm, value[2] / norm)


def _line_of(text: str, where: str) -> int:
    """1-based line of the table header (or key) `where` in the TOML text; 0 if unknown."""
    pattern = re.compile(r"^\s*\[\s*" + re.escape(where).replace(r"\.", r"\s*\.\s*") + r"\s*\]")
    for number, line in enumerate(text.splitlines(), start=1):
        if pattern.match(line):
            return number
    head = where.split(".")[0]
    for number, line in enumerate(text.splitlines(), start=1):
        if re.match(r"^\s*" + re.escape(head) + r"\s*[.=]", line):
            return number
    return 0
