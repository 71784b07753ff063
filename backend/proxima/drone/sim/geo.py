"""Local NED metres <-> latitude, longitude, altitude around the simulated vehicle's home.

A flat-Earth approximation (equirectangular, WGS-84 equatorial radius): exact enough
within the few kilometres a simulated multicopter flies. The home point is the local
origin.
"""

from __future__ import annotations

import math

EARTH_RADIUS_M = 6_378_137.0


def global_from_local(
    home: tuple[float, float, float], north: float, east: float, down: float
) -> tuple[float, float, float]:
    """Latitude, longitude (degrees) and altitude AMSL (m) of a local NED point."""
    lat0, lon0, alt0 = home
    lat = lat0 + math.degrees(north / EARTH_RADIUS_M)
    lon = lon0 + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
    return lat, lon, alt0 - down


def local_from_global(
    home: tuple[float, float, float], lat: float, lon: float
) -> tuple[float, float]:
    """North and east metres of (lat, lon) from home."""
    lat0, lon0, _ = home
    north = math.radians(lat - lat0) * EARTH_RADIUS_M
    east = math.radians(lon - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
    return north, east
