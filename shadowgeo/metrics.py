"""Planning metrics of sunlight, each stated as the rule it follows.

Every metric here is computed from exact shadows (:mod:`shadowgeo.sunlight_surfaces`)
at sun samples: a sample stands for ``step`` of time around it, and a point
sunlit at a sample gets that ``step`` of sun. The only approximation is that
sampling; the shadow at each sample is exact.

- :func:`bre_amenity`: BRE, *Site layout planning for daylight and sunlight*
  (BR 209, third edition 2022, section 3.3): an amenity area (a garden, a
  park) appears adequately sunlit through the year when at least half of its
  area can receive at least two hours of sunlight on 21 March.
- :func:`en17037_exposure`: EN 17037:2018 *Daylight in buildings*, clause 5.3
  and Annex A: sunlight exposure of a room is the number of hours of direct
  sun on a reference point on the inside of a window (its centre of width,
  at least 1.2 m above the floor and 0.3 m above the sill) on one chosen day
  between 1 February and 21 March, counting only while the sun is above a
  minimum elevation set for the site; minimum 1.5 h, medium 3 h, high 4 h.
- :func:`longest_sunlit`: the longest run of consecutive sunlit samples at
  each point (consecutive: exactly ``step`` apart), in hours.
- :func:`shadow_hours_by_owner`: how long each building's surfaces are in
  shadow (defined there).
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import plane2d as poly
from .errors import GeometryError
from .sun import frame, hourly, sun_position
from .sunlight_surfaces import SurfaceSunlight, surface_sun_study
from .tolerance import Tolerance
from .topology import MeshLike, as_caster

__all__ = [
    "AmenityCheck",
    "EN17037_LEVELS",
    "EN17037_MIN_ELEVATION",
    "OwnerShadow",
    "WindowExposure",
    "bre_amenity",
    "day_times",
    "en17037_exposure",
    "en17037_level",
    "longest_sunlit",
    "polygon_mesh",
    "shadow_hours_by_owner",
]

# EN 17037's levels of sunlight exposure: hours of sun on the chosen day.
EN17037_LEVELS = (("high", 4.0), ("medium", 3.0), ("minimum", 1.5))

# The default minimum sun elevation, in degrees, below which EN 17037 counts
# no sun. The standard sets the value by site (its Annex A tabulates it for
# European capitals, rising with latitude); give the site's own value.
EN17037_MIN_ELEVATION = 10.0


@dataclass(frozen=True)
class AmenityCheck:
    """BRE's two-hours-on-21-March test of an amenity area.

    fraction : float
        Share of the area that receives at least ``hours`` of sun.
    hours : float
        The sunlight asked for (2 h).
    share : float
        The share of the area that must have it (0.5).
    sunlight : SurfaceSunlight
        The study behind it (the area as a triangle mesh, its levels).
    """

    fraction: float
    hours: float
    share: float
    sunlight: SurfaceSunlight

    @property
    def passes(self) -> bool:
        """At least ``share`` of the area has at least ``hours`` of sun."""
        return self.fraction >= self.share


@dataclass(frozen=True)
class WindowExposure:
    """EN 17037's sunlight exposure at one window point.

    hours : float
        Hours of sun on the day, the sun above ``min_elevation``.
    level : str
        ``"high"`` (>= 4 h), ``"medium"`` (>= 3 h), ``"minimum"`` (>= 1.5 h)
        or ``"none"``.
    longest : float
        The longest continuous sunlit period, hours.
    times : tuple of datetime
        The samples counted (the sun above ``min_elevation``).
    sunlit : (s,) bool
        Whether the point has sun at each of ``times``.
    min_elevation : float
        Degrees.
    """

    hours: float
    level: str
    longest: float
    times: tuple[_dt.datetime, ...]
    sunlit: NDArray[np.bool_]
    min_elevation: float


@dataclass(frozen=True)
class OwnerShadow:
    """Shadow durations of each owner's faces (a building's walls and roofs).

    owners : (k,) int64
        The owners, rising.
    cast_hours : (k,) float64
        Area-weighted mean hours the owner's faces lie in a cast shadow while
        they face the sun (another building's, or the owner's own other parts).
    turned_hours : (k,) float64
        Area-weighted mean hours the owner's faces are turned away from the
        sun while it is up (self-shadow of the face).
    sun_hours : float
        Hours the sun is up over the samples.
    """

    owners: NDArray[np.int64]
    cast_hours: NDArray[np.float64]
    turned_hours: NDArray[np.float64]
    sun_hours: float

    @property
    def shaded_hours(self) -> NDArray[np.float64]:
        """(k,) mean hours without sun, cast shadow and turned away together."""
        total: NDArray[np.float64] = self.cast_hours + self.turned_hours
        return total


def day_times(
    day: _dt.date, longitude: float, step: _dt.timedelta, tz: _dt.tzinfo | None = None
) -> list[_dt.datetime]:
    """Sample times over ``day`` every ``step`` (each the middle of its
    interval), the day taken in ``tz``, by default the site's mean solar
    time (UTC shifted by ``longitude / 15`` hours: the day is centred on
    the sun's transit, whatever the time zone)."""
    zone = tz or _dt.timezone(_dt.timedelta(hours=longitude / 15.0))
    start = _dt.datetime(day.year, day.month, day.day, tzinfo=zone)
    return hourly(start, start + _dt.timedelta(days=1), step)


def polygon_mesh(
    polygon: ArrayLike, up: str = "Y"
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A planar (n, 3) polygon (convex or not) as (vertices, faces)
    triangles. Its front is given by its winding (counter-clockwise seen
    from the front); a polygon facing down (away from ``up``) is turned to
    face up, as an amenity area on the ground receives from the sky."""
    points = np.asarray(polygon, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 3:
        raise GeometryError(f"a polygon must be (n >= 3, 3) points, got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise GeometryError("the polygon has NaN or infinite coordinates")
    # Newell's normal: the polygon's area vector
    following = np.roll(points, -1, axis=0)
    normal = 0.5 * np.cross(points, following).sum(axis=0)
    length = float(np.linalg.norm(normal))
    if not length > 0:
        raise GeometryError("the polygon has no area")
    unit = normal / length
    if unit @ frame(up)[2] < 0:
        points, unit = points[::-1], -unit
    helper = np.eye(3)[int(np.argmin(np.abs(unit)))]
    u = np.cross(helper, unit)
    u /= np.linalg.norm(u)
    v = np.cross(unit, u)
    centre = points.mean(axis=0)
    flat = np.column_stack([(points - centre) @ u, (points - centre) @ v])
    extent = float(np.abs(flat).max())
    scale = poly.local_scale(2.0 * extent)
    corners, faces = poly.triangulate_parts([[flat * scale]])
    corners = corners / scale
    vertices = centre + corners[:, :1] * u + corners[:, 1:] * v
    return vertices, np.asarray(faces, dtype=np.int64)


def bre_amenity(
    casters: MeshLike | Sequence[MeshLike],
    area: ArrayLike,
    *,
    latitude: float,
    longitude: float,
    year: int,
    day: _dt.date | None = None,
    hours: float = 2.0,
    share: float = 0.5,
    step: _dt.timedelta | None = None,
    tz: _dt.tzinfo | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
) -> AmenityCheck:
    """BRE's test of an amenity area (BR 209, 2022, section 3.3.17): at
    least half of it should receive at least two hours of sunlight on
    21 March.

    Parameters
    ----------
    casters : mesh or list of meshes
        Everything that may shade the area.
    area : (n, 3) array_like
        The amenity area: a planar polygon of any orientation (a garden, a
        terrace, a roof garden, a balcony's floor), see :func:`polygon_mesh`.
    latitude, longitude : float
        The site, degrees.
    year : int
        The year of the 21 March (the sun's path shifts little from year to year).
    day : date
        Another day instead of 21 March.
    hours, share : float
        BRE's two hours over half of the area.
    step : timedelta
        Sample spacing, 10 minutes by default.
    tz : tzinfo
        The day's time zone, by default the site's mean solar time.
    up, north
        The scene's frame, as in :func:`shadowgeo.sun.frame`.

    Returns
    -------
    AmenityCheck
        The share of the area with at least ``hours`` (exact polygons of the
        sampled sunlight) and whether it passes.
    """
    step = step or _dt.timedelta(minutes=10)
    when = day or _dt.date(year, 3, 21)
    mesh = polygon_mesh(area, up)
    times = day_times(when, longitude, step, tz)
    study = surface_sun_study(
        casters, mesh, times, latitude=latitude, longitude=longitude, step=step, up=up, north=north
    )
    met = float(study.area_with_at_least(hours).sum())
    total = float(study.face_areas.sum())
    return AmenityCheck(met / total if total > 0 else 0.0, hours, share, study)


def en17037_level(hours: float) -> str:
    """EN 17037's level of a sunlight exposure of ``hours`` (see the module notes).

    >>> [en17037_level(hours) for hours in (1.0, 1.5, 3.25, 4.0)]
    ['none', 'minimum', 'medium', 'high']
    """
    for name, least in EN17037_LEVELS:
        if hours >= least or math.isclose(hours, least):
            return name
    return "none"


def en17037_exposure(
    casters: MeshLike | Sequence[MeshLike],
    point: ArrayLike,
    normal: ArrayLike,
    day: _dt.date,
    *,
    latitude: float,
    longitude: float,
    min_elevation: float = EN17037_MIN_ELEVATION,
    step: _dt.timedelta | None = None,
    tz: _dt.tzinfo | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
) -> WindowExposure:
    """EN 17037's sunlight exposure at a window's reference point.

    Parameters
    ----------
    casters : mesh or list of meshes
        The building itself (its walls, reveals, balconies) and its
        surroundings.
    point : (3,) array_like
        The reference point (EN 17037: on the inner surface of the window,
        centre of its width, at least 1.2 m above the floor and 0.3 m above
        the sill).
    normal : (3,) array_like
        The window's outward normal: the sun counts only in front of it.
    day : date
        A day between 1 February and 21 March (EN 17037 leaves the choice to
        the national annex; not checked here).
    latitude, longitude : float
    min_elevation : float
        Degrees; sun below it is not counted. EN 17037 gives it by site
        (:data:`EN17037_MIN_ELEVATION` is only a default: give the site's).
    step : timedelta
        Sample spacing, 5 minutes by default.
    tz, up, north
        As in :func:`bre_amenity`.

    Returns
    -------
    WindowExposure
    """
    step = step or _dt.timedelta(minutes=5)
    where = np.asarray(point, dtype=np.float64).reshape(3)
    facing = np.asarray(normal, dtype=np.float64).reshape(3)
    if not (np.all(np.isfinite(where)) and np.all(np.isfinite(facing))):
        raise GeometryError("the window's point and normal must be finite")
    times = [
        when
        for when in day_times(day, longitude, step, tz)
        if sun_position(latitude, longitude, when)[1] >= min_elevation
    ]
    patch = _point_patch(casters, where, facing)
    study = surface_sun_study(
        casters,
        patch,
        times,
        latitude=latitude,
        longitude=longitude,
        step=step,
        up=up,
        north=north,
        levels=False,
    )
    sunlit = study.sunlit(where[None], [0])[:, 0]
    hours = float(sunlit.sum()) * study.hours_per_sample
    longest = float(longest_sunlit(sunlit[:, None], study.times, step)[0])
    return WindowExposure(
        hours, en17037_level(hours), longest, study.times, sunlit, float(min_elevation)
    )


def _point_patch(
    casters: MeshLike | Sequence[MeshLike], point: NDArray[np.float64], normal: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A triangle around ``point`` facing ``normal``, of the size below which
    a receiver point still counts as on its plane (the tolerance's coplanar
    length): the exact shadow on it gives the point's."""
    length = float(np.linalg.norm(normal))
    if not length > 0:
        raise GeometryError("the window's normal is zero")
    unit = normal / length
    items: list[MeshLike] = list(casters) if isinstance(casters, list) else [casters]  # type: ignore[list-item]
    bounds = [as_caster(item).bounds for item in items]
    radius = Tolerance.for_points(point[None], *bounds).coplanar_length
    helper = np.eye(3)[int(np.argmin(np.abs(unit)))]
    u = np.cross(helper, unit)
    u /= np.linalg.norm(u)
    v = np.cross(unit, u)
    angles = np.radians([90.0, 210.0, 330.0])
    corners = point + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    return corners, np.array([[0, 1, 2]], dtype=np.int64)


def longest_sunlit(
    sunlit: ArrayLike, times: Sequence[_dt.datetime], step: _dt.timedelta
) -> NDArray[np.float64]:
    """(n,) the longest continuous sunlit period at each point, in hours.

    ``sunlit`` (s, n) bool: whether each point has sun at each of ``times``
    (rising); a run of sunlit samples each ``step`` after the one before is
    continuous and lasts its count times ``step``. A gap in the samples (the
    night, samples dropped below a minimum elevation) ends a run.

    Examples
    --------
    >>> import datetime as dt
    >>> step = dt.timedelta(hours=1)
    >>> times = [dt.datetime(2026, 3, 21, h, 30, tzinfo=dt.UTC) for h in (8, 9, 10, 13, 14)]
    >>> longest_sunlit([[1], [1], [0], [1], [1]], times, step).tolist()
    [2.0]
    """
    lit = np.asarray(sunlit, dtype=bool)
    if lit.ndim != 2 or lit.shape[0] != len(times):
        raise GeometryError(f"sunlit must be (samples, points) with {len(times)} samples")
    run = np.zeros(lit.shape[1], dtype=np.int64)
    best = np.zeros(lit.shape[1], dtype=np.int64)
    for index in range(len(times)):
        following = index > 0 and times[index] - times[index - 1] == step
        run = np.where(lit[index], (run if following else 0) + 1, 0)
        best = np.maximum(best, run)
    hours: NDArray[np.float64] = best.astype(np.float64) * (step.total_seconds() / 3600.0)
    return hours


def shadow_hours_by_owner(sunlight: SurfaceSunlight, owner: ArrayLike) -> OwnerShadow:
    """Shadow duration per building: for each owner (``owner`` (m,) gives
    each receiver face's building), the area-weighted mean over its faces of
    the hours each point spends in cast shadow while its face turns to the
    sun, and of the hours its face is turned away from the sun (the sun up).
    Exact from each sample's shadowed areas (no levels needed)."""
    owners = np.asarray(owner, dtype=np.int64).reshape(-1)
    if len(owners) != len(sunlight.faces):
        raise GeometryError(f"{len(owners)} owners for {len(sunlight.faces)} faces")
    areas = sunlight.face_areas
    cast = np.zeros(len(owners))
    turned = np.zeros(len(owners))
    for sample in sunlight.shadows:
        cast += np.where(sample.dark, 0.0, sample.fraction)
        turned += sample.dark
    kept, slot = np.unique(owners, return_inverse=True)
    weight = np.bincount(slot, weights=areas, minlength=len(kept))
    per_hour = sunlight.hours_per_sample

    def mean(values: NDArray[np.float64]) -> NDArray[np.float64]:
        summed = np.bincount(slot, weights=values * areas, minlength=len(kept))
        result: NDArray[np.float64] = (
            np.divide(summed, weight, out=np.zeros_like(summed), where=weight > 0) * per_hour
        )
        return result

    return OwnerShadow(kept, mean(cast), mean(turned), len(sunlight.shadows) * per_hour)
