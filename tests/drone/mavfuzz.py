"""Random and mutated MAVLink datagrams for the fuzz tests, reproducible from a seed.

Messages are built by pymavlink's own encoders of the common dialect with random field
values (NaN, infinities, extremes, random numbers and bytes), then sent whole as
MAVLink 2 or 1, or broken: truncated, with a bad CRC, a wrong length byte, flipped
bytes, several packets in one datagram, or plain garbage. Half of the messages are the
kinds the simulator handles, aimed at its system id, so they reach its handlers.

`safe=True` keeps the state-changing commands (arm, speed, message intervals) and
parameter writes to values the vehicle must refuse, so that a vehicle fuzzed on the
ground is still on the ground, disarmed, with its parameters, afterwards.
"""

from __future__ import annotations

import math
import os
import random
import struct
from collections import Counter
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import common

FLOATS = (
    math.nan,
    math.inf,
    -math.inf,
    0.0,
    -0.0,
    1.0,
    -1.0,
    -2.0,
    0.5,
    21196.0,
    1e-45,
    1e38,
    -1e38,
    3.4028234e38,
    2147483647.0,
    -2147483648.0,
)
BAD_FLOATS = (math.nan, math.inf, -math.inf, 1e38, -1e38, 0.5, -7.0, 3.4028234e38)
INT_RANGES = {
    "uint8_t": (0, 2**8 - 1),
    "int8_t": (-(2**7), 2**7 - 1),
    "uint16_t": (0, 2**16 - 1),
    "int16_t": (-(2**15), 2**15 - 1),
    "uint32_t": (0, 2**32 - 1),
    "int32_t": (-(2**31), 2**31 - 1),
    "uint64_t": (0, 2**64 - 1),
    "int64_t": (-(2**63), 2**63 - 1),
}
HANDLED = (
    "HEARTBEAT",
    "COMMAND_LONG",
    "COMMAND_INT",
    "SET_MODE",
    "SET_POSITION_TARGET_LOCAL_NED",
    "SET_POSITION_TARGET_GLOBAL_INT",
    "PARAM_SET",
    "PARAM_REQUEST_READ",
    "PARAM_REQUEST_LIST",
    "MISSION_COUNT",
    "MISSION_ITEM_INT",
    "MISSION_ITEM",
    "MISSION_REQUEST_INT",
    "MISSION_REQUEST",
    "MISSION_REQUEST_LIST",
    "MISSION_CLEAR_ALL",
    "MISSION_SET_CURRENT",
    "FILE_TRANSFER_PROTOCOL",
)
# Commands the simulator acts on, and those a safe fuzz only sends bad params to.
COMMANDS = (16, 20, 21, 22, 176, 178, 189, 192, 400, 410, 510, 511, 512, 520)
STATE_CHANGING = frozenset({178, 400, 511})
_CLASSES = {cls.msgname: cls for cls in common.mavlink_map.values()}


class Fuzzer:
    """Datagrams for a vehicle with system id `sysid`; `param_names` are its parameters
    (PARAM_SET then names them often), `senders` the system ids messages claim."""

    def __init__(
        self,
        seed: int,
        sysid: int,
        *,
        param_names: tuple[str, ...] = (),
        senders: tuple[int, ...] = (255,),
        safe: bool = True,
    ) -> None:
        self.rng = random.Random(seed)
        self.sysid = sysid
        self.param_names = param_names
        self.senders = senders
        self.safe = safe
        self.kinds: Counter[str] = Counter()  # what was sent, by mutation
        self._encoders = {
            (s, c): common.MAVLink(None, srcSystem=s, srcComponent=c)
            for s in {*senders, 1}
            for c in (1, 190)
        }
        self._all = sorted(_CLASSES)

    # --- field values ------------------------------------------------------------------
    def _value(self, ftype: str) -> Any:
        rng = self.rng
        if ftype in ("float", "double"):
            if rng.random() < 0.6:
                return rng.choice(FLOATS)
            return rng.uniform(-1e6, 1e6) if rng.random() < 0.5 else rng.uniform(-10, 10)
        if ftype == "char":
            return bytes(rng.randrange(256) for _ in range(rng.randrange(0, 20)))
        lo, hi = INT_RANGES[ftype]
        return rng.choice((lo, hi, 0, 1, rng.randint(lo, hi), rng.randint(0, min(hi, 600))))

    def _fields(self, cls: Any) -> dict[str, Any]:
        out: dict[str, Any] = {}
        lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
        for name, ftype in zip(cls.fieldnames, cls.fieldtypes, strict=True):
            length = lengths[name]
            if length and ftype != "char":
                out[name] = [self._value(ftype) for _ in range(length)]
            elif length:
                out[name] = self._value("char")[:length]
            else:
                out[name] = self._value(ftype)
        return out

    def message(self) -> Any:
        """One message with random fields (half of them of a kind the vehicle handles)."""
        rng = self.rng
        name = rng.choice(HANDLED) if rng.random() < 0.5 else rng.choice(self._all)
        cls = _CLASSES[name]
        f = self._fields(cls)
        if "target_system" in f and rng.random() < 0.85:
            f["target_system"] = rng.choice((self.sysid, 0))
        if "target_component" in f and rng.random() < 0.85:
            f["target_component"] = rng.choice((0, 1))
        if name in ("COMMAND_LONG", "COMMAND_INT") and rng.random() < 0.7:
            f["command"] = rng.choice(COMMANDS)
        if name == "COMMAND_LONG" and self.safe and f["command"] in STATE_CHANGING:
            for i in range(1, 8):
                f[f"param{i}"] = rng.choice(BAD_FLOATS)
        if name == "COMMAND_INT" and self.safe and f["command"] in STATE_CHANGING:
            for i in range(1, 5):
                f[f"param{i}"] = rng.choice(BAD_FLOATS)
        if name == "PARAM_SET" and self.param_names and rng.random() < 0.6:
            f["param_id"] = rng.choice(self.param_names).encode()
            if self.safe:
                f["param_value"] = rng.choice((math.nan, math.inf, -math.inf, 1e38, -1e38))
                f["param_type"] = common.MAV_PARAM_TYPE_REAL32
        return cls(**f)

    # --- datagrams ---------------------------------------------------------------------
    def _packed(self, msg: Any, v1: bool) -> bytes:
        enc = self._encoders[(self.rng.choice(self.senders), self.rng.choice((1, 190)))]
        return bytes(msg.pack(enc, force_mavlink1=v1))

    def _packed_or_empty(self, msg: Any) -> bytes:
        try:
            return self._packed(msg, False)
        except (struct.error, OverflowError, ValueError, TypeError):
            return b""

    def datagram(self) -> bytes:
        """One datagram: a whole, broken or garbage MAVLink packet (or several)."""
        rng = self.rng
        roll = rng.random()
        msg = self.message()
        v1 = msg.id < 256 and rng.random() < 0.25
        try:
            buf = self._packed(msg, v1)
        except (struct.error, OverflowError, ValueError, TypeError):  # not encodable
            self.kinds["unencodable"] += 1
            return bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300)))
        if roll < 0.45:
            kind, out = ("v1" if v1 else "v2"), buf
        elif roll < 0.55:
            kind, out = "truncated", buf[: rng.randrange(1, max(2, len(buf)))]
        elif roll < 0.65:
            kind, out = "bad_crc", buf[:-2] + bytes([buf[-2] ^ 0xFF, buf[-1] ^ 0x5A])
        elif roll < 0.72:
            kind = "bad_length"
            out = buf[:1] + bytes([rng.randrange(256)]) + buf[2:]
        elif roll < 0.82:
            kind, data = "flipped", bytearray(buf)
            for _ in range(rng.randint(1, 4)):
                data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
            out = bytes(data)
        elif roll < 0.9:
            kind = "several"
            out = buf + b"".join(self._packed_or_empty(self.message()) for _ in range(2))
        elif roll < 0.95:
            kind = "signed"  # incompat flag 1: a signature nobody can check
            out = (
                buf[:2]
                + bytes([buf[2] | 1])
                + buf[3:]
                + bytes(rng.randrange(256) for _ in range(13))
            )
        else:
            kind = "garbage"
            start = rng.choice((b"\xfd", b"\xfe", b""))
            out = start + bytes(rng.randrange(256) for _ in range(rng.randrange(0, 280)))
        self.kinds[kind] += 1
        return out
