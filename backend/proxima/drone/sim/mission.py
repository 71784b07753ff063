"""The MAVLink mission protocol of the simulated vehicle: upload, download and clear of
missions, geofence items and rally points (one store per MAV_MISSION_TYPE).

Items are checked as they arrive (frame, command for the mission type, finite params,
positions on Earth) and a bad one ends the upload with the MAV_MISSION_RESULT that names
it; a good upload replaces the stored list in one piece. Missions are stored, not flown:
the vehicle reads a stored landing sequence (MAV_CMD_DO_LAND_START ... NAV_LAND) for
DO_LAND_START, nothing else. On ArduPilot item 0 of a mission is the home position, as
ArduPilot reports it. MISSION_ITEM_INT with `current` 2 is ArduPilot's guided "fly to".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from proxima.drone.mavlink.fields import INT32_MAX, finite
from proxima.drone.mavlink.protocol import mav

if TYPE_CHECKING:
    from proxima.drone.sim.vehicle import Vehicle

MISSION, FENCE, RALLY = (
    mav.MAV_MISSION_TYPE_MISSION,
    mav.MAV_MISSION_TYPE_FENCE,
    mav.MAV_MISSION_TYPE_RALLY,
)
CAPACITY = {MISSION: 500, FENCE: 100, RALLY: 20}
GLOBAL_FRAMES = frozenset(
    {
        mav.MAV_FRAME_GLOBAL,
        mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        mav.MAV_FRAME_GLOBAL_INT,
        mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        mav.MAV_FRAME_GLOBAL_TERRAIN_ALT,
        mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
    }
)
FENCE_COMMANDS = frozenset(range(mav.MAV_CMD_NAV_FENCE_RETURN_POINT, 5005))  # 5000..5004
RALLY_COMMANDS = frozenset({mav.MAV_CMD_NAV_RALLY_POINT})
UPLOAD_RETRY_S = 1.0  # re-request an item after this long without it ...
UPLOAD_RETRIES = 5  # ... this many times, then give the upload up
_INVALID_PARAM = (
    mav.MAV_MISSION_INVALID_PARAM1,
    mav.MAV_MISSION_INVALID_PARAM2,
    mav.MAV_MISSION_INVALID_PARAM3,
    mav.MAV_MISSION_INVALID_PARAM4,
)


@dataclass(frozen=True)
class MissionItem:
    """One item as MISSION_ITEM_INT carries it: x, y are 1e-7 degrees in global frames,
    metres x 1e4 in local ones."""

    seq: int
    frame: int
    command: int
    current: int
    autocontinue: int
    params: tuple[float, float, float, float]
    x: int
    y: int
    z: float

    @property
    def global_frame(self) -> bool:
        return self.frame in GLOBAL_FRAMES


def check_item(item: MissionItem, mission_type: int) -> int:
    """MAV_MISSION_ACCEPTED, or the MAV_MISSION_RESULT that names what is wrong."""
    if item.frame not in mav.enums["MAV_FRAME"]:
        return mav.MAV_MISSION_UNSUPPORTED_FRAME
    known = item.command in mav.enums["MAV_CMD"]
    if mission_type == FENCE:
        allowed = item.command in FENCE_COMMANDS
    elif mission_type == RALLY:
        allowed = item.command in RALLY_COMMANDS
    else:
        allowed = known and item.command not in FENCE_COMMANDS | RALLY_COMMANDS
    if not allowed:
        return mav.MAV_MISSION_UNSUPPORTED
    for i, p in enumerate(item.params):
        if math.isinf(p):  # NaN is MAVLink's "default"; infinity means nothing
            return _INVALID_PARAM[i]
    positional = item.frame != mav.MAV_FRAME_MISSION
    if math.isinf(item.z) or (positional and math.isnan(item.z)):
        return mav.MAV_MISSION_INVALID_PARAM7
    if item.global_frame:
        if not -900_000_000 <= item.x <= 900_000_000:
            return mav.MAV_MISSION_INVALID_PARAM5_X
        if not -1_800_000_000 <= item.y <= 1_800_000_000:
            return mav.MAV_MISSION_INVALID_PARAM6_Y
    return mav.MAV_MISSION_ACCEPTED


@dataclass
class MissionStore:
    """The stored lists by mission type and the current mission item."""

    lists: dict[int, list[MissionItem]] = field(
        default_factory=lambda: {MISSION: [], FENCE: [], RALLY: []}
    )
    current: int = 0

    def landing_sequence(self) -> MissionItem | None:
        """The NAV_LAND after the mission's first DO_LAND_START, if there is one."""
        items = self.lists[MISSION]
        starts = [i for i, it in enumerate(items) if it.command == mav.MAV_CMD_DO_LAND_START]
        if not starts:
            return None
        for it in items[starts[0] + 1 :]:
            if it.command == mav.MAV_CMD_NAV_LAND:
                return it
        return None


@dataclass
class _Upload:
    mission_type: int
    count: int
    peer: tuple[int, int]
    items: list[MissionItem] = field(default_factory=list)
    asked_at: float = 0.0
    asks: int = 0


def _item_from_int(msg: Any) -> MissionItem:
    params = (msg.param1, msg.param2, msg.param3, msg.param4)
    return MissionItem(
        msg.seq, msg.frame, msg.command, msg.current, msg.autocontinue, params, msg.x, msg.y, msg.z
    )


def _item_from_float(msg: Any) -> MissionItem:
    """A legacy MISSION_ITEM (x, y as floats) in MISSION_ITEM_INT's units."""
    scale = 1e7 if msg.frame in GLOBAL_FRAMES else 1e4
    x = round(msg.x * scale) if finite(msg.x) and abs(msg.x * scale) < INT32_MAX else INT32_MAX
    y = round(msg.y * scale) if finite(msg.y) and abs(msg.y * scale) < INT32_MAX else INT32_MAX
    params = (msg.param1, msg.param2, msg.param3, msg.param4)
    return MissionItem(
        msg.seq, msg.frame, msg.command, msg.current, msg.autocontinue, params, x, y, msg.z
    )


class MissionService:
    """The mission protocol on the server's encoder `m` for `vehicle`; `clock()` is
    monotonic seconds (for the upload's re-requests)."""

    def __init__(self, vehicle: Vehicle, m: Any, clock: Callable[[], float]) -> None:
        self.vehicle = vehicle
        self.store = vehicle.missions
        self.m = m
        self.clock = clock
        self.upload: _Upload | None = None
        self.messages: dict[str, Callable[[Any], None]] = {
            "MISSION_COUNT": self._count,
            "MISSION_ITEM_INT": lambda msg: self._item(msg, _item_from_int(msg)),
            "MISSION_ITEM": lambda msg: self._item(msg, _item_from_float(msg)),
            "MISSION_REQUEST_LIST": self._request_list,
            "MISSION_REQUEST_INT": lambda msg: self._request(msg, as_int=True),
            "MISSION_REQUEST": lambda msg: self._request(msg, as_int=False),
            "MISSION_CLEAR_ALL": self._clear_all,
            "MISSION_SET_CURRENT": self._set_current,
        }

    # --- upload -------------------------------------------------------------------------
    def _count(self, msg: Any) -> None:
        kind, peer = msg.mission_type, _peer(msg)
        if kind not in CAPACITY:
            self._ack(peer, mav.MAV_MISSION_UNSUPPORTED, kind)
            return
        if msg.count > CAPACITY[kind]:
            self._ack(peer, mav.MAV_MISSION_NO_SPACE, kind)
            return
        self.upload = None
        if msg.count == 0:
            self.store.lists[kind] = []
            self._ack(peer, mav.MAV_MISSION_ACCEPTED, kind)
            return
        self.upload = _Upload(kind, msg.count, peer)
        self._ask()

    def _item(self, msg: Any, item: MissionItem) -> None:
        peer, kind = _peer(msg), msg.mission_type
        if item.current == 2 and kind == MISSION and self.upload is None:
            self._guided_item(peer, item)
            return
        up = self.upload
        if up is None or peer != up.peer or kind != up.mission_type:
            return  # not part of an upload in progress: nothing asked for it
        if item.seq != len(up.items):
            if item.seq < len(up.items):
                self._ask()  # a duplicate: ask again for the one we need
            return
        result = check_item(item, kind)
        if result != mav.MAV_MISSION_ACCEPTED:
            self.upload = None
            self._ack(peer, result, kind)
            return
        up.items.append(item)
        if len(up.items) < up.count:
            self._ask()
            return
        self.store.lists[kind] = up.items
        if kind == MISSION:
            self.store.current = 0
        self.upload = None
        self._ack(peer, mav.MAV_MISSION_ACCEPTED, kind)
        self.vehicle.statustext(f"Mission type {kind}: {len(up.items)} items stored")

    def _guided_item(self, peer: tuple[int, int], item: MissionItem) -> None:
        """ArduPilot's guided "fly to" (MISSION_ITEM_INT current=2)."""
        result = mav.MAV_MISSION_UNSUPPORTED
        if self.vehicle.fw.guided_mission_item:
            lat, lon = item.x / 1e7, item.y / 1e7
            relative = item.frame in (
                mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            )
            ok = item.global_frame and check_item(item, MISSION) == mav.MAV_MISSION_ACCEPTED
            done = ok and self.vehicle.fly_to_global(lat, lon, item.z, relative, change_mode=False)
            result = mav.MAV_MISSION_ACCEPTED if done else mav.MAV_MISSION_ERROR
        self._ack(peer, result, MISSION)

    def tick(self, now: float) -> None:
        """Re-request an upload's missing item; give the upload up after its retries."""
        up = self.upload
        if up is None or now - up.asked_at < UPLOAD_RETRY_S:
            return
        if up.asks > UPLOAD_RETRIES:
            self.upload = None
            self._ack(up.peer, mav.MAV_MISSION_OPERATION_CANCELLED, up.mission_type)
            return
        self._ask()

    def _ask(self) -> None:
        up = self.upload
        assert up is not None
        up.asked_at, up.asks = self.clock(), up.asks + 1
        self.m.mission_request_int_send(*up.peer, len(up.items), up.mission_type)

    # --- download, clear ----------------------------------------------------------------
    def _items(self, kind: int) -> list[MissionItem]:
        items = list(self.store.lists[kind])
        if kind == MISSION and self.vehicle.fw.mission_home_item:
            lat, lon, alt = self.vehicle.cfg.home
            home = MissionItem(
                0,
                mav.MAV_FRAME_GLOBAL_INT,
                mav.MAV_CMD_NAV_WAYPOINT,
                0,
                1,
                (0.0, 0.0, 0.0, 0.0),
                round(lat * 1e7),
                round(lon * 1e7),
                alt,
            )
            items = [home, *items[1:]]
        return items

    def _request_list(self, msg: Any) -> None:
        kind, peer = msg.mission_type, _peer(msg)
        if kind not in CAPACITY:
            self._ack(peer, mav.MAV_MISSION_UNSUPPORTED, kind)
            return
        self.m.mission_count_send(*peer, len(self._items(kind)), kind)

    def _request(self, msg: Any, as_int: bool) -> None:
        kind, peer = msg.mission_type, _peer(msg)
        if kind not in CAPACITY:
            self._ack(peer, mav.MAV_MISSION_UNSUPPORTED, kind)
            return
        items = self._items(kind)
        if not 0 <= msg.seq < len(items):
            self._ack(peer, mav.MAV_MISSION_INVALID_SEQUENCE, kind)
            return
        it = items[msg.seq]
        current = int(kind == MISSION and it.seq == self.store.current)
        if as_int:
            self.m.mission_item_int_send(
                *peer, it.seq, it.frame, it.command, current, it.autocontinue, *it.params,
                it.x, it.y, it.z, kind,
            )  # fmt: skip
        else:
            scale = 1e7 if it.global_frame else 1e4
            self.m.mission_item_send(
                *peer, it.seq, it.frame, it.command, current, it.autocontinue, *it.params,
                it.x / scale, it.y / scale, it.z, kind,
            )  # fmt: skip

    def _clear_all(self, msg: Any) -> None:
        kind, peer = msg.mission_type, _peer(msg)
        if kind == mav.MAV_MISSION_TYPE_ALL:
            for k in CAPACITY:
                self.store.lists[k] = []
        elif kind in CAPACITY:
            self.store.lists[kind] = []
        else:
            self._ack(peer, mav.MAV_MISSION_UNSUPPORTED, kind)
            return
        if kind in (MISSION, mav.MAV_MISSION_TYPE_ALL):
            self.store.current = 0
        self._ack(peer, mav.MAV_MISSION_ACCEPTED, kind)

    def _set_current(self, msg: Any) -> None:
        if 0 <= msg.seq < max(len(self._items(MISSION)), 1):
            self.store.current = msg.seq
        self.m.mission_current_send(self.store.current, len(self._items(MISSION)))

    def _ack(self, peer: tuple[int, int], result: int, kind: int) -> None:
        self.m.mission_ack_send(*peer, result, kind & 0xFF)


def _peer(msg: Any) -> tuple[int, int]:
    return msg.get_srcSystem(), msg.get_srcComponent()
