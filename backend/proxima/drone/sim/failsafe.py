"""The simulated vehicle's failsafes in flight: geofence, battery and ground-station loss,
each configured by the autopilot's own parameters (`param_sets`) and each triggered
once per event (a breach, a battery level, a silence), as ArduPilot and PX4 do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from proxima.drone.mavlink.protocol import mav

if TYPE_CHECKING:
    from proxima.drone.sim.vehicle import Vehicle

_BATTERY_SEVERITY = {"low": 1, "critical": 2, "emergency": 3}
_RETURNING = frozenset({"RTL", "LAND"})


@dataclass
class FailsafeState:
    """What has already been triggered in this flight."""

    battery_level: str | None = None
    fence_breached: bool = False
    gcs_lost: bool = False


def check(v: Vehicle, now: float) -> None:
    """Run the failsafe checks of a flying vehicle."""
    _fence(v)
    _battery(v)
    _gcs(v, now)


def rtl_altitude(v: Vehicle) -> float:
    """The RTL altitude, kept below an active fence ceiling (as ArduCopter does)."""
    alt = v.limits.rtl_alt
    fence = v.fw.params.fence(v.params)
    if fence is not None and fence.alt_max is not None:
        alt = min(alt, fence.alt_max - 1.0)
    return max(alt, 1.0)


def _fence(v: Vehicle) -> None:
    fence = v.fw.params.fence(v.params)
    if fence is None:
        v.failsafes.fence_breached = False
        return
    out = fence.radius is not None and math.hypot(v.pos[0], v.pos[1]) > fence.radius
    out = out or (fence.alt_max is not None and v.altitude() > fence.alt_max)
    if out and not v.failsafes.fence_breached:
        v.failsafes.fence_breached = True
        v.statustext(f"Fence breach: {fence.action}", mav.MAV_SEVERITY_CRITICAL)
        if v.mode not in _RETURNING:
            v.act(fence.action)
    elif not out:
        v.failsafes.fence_breached = False


def _battery(v: Vehicle) -> None:
    level = v.fw.params.battery(v.params, v.battery, v.battery_voltage())
    if level is None:
        return
    name, action = level
    was = v.failsafes.battery_level
    if was is not None and _BATTERY_SEVERITY[name] <= _BATTERY_SEVERITY[was]:
        return
    v.failsafes.battery_level = name
    v.statustext(f"Battery {name}: {action}", mav.MAV_SEVERITY_CRITICAL)
    if action == "land" and v.mode == "LAND":
        return
    v.act(action)


def _gcs(v: Vehicle, now: float) -> None:
    rule = v.fw.params.gcs_loss(v.params)
    heard = v.gcs_heard_at
    if rule is None or heard is None or v.failsafes.gcs_lost or now - heard <= rule.timeout:
        return
    v.failsafes.gcs_lost = True
    v.statustext(f"GCS lost: {rule.action}", mav.MAV_SEVERITY_CRITICAL)
    if v.mode not in _RETURNING:
        v.act(rule.action)
