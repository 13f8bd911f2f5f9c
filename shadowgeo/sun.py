"""Where the sun is: its direction in a scene's frame for a place and a time.

The astronomy is astral's (``pip install "shadowgeo[sun]"``), a maintained
library accurate to about 0.01 degree for centuries around today, with
atmospheric refraction, which is what a shadow on the ground sees. This module
only turns its azimuth and elevation into a direction in the scene's frame.

The scene's frame: ``up`` is the scene's up axis (``"Y"`` for X3D and glTF,
``"Z"`` for USD or CAD scenes) and ``north`` the horizontal direction that
points north; east is ``north x up``. The defaults (Y up, north along -Z, so
east is +X) are the usual ones for a Y-up map: looking down the -Y axis, north
is at the top of the screen.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError
from .lights import DirectionalLight

__all__ = ["days", "frame", "hourly", "sun_direction", "sun_lights", "sun_position"]

_UP = {"Y": np.array([0.0, 1.0, 0.0]), "Z": np.array([0.0, 0.0, 1.0])}
_NORTH = {"Y": np.array([0.0, 0.0, -1.0]), "Z": np.array([0.0, 1.0, 0.0])}


def _astral() -> tuple[Any, Callable[..., float], Callable[..., float]]:
    try:
        from astral import Observer
        from astral.sun import azimuth, elevation
    except ImportError:
        raise ImportError('sun positions need astral: pip install "shadowgeo[sun]"') from None
    return Observer, azimuth, elevation


def frame(
    up: str = "Y", north: ArrayLike | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Unit (east, north, up) vectors of a scene whose up axis is ``up``.

    ``north`` defaults to -Z for a Y-up scene and +Y for a Z-up scene; any
    other horizontal direction may be given (it is made orthogonal to up).
    """
    key = up.upper()
    if key not in _UP:
        raise GeometryError(f"up must be 'Y' or 'Z', got {up!r}")
    up_vector = _UP[key]
    north_vector = _NORTH[key] if north is None else np.asarray(north, dtype=np.float64)
    if north_vector.shape != (3,) or not np.all(np.isfinite(north_vector)):
        raise GeometryError(f"north must be a finite 3-vector, got {north!r}")
    north_vector = north_vector - np.dot(north_vector, up_vector) * up_vector
    length = float(np.linalg.norm(north_vector))
    if length == 0.0:
        raise GeometryError(f"north {north!r} is parallel to the up axis")
    north_vector = north_vector / length
    east = np.cross(north_vector, up_vector)
    return east, north_vector, up_vector


def _utc(when: _dt.datetime) -> _dt.datetime:
    if when.tzinfo is None:
        raise GeometryError(
            f"time {when.isoformat()} has no time zone: give an aware datetime "
            "(datetime.timezone.utc or zoneinfo.ZoneInfo(...))"
        )
    return when.astimezone(_dt.UTC)


def sun_position(latitude: float, longitude: float, when: _dt.datetime) -> tuple[float, float]:
    """The sun's (azimuth, elevation) in degrees: azimuth clockwise from north,
    elevation above the horizon with refraction (negative below it).

    Examples
    --------
    >>> import datetime as dt
    >>> azimuth, elevation = sun_position(0.0, 0.0, dt.datetime(2026, 3, 20, 12, 7, tzinfo=dt.UTC))
    >>> round(elevation)  # the sun overhead at the equator near an equinox noon
    90
    """
    if not (-90.0 <= latitude <= 90.0) or not (-180.0 <= longitude <= 180.0):
        raise GeometryError(
            f"latitude {latitude} must be in [-90, 90] and longitude {longitude} in [-180, 180]"
        )
    observer_type, azimuth, elevation = _astral()
    observer = observer_type(latitude=latitude, longitude=longitude)
    moment = _utc(when)
    return float(azimuth(observer, moment)), float(elevation(observer, moment))


def sun_direction(
    latitude: float,
    longitude: float,
    when: _dt.datetime,
    *,
    up: str = "Y",
    north: ArrayLike | None = None,
) -> NDArray[np.float64] | None:
    """The unit direction sunlight travels at ``when``, in the scene's frame,
    or None when the sun is below the horizon (it casts no shadow then).

    Examples
    --------
    >>> import datetime as dt
    >>> noon = dt.datetime(2026, 6, 21, 12, 0, tzinfo=dt.UTC)
    >>> direction = sun_direction(51.48, 0.0, noon)  # Greenwich, midsummer noon
    >>> round(math.degrees(math.asin(-direction[1])))  # 90 - 51.48 + 23.44 degrees high
    62
    >>> bool(direction[2] < 0)  # the sun is in the south: its light travels north, -Z
    True
    """
    azimuth, elevation = sun_position(latitude, longitude, when)
    if elevation <= 0.0:
        return None
    east, north_vector, up_vector = frame(up, north)
    az, el = math.radians(azimuth), math.radians(elevation)
    towards_sun = math.cos(el) * (math.sin(az) * east + math.cos(az) * north_vector)
    towards_sun = towards_sun + math.sin(el) * up_vector
    return -towards_sun / float(np.linalg.norm(towards_sun))


def sun_lights(
    latitude: float,
    longitude: float,
    times: Iterable[_dt.datetime],
    *,
    up: str = "Y",
    north: ArrayLike | None = None,
) -> tuple[list[_dt.datetime], list[DirectionalLight]]:
    """The times of ``times`` when the sun is up, and a DirectionalLight for each."""
    kept: list[_dt.datetime] = []
    lights: list[DirectionalLight] = []
    for when in times:
        direction = sun_direction(latitude, longitude, when, up=up, north=north)
        if direction is not None:
            kept.append(when)
            lights.append(DirectionalLight(direction))
    return kept, lights


def hourly(
    start: _dt.datetime, end: _dt.datetime, step: _dt.timedelta | None = None
) -> list[_dt.datetime]:
    """Times from ``start`` (inclusive) to ``end`` (exclusive) every ``step``
    (one hour by default), each the middle of its interval: a sample stands for
    the ``step`` around it."""
    step = step or _dt.timedelta(hours=1)
    if step <= _dt.timedelta(0):
        raise GeometryError(f"step must be positive, got {step}")
    times: list[_dt.datetime] = []
    when = _utc(start) + step / 2
    stop = _utc(end)
    while when < stop:
        times.append(when)
        when += step
    return times


def days(times: Sequence[_dt.datetime], tz: _dt.tzinfo | None = None) -> dict[_dt.date, list[int]]:
    """Indices of ``times`` grouped by calendar day in ``tz`` (UTC by default)."""
    groups: dict[_dt.date, list[int]] = {}
    zone = tz or _dt.UTC
    for index, when in enumerate(times):
        groups.setdefault(_utc(when).astimezone(zone).date(), []).append(index)
    return groups
