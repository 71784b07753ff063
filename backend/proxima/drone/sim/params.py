"""The simulated vehicle's parameters: typed, bounded values and the MAVLink parameter
protocol that reads and writes them.

`ParamStore` holds one autopilot's documented set (`param_sets`) and refuses what is not
a number, not integral for an integer parameter or out of its range. `ParamService` is
the protocol (PARAM_REQUEST_LIST, PARAM_REQUEST_READ, PARAM_SET -> PARAM_VALUE, and
PARAM_ERROR for an unknown name or a refused value). Values travel as ArduPilot sends
them (integers cast to the float field, MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST) or
as PX4 does (the integer's bytes in the float field, PARAM_ENCODE_BYTEWISE).
"""

from __future__ import annotations

import struct
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from proxima.drone.mavlink.fields import finite, text
from proxima.drone.mavlink.protocol import mav

REAL32 = mav.MAV_PARAM_TYPE_REAL32
INT8 = mav.MAV_PARAM_TYPE_INT8
INT16 = mav.MAV_PARAM_TYPE_INT16
INT32 = mav.MAV_PARAM_TYPE_INT32
# Integer types and the struct format of their bytes (PX4's bytewise encoding).
_INT_FORMATS = {
    mav.MAV_PARAM_TYPE_UINT8: "<B",
    INT8: "<b",
    mav.MAV_PARAM_TYPE_UINT16: "<H",
    INT16: "<h",
    mav.MAV_PARAM_TYPE_UINT32: "<I",
    INT32: "<i",
}
PARAM_ID_LEN = 16
SEND_PER_TICK = 25  # PARAM_VALUEs of a list request per physics tick (paced, as autopilots do)


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: its autopilot's name, MAV_PARAM_TYPE, default, accepted range,
    and whether the simulator acts on it (`obeyed`) or only stores it."""

    name: str
    kind: int
    default: float
    lo: float
    hi: float
    doc: str
    obeyed: bool = True

    @property
    def integer(self) -> bool:
        return self.kind != REAL32


class ParamStore:
    """The values of one parameter set, in its order (the PARAM_VALUE index)."""

    def __init__(self, specs: Iterable[ParamSpec], bytewise: bool) -> None:
        self.specs = {s.name: s for s in specs}
        self.order = list(self.specs)
        self.values = {s.name: float(s.default) for s in self.specs.values()}
        self.bytewise = bytewise  # PX4's encoding of integers
        self.version = 0  # counts accepted changes (readers cache on it)
        for spec in self.specs.values():
            if not spec.lo <= spec.default <= spec.hi or len(spec.name) > PARAM_ID_LEN:
                raise ValueError(f"parameter {spec.name}: default {spec.default} outside range")

    def __getitem__(self, name: str) -> float:
        return self.values[name]

    def __len__(self) -> int:
        return len(self.order)

    def index(self, name: str) -> int:
        return self.order.index(name)

    def check(self, name: str, value: float) -> str | None:
        """Why `value` cannot be set for `name`, or None."""
        spec = self.specs.get(name)
        if spec is None:
            return f"no parameter {name!r}"
        if not finite(value):
            return f"{name}: {value} is not a number"
        if spec.integer and value != int(value):
            return f"{name}: {value} is not an integer"
        if not spec.lo <= value <= spec.hi:
            return f"{name}: {value:g} outside [{spec.lo:g}, {spec.hi:g}]"
        return None

    def set(self, name: str, value: float) -> str | None:
        """Set `name` to `value`; None when accepted, else why not (nothing changes)."""
        why = self.check(name, value)
        if why is None:
            self.values[name] = float(value)
            self.version += 1
        return why

    # --- the wire -------------------------------------------------------------------
    def encode(self, name: str) -> float:
        """PARAM_VALUE.param_value of `name`."""
        spec, value = self.specs[name], self.values[name]
        if self.bytewise and spec.integer:
            raw = struct.pack(_INT_FORMATS[spec.kind], int(value)).ljust(4, b"\0")
            return struct.unpack("<f", raw)[0]
        return value

    def decode(self, name: str, raw: float, wire_kind: int) -> float | None:
        """The value a PARAM_SET means, read by the type it declares (`wire_kind`);
        None when that type is not a parameter type."""
        spec = self.specs[name]
        kind = wire_kind if wire_kind in _INT_FORMATS or wire_kind == REAL32 else None
        if kind is None:
            return None
        if kind == REAL32 or not self.bytewise:
            return raw
        fmt = _INT_FORMATS[kind]
        size = struct.calcsize(fmt)
        try:
            packed = struct.pack("<f", raw)
        except (OverflowError, struct.error):  # a double beyond float32
            return None
        value = struct.unpack(fmt, packed[:size])[0]
        return float(value) if spec.integer else None


class ParamService:
    """The parameter protocol of one vehicle, on the server's encoder `m`.
    `say(text, severity)` reports a refused PARAM_SET as the vehicle's STATUSTEXT."""

    def __init__(self, store: ParamStore, m: Any, say: Callable[[str, int], None]) -> None:
        self.store = store
        self.m = m
        self.say = say
        self._queue: deque[int] = deque()  # indices of a list request still to send
        self.messages: dict[str, Callable[[Any], None]] = {
            "PARAM_REQUEST_LIST": self._request_list,
            "PARAM_REQUEST_READ": self._request_read,
            "PARAM_SET": self._set,
        }

    def tick(self, now: float) -> None:
        """Send the next PARAM_VALUEs of a list request."""
        for _ in range(min(SEND_PER_TICK, len(self._queue))):
            self._send_value(self._queue.popleft())

    def _request_list(self, msg: Any) -> None:
        self._queue.clear()  # a new list request restarts the list (PARAM_VALUE is broadcast)
        self._queue.extend(range(len(self.store)))

    def _request_read(self, msg: Any) -> None:
        index = msg.param_index
        name = text(msg.param_id, PARAM_ID_LEN)
        if index >= 0:  # the index wins over the name (parameter protocol)
            if index < len(self.store):
                self._send_value(index)
            else:
                self._error(msg, name, index, mav.MAV_PARAM_ERROR_DOES_NOT_EXIST)
        elif name in self.store.specs:
            self._send_value(self.store.index(name))
        else:
            self._error(msg, name, index, mav.MAV_PARAM_ERROR_DOES_NOT_EXIST)

    def _set(self, msg: Any) -> None:
        name = text(msg.param_id, PARAM_ID_LEN)
        if name not in self.store.specs:
            self._error(msg, name, -1, mav.MAV_PARAM_ERROR_DOES_NOT_EXIST)
            return
        value = self.store.decode(name, msg.param_value, msg.param_type)
        why = (
            f"{name}: param_type {msg.param_type} is not a parameter type"
            if value is None
            else self.store.set(name, value)
        )
        if why is not None:
            self.say(f"Param refused: {why}"[:50], mav.MAV_SEVERITY_WARNING)
            self._error(msg, name, self.store.index(name), mav.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE)
            return
        self._send_value(self.store.index(name))  # the new value confirms the set

    def _send_value(self, index: int) -> None:
        name = self.store.order[index]
        value = self.store.encode(name)
        kind = self.store.specs[name].kind
        self.m.param_value_send(name.encode(), value, kind, len(self.store), index)

    def _error(self, msg: Any, name: str, index: int, error: int) -> None:
        self.m.param_error_send(
            msg.get_srcSystem(), msg.get_srcComponent(), name.encode()[:16], index, error
        )
