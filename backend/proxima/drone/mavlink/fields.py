"""Reading MAVLink fields that nobody vouches for.

Every field of every message is untrusted on both sides of the link: a float may be NaN
or infinite, an enum may be out of range, an integer may not be integral. MAVLink gives
NaN a meaning in float params ("use the default / keep the current value") and
INT32_MAX in integer ones (COMMAND_INT x, y); nothing gives infinity a meaning. These
helpers turn a raw field into a value or None (refuse the message), so that no handler
ever calls `int()` on a NaN.
"""

from __future__ import annotations

import math

INT32_MAX = 2**31 - 1  # "unset" in COMMAND_INT's x and y


def finite(*values: float) -> bool:
    """Whether every value is a finite number."""
    return all(isinstance(v, int | float) and math.isfinite(v) for v in values)


def or_default(value: float, default: float) -> float | None:
    """A float param where NaN means "default": the value, `default` for NaN, None for
    infinity (refuse)."""
    if math.isnan(value):
        return default
    return value if math.isfinite(value) else None


def mav_bool(value: float, nan: bool | None = None) -> bool | None:
    """A MAV_BOOL param: exactly 0 or 1 ("values not equal to 0 or 1 are invalid");
    NaN reads as `nan` (None: refuse)."""
    if math.isnan(value):
        return nan
    if value == 0.0:
        return False
    if value == 1.0:
        return True
    return None


def integer(value: float, lo: int, hi: int, nan: int | None = None) -> int | None:
    """An integral float param within [lo, hi]; NaN reads as `nan` (None: refuse)."""
    if math.isnan(value):
        return nan
    if not math.isfinite(value) or value != int(value):
        return None
    n = int(value)
    return n if lo <= n <= hi else None


def degrees_e7(value: int) -> float:
    """A COMMAND_INT / *_INT latitude or longitude in 1e-7 degrees as degrees; NaN for
    INT32_MAX (unset)."""
    return math.nan if value == INT32_MAX else value / 1e7


def valid_lat_lon(lat: float, lon: float) -> bool:
    """Whether (lat, lon) is a place on Earth."""
    return finite(lat, lon) and -90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0


def text(raw: bytes | str, limit: int) -> str:
    """A fixed-size char field (param ids, STATUSTEXT) as text: up to the first NUL,
    at most `limit` characters, undecodable bytes replaced."""
    if isinstance(raw, bytes):
        raw = raw.split(b"\0", 1)[0].decode("utf-8", errors="replace")
    return raw.split("\0", 1)[0][:limit]
