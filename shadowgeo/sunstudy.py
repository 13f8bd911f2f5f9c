"""Sun studies: how long each point of a region is in sunlight over a set of times.

A sun study takes casters, a receiving region on a plane and sample times; each
sample stands for ``step`` of time (an hour by default). For every sample with
the sun above the horizon it casts the exact shadow (:func:`project_shadow`
with a :class:`DirectionalLight` from :mod:`shadowgeo.sun`), and then returns
the region cut into exact polygons of equal sunlight duration.

How the level sets stay exact: the shadows are unions already (each a set of
non-overlapping counter-clockwise outer loops with clockwise holes), so the
number of samples shadowing a point is its winding number over all the
shadows' loops; :func:`shadowgeo.levels.cover_levels` cuts the region by that
number, exactly, one tile of a few thousand vertices at a time. The level
polygons come back cut along the tile edges.

The sun's disc: with ``sun_angle`` (its angular diameter, 0.53 degrees, in
radians) each sample's sun is a disc, replaced by ``sun_samples`` directions
spread evenly over it (:func:`shadowgeo.soft.light_samples`, as
:func:`~shadowgeo.soft_shadow` spreads a sun with a size), each casting its
exact shadow; a point's sunlight at a sample is the share of those directions
it sees, so durations near shadow edges become fractional (in steps of
``step / sun_samples``) and the levels are cut from all the directions'
shadows at once, still exact for them and still nested. Where a straight edge
crosses the disc the share is the circular segment's, to the samples' error
(see :data:`SUN_DISC_SAMPLES`). A sample counts when the sun's centre is
up, as without the disc; its directions under the horizon are dark. With
``sun_angle`` 0 (the default) the study is the point sun's, bit for bit.

Translucent casters (``opacity``, one value a caster face) count by their
opacity, as the converter's rule (:mod:`shadowgeo.scene.opacity`: opacity
``1 - Material.transparency`` in sixteenths; a point takes the darkness of the
most opaque caster hiding it): at a sample a point gets ``(1 - a) * step`` of
sun, ``a`` the largest opacity among the casters hiding it. The study adds
up one opaque study a distinct opacity, of the faces at least that opaque,
each shadow counted a whole number of times in the winding-number cover
(:mod:`shadowgeo.opacity`), so the levels stay exact, in steps of
``step / units`` (16 units at most, 2 for opacities 0.5 and 1). Every caster
opaque is the opaque study, bit for bit.

Studies over many days (a year of hourly samples) are cut into one study a day
(:func:`sun_study_by_day`); days are independent, so they run in parallel on
Dask when a scheduler is given, with results identical to the serial run.
"""

from __future__ import annotations

import datetime as _dt
import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from manifold3d import CrossSection
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError
from .levels import cover_level_areas, cover_levels
from .lights import DirectionalLight
from .limits import RELATIVE_ROUNDING
from .opacity import Layers, layers
from .parallel import each_day
from .plane import Plane
from .plane2d import components, local_scale, points_in_parts, signed_areas, unite
from .projection import project_shadow
from .soft import light_samples
from .sun import frame as sun_frame
from .sun import sun_lights
from .topology import Caster, as_caster

__all__ = [
    "DaySummary",
    "Polygons",
    "SUN_DISC_SAMPLES",
    "SunStudies",
    "SunStudy",
    "days_table",
    "sun_study",
    "sun_study_by_day",
    "sun_summaries_by_day",
]

Polygons = list[list[NDArray[np.float64]]]

# Directions each sample's sun disc is spread over when a study is not told
# how many. Fewer than soft_shadow's 64: the levels are cut from every
# direction's shadow at once, and that cut's cost grows with about the cube
# of their number (a 1 m cube's day of 12 hourly samples on a shared 2-core
# machine: 0.08 s with a point sun, 0.3 s with 8 directions, 3 s with 16,
# 40 s with 32). With 16, the share of the disc a straight edge leaves is
# within 0.066 of a sample's time at most and 0.020 on average over the
# penumbra; with 64, 0.032 and 0.0085 (tests/test_sunstudy_disc.py, against
# the circular segment's area).
SUN_DISC_SAMPLES = 16


@dataclass(frozen=True)
class _Frame:
    """Plane 2-D coordinates <-> the local frame handed to Clipper2."""

    centre: NDArray[np.float64]
    scale: float

    def to_local(self, loop: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.ascontiguousarray((loop - self.centre) * self.scale)

    def to_plane(self, loop: NDArray[np.float64]) -> NDArray[np.float64]:
        return loop / self.scale + self.centre

    def polygons(self, region: CrossSection) -> Polygons:
        return [[self.to_plane(loop) for loop in part] for part in components(region)]


def _area(polygons: Polygons) -> float:
    return float(sum(signed_areas(part).sum() for part in polygons))


@dataclass(frozen=True)
class SunStudy:
    """Sunlight over a region of a plane.

    Attributes
    ----------
    plane : Plane
    region : list of [outer, hole, ...] (k, 2) float64
        The receiving region in ``plane.to_2d`` coordinates.
    times : tuple of datetime
        The samples with the sun above the horizon.
    step : timedelta
        The time each sample stands for.
    shadows : tuple of polygons
        The exact shadow within the region at each of ``times``; with the
        sun's disc, ``disc_samples`` shadows a time, one per direction over
        the disc, time after time (a direction under the horizon shades the
        whole region).
    levels : dict[int, polygons]
        For ``k`` sunlit samples (of ``times``, or with the disc of its
        directions), the part of the region sunlit for exactly
        ``k * step / disc_samples``; levels with no area are left out. The
        levels tile the region: their areas add up to its area. A level's
        parts may be cut along the edges of the tiles it was computed in.
    sun_angle : float
        The sun's angular diameter in radians (0: a point sun).
    disc_samples : int
        The directions each sample's sun disc is spread over (1 for a point sun).
    shadow_weights : tuple of int
        How many units each of ``shadows`` takes from the sun at a point it
        covers (empty: 1 each). With translucent casters a direction has one
        shadow a distinct opacity, lowest first, each of the casters at least
        that opaque; a direction under the horizon has the whole region,
        weighing ``opacity_units``.
    opacity_units : int
        The parts a direction's sunlight is counted in (1 with every caster
        opaque, see :mod:`shadowgeo.opacity`); a level ``k`` is
        ``k * step / (disc_samples * opacity_units)``.
    """

    plane: Plane
    region: Polygons
    times: tuple[_dt.datetime, ...]
    step: _dt.timedelta
    shadows: tuple[Polygons, ...]
    levels: dict[int, Polygons] = field(repr=False)
    sun_angle: float = 0.0
    disc_samples: int = 1
    shadow_weights: tuple[int, ...] = ()
    opacity_units: int = 1

    @property
    def area(self) -> float:
        """Area of the region."""
        return _area(self.region)

    def hours(self, k: int) -> float:
        """Sunlight duration, in hours, of level ``k``."""
        return _hours(k, self.step, self.disc_samples * self.opacity_units)

    @property
    def full_level(self) -> int:
        """The level of a point in sunlight at every sample: the units of all
        the samples' directions."""
        return len(self.times) * self.disc_samples * self.opacity_units

    def level_areas(self) -> dict[float, float]:
        """Area of the region sunlit for each duration (hours -> area)."""
        return dict(self._level_areas)

    @functools.cached_property
    def _level_areas(self) -> dict[float, float]:
        # measured once: a day's levels over a city are thousands of polygons
        return {self.hours(k): _area(parts) for k, parts in sorted(self.levels.items())}

    def area_with_at_least(self, hours: float) -> float:
        """Area of the part of the region sunlit for at least ``hours``."""
        return _at_least(self._level_areas, hours)

    def fraction_meeting(self, hours: float) -> float:
        """Fraction of the region's area sunlit for at least ``hours`` (0 for
        an empty region)."""
        total = self.area
        return self.area_with_at_least(hours) / total if total > 0 else 0.0

    def sunlit_hours(self, points: ArrayLike) -> NDArray[np.float64]:
        """Sunlight duration, in hours, at (n, 2) plane points of the region
        (NaN outside it), from the shadows' polygons by even-odd ray crossing."""
        uv = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        inside_region = points_in_parts(uv, self.region)
        shadowed = np.zeros(len(uv))
        weights = self.shadow_weights or (1,) * len(self.shadows)
        for shadow, weight in zip(self.shadows, weights, strict=True):
            shadowed += weight * points_in_parts(uv, shadow)
        units = self.disc_samples * self.opacity_units
        lit = (self.full_level - shadowed) * self.step.total_seconds() / 3600.0 / units
        return np.where(inside_region, lit, np.nan)


def _hours(k: int, step: _dt.timedelta, per_sample: int = 1) -> float:
    """The duration, in hours, of ``k`` samples of ``step`` each, or of ``k``
    of the ``per_sample`` directions of each sample's sun disc."""
    return k * step.total_seconds() / 3600.0 / per_sample


def _at_least(level_areas: dict[float, float], hours: float) -> float:
    """The areas of the durations of at least ``hours``, summed in rising order."""
    return float(
        sum(area for duration, area in level_areas.items() if duration >= hours - RELATIVE_ROUNDING)
    )


@dataclass(frozen=True)
class DaySummary:
    """A day's sunlight without its polygons: what a table of many days needs
    (a year's level polygons over a city are millions of arrays; its
    summaries are a few numbers a day). ``level_areas``: hours of sunlight
    -> area, rising. :meth:`of` takes a :class:`SunStudy`'s own figures;
    :func:`sun_summaries_by_day` computes them from the levels' areas alone,
    which agree with the study's polygons to rounding (about 1e-15 of the
    region)."""

    samples: int
    area: float
    level_areas: dict[float, float]

    @classmethod
    def of(cls, study: SunStudy) -> DaySummary:
        return cls(len(study.times), study.area, study.level_areas())

    def area_with_at_least(self, hours: float) -> float:
        """As :meth:`SunStudy.area_with_at_least`."""
        return _at_least(self.level_areas, hours)

    def fraction_meeting(self, hours: float) -> float:
        """As :meth:`SunStudy.fraction_meeting`."""
        return self.area_with_at_least(hours) / self.area if self.area > 0 else 0.0


def days_table(summaries: dict[_dt.date, DaySummary], hours: float) -> str:
    """A Markdown table: day, samples with sun, fraction meeting ``hours``."""
    lines = [f"| day | sun samples | fraction with >= {hours:g} h |", "|---|---:|---:|"]
    for day, summary in summaries.items():
        lines.append(f"| {day} | {summary.samples} | {summary.fraction_meeting(hours):.4f} |")
    return "\n".join(lines)


def _region_polygon(plane: Plane, region: ArrayLike) -> NDArray[np.float64]:
    points = np.asarray(region, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 3:
        raise GeometryError(f"region must be an (n >= 3, 3) polygon, got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise GeometryError("region has NaN or infinite coordinates")
    return points


@dataclass(frozen=True)
class _Cast:
    """A day's exact shadows on the region, as its levels count them: each
    of ``shadows`` ``weights`` times (see :class:`SunStudy`)."""

    frame: _Frame
    region: CrossSection
    kept: list[_dt.datetime]
    shadows: list[Polygons]
    weights: list[int]
    units: int
    directions: int

    @property
    def count(self) -> int:
        """The level of a point no shadow covers."""
        return self.directions * self.units

    def local_regions(self) -> list[list[NDArray[np.float64]]]:
        """Each shadow in the frame's local coordinates, once per unit of its weight."""
        regions = _local_regions(self.frame, self.shadows)
        return [
            region
            for region, weight in zip(regions, self.weights, strict=True)
            for _ in range(weight)
        ]


def _levels(cast: _Cast) -> dict[int, Polygons]:
    """Exactly-``k``-units-sunlit parts of the region (:func:`cover_levels`
    of the weighted shadows: ``k`` sunlit is ``count - k`` shadowed)."""
    count = cast.count
    covered = sorted(cover_levels(cast.local_regions(), cast.region).items(), reverse=True)
    flat = [loop for _, parts in covered for part in parts for loop in part]
    plane = iter(_map_loops(cast.frame.to_plane, flat))
    return {count - m: [[next(plane) for _ in part] for part in parts] for m, parts in covered}


def _local_regions(frame: _Frame, shadows: Sequence[Polygons]) -> list[list[NDArray[np.float64]]]:
    """Each shadow's loops in ``frame``'s local coordinates, one region each."""
    loops = [loop for shadow in shadows for part in shadow for loop in part]
    local = iter(_map_loops(frame.to_local, loops))
    return [[next(local) for part in shadow for _ in part] for shadow in shadows]


def _map_loops(
    transform: Callable[[NDArray[np.float64]], NDArray[np.float64]],
    loops: list[NDArray[np.float64]],
) -> list[NDArray[np.float64]]:
    """``transform`` (pointwise) of every loop, in one numpy pass."""
    if not loops:
        return []
    ends = np.cumsum([len(loop) for loop in loops])[:-1]
    return np.split(transform(np.concatenate(loops)), ends)


def sun_study(
    casters: Any,
    plane: Plane,
    region: ArrayLike,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
    sun_angle: float = 0.0,
    sun_samples: int | None = None,
    opacity: ArrayLike | None = None,
) -> SunStudy:
    """Exact sunlight durations over ``region`` on ``plane`` at ``times``.

    Parameters
    ----------
    casters : mesh or list of meshes
        ``trimesh.Trimesh``, ``(vertices, faces)`` or :class:`Caster`; a list
        is treated as one caster.
    plane : Plane
        The receiving plane, its normal towards the sky.
    region : (n, 3) array_like
        A polygon on ``plane`` (convex or not): the area studied.
    times : sequence of aware datetime
        Sample times; each stands for ``step`` around it. Samples with the
        sun below the horizon count as dark and are dropped.
    latitude, longitude : float
        The site, in degrees (north and east positive).
    step : timedelta
        Duration of a sample, one hour by default.
    up, north
        The scene's frame, as in :func:`shadowgeo.sun.frame`.
    sun_angle : float
        The sun's angular diameter in radians (the real sun's is 0.53
        degrees, ``math.radians(0.53)``); 0, the default, is a point sun.
        With a disc, a point's sunlight at a sample is the share of the disc
        it sees (see the module notes).
    sun_samples : int
        The directions each sample's disc is spread over (default
        :data:`SUN_DISC_SAMPLES`, 16); the levels' cost grows with about
        the cube of the shadows cut, ``len(times) * sun_samples``.
    opacity : (m,) array_like, optional
        Each caster face's opacity (0 to 1, rounded to sixteenths; the
        faces of a list of casters in order). A point hidden at a sample
        gets ``1 - a`` of its sun, ``a`` the largest opacity of the faces
        hiding it (see the module notes); None, the default: every face is
        opaque.

    Returns
    -------
    SunStudy

    Examples
    --------
    A 1 m cube on a 10 m square plot in London on the spring equinox:

    >>> import datetime as dt, trimesh
    >>> from shadowgeo import Plane
    >>> cube = trimesh.creation.box([1, 1, 1]); _ = cube.apply_translation([0, 0.5, 0])
    >>> plot = [[-5, 0, 5], [5, 0, 5], [5, 0, -5], [-5, 0, -5]]
    >>> day = [dt.datetime(2026, 3, 21, h, 30, tzinfo=dt.UTC) for h in range(24)]
    >>> study = sun_study(cube, Plane([0, 1, 0]), plot, day, latitude=51.5, longitude=0.0)
    >>> len(study.times), round(sum(study.level_areas().values()), 9)
    (12, 100.0)

    The sun as its 0.53 degree disc, four directions a sample: near the
    shadow's edges a point sees part of the disc, a quarter hour at a time.

    >>> import math
    >>> disc = sun_study(cube, Plane([0, 1, 0]), plot, day, latitude=51.5, longitude=0.0,
    ...                  sun_angle=math.radians(0.53), sun_samples=4)
    >>> len(disc.shadows), sorted({disc.hours(k) % 1 for k in disc.levels})
    (48, [0.0, 0.25, 0.5, 0.75])
    """
    step = step or _dt.timedelta(hours=1)
    disc = _Disc.of(sun_angle, sun_samples, up, north)
    cast = _day_shadows(
        casters, plane, region, times, latitude, longitude, up, north, disc, opacity
    )
    return SunStudy(
        plane=plane,
        region=cast.frame.polygons(cast.region),
        times=tuple(cast.kept),
        step=step,
        shadows=tuple(cast.shadows),
        levels=_levels(cast),
        sun_angle=disc.angle,
        disc_samples=disc.samples,
        shadow_weights=tuple(cast.weights),
        opacity_units=cast.units,
    )


@dataclass(frozen=True)
class _Disc:
    """The sun's disc as a study samples it: its angular diameter, the
    directions each sun position is spread over (1: a point sun) and the
    scene's up vector (the directions under the horizon are dark)."""

    angle: float
    samples: int
    up: NDArray[np.float64]

    @classmethod
    def of(cls, angle: float, samples: int | None, up: str, north: ArrayLike | None) -> _Disc:
        angle = float(angle)
        if not 0 <= angle < math.pi / 2:
            raise GeometryError(
                f"sun_angle must be in [0, pi/2) radians (the sun's is 0.00925), got {angle!r}"
            )
        count = 1 if angle == 0 else SUN_DISC_SAMPLES if samples is None else int(samples)
        if count < 1:
            raise GeometryError(f"sun_samples must be >= 1, got {samples!r}")
        return cls(angle, count, sun_frame(up, north)[2])

    def directions(self, light: DirectionalLight) -> list[DirectionalLight]:
        """The directions spread over the disc round ``light``'s
        (:func:`shadowgeo.soft.light_samples`)."""
        spread = DirectionalLight(light.direction, angle=self.angle)
        return [s for s in light_samples(spread, self.samples) if isinstance(s, DirectionalLight)]

    def shadows(
        self,
        caster: Any,
        lights: list[DirectionalLight],
        plane: Plane,
        polygon: NDArray[np.float64],
    ) -> list[Polygons | None]:
        """Each sun position's directions' exact shadows on the region
        ``polygon`` (None for those under the horizon), position after
        position."""
        spread = [d for light in lights for d in self.directions(light)]
        up = [float(d.direction @ self.up) < 0 for d in spread]
        above = [d for d, lit in zip(spread, up, strict=True) if lit]
        cast = iter(project_shadow(caster, above, plane, receiver=polygon) if above else [])
        return [next(cast).polygons if lit else None for lit in up]


def _day_shadows(
    casters: Any,
    plane: Plane,
    region: ArrayLike,
    times: Sequence[_dt.datetime],
    latitude: float,
    longitude: float,
    up: str,
    north: ArrayLike | None,
    disc: _Disc,
    opacity: ArrayLike | None = None,
) -> _Cast:
    """The local frame, the region in it, the samples with the sun up and
    their exact shadows on the region (plane coordinates; with the sun's
    ``disc``, those of each sample's directions, sample after sample; with
    translucent casters, each direction's shadow of each opacity threshold)."""
    polygon = _region_polygon(plane, region)
    caster = _one_caster(casters)
    kept, lights = sun_lights(latitude, longitude, times, up=up, north=north)
    region_2d = plane.to_2d(polygon)
    if signed_areas([region_2d])[0] < 0:
        region_2d = region_2d[::-1]
    extent = float(np.max(np.abs(region_2d - region_2d.mean(axis=0)))) or 1.0
    frame = _Frame(region_2d.mean(axis=0), local_scale(2.0 * extent))
    region_cs = unite([frame.to_local(region_2d)])
    layered, parts = _layered(caster, opacity)
    per_layer = [_directions_shadows(part, lights, plane, polygon, disc) for part in parts]
    shadows, weights = _weighted(per_layer, layered, [[region_2d]])
    directions = len(kept) * disc.samples
    return _Cast(frame, region_cs, kept, shadows, weights, layered.units, directions)


def _layered(caster: Any, opacity: ArrayLike | None) -> tuple[Layers, list[Any]]:
    """The opacity thresholds of ``caster``'s faces and the caster of each
    (the faces at least that opaque); every face opaque: the caster as given."""
    if opacity is None:
        return layers(None, 0), [caster]
    whole = caster if isinstance(caster, Caster) else as_caster(caster)
    layered = layers(opacity, len(whole.faces))
    if layered.opaque:
        return layered, [caster]
    return layered, [(whole.vertices, whole.faces[faces]) for faces in layered.faces]


def _directions_shadows(
    caster: Any,
    lights: list[DirectionalLight],
    plane: Plane,
    polygon: NDArray[np.float64],
    disc: _Disc,
) -> list[Polygons | None]:
    """Each sample's (or with the sun's disc, each direction's) exact shadow
    of ``caster`` on the region ``polygon``; None under the horizon."""
    if disc.samples > 1:
        return disc.shadows(caster, lights, plane, polygon)
    # one call for the day: the caster is checked and prepared once for every sun position
    cast = project_shadow(caster, lights, plane, receiver=polygon) if lights else []
    # each shadow is already cut to the region, a union of non-overlapping parts
    return [shadow.polygons for shadow in cast]


def _weighted(
    per_layer: list[list[Polygons | None]], layered: Layers, whole: Polygons
) -> tuple[list[Polygons], list[int]]:
    """The shadows a study counts, direction after direction (each
    threshold's, lowest first), and each one's weight: a direction under
    the horizon is the ``whole`` region, dark in every unit."""
    shadows: list[Polygons] = []
    weights: list[int] = []
    for direction in zip(*per_layer, strict=True):
        cast = [shadow for shadow in direction if shadow is not None]
        if len(cast) < len(direction):
            shadows.append(whole)
            weights.append(layered.units)
        else:
            shadows.extend(cast)
            weights.extend(layered.weights)
    return shadows, weights


def _one_caster(casters: Any) -> Any:
    """A list of meshes as one (vertices, faces) caster; anything else as is."""
    if isinstance(casters, list):
        parts = [as_caster(mesh) for mesh in casters]
        vertices, faces, base = [], [], 0
        for part in parts:
            vertices.append(part.vertices)
            faces.append(part.faces + base)
            base += len(part.vertices)
        if not parts:
            raise GeometryError("no casters given")
        return np.concatenate(vertices), np.concatenate(faces)
    return casters


@dataclass(frozen=True)
class SunStudies:
    """One :class:`SunStudy` per calendar day."""

    days: dict[_dt.date, SunStudy]

    def fraction_meeting(self, hours: float) -> dict[_dt.date, float]:
        """For each day, the fraction of the region sunlit at least ``hours``."""
        return {day: study.fraction_meeting(hours) for day, study in self.days.items()}

    def table(self, hours: float) -> str:
        """A Markdown table: day, samples with sun, fraction meeting ``hours``."""
        return days_table(self.summaries(), hours)

    def summaries(self) -> dict[_dt.date, DaySummary]:
        """Each day's :class:`DaySummary`."""
        return {day: DaySummary.of(study) for day, study in self.days.items()}


def sun_study_by_day(
    casters: Any,
    plane: Plane,
    region: ArrayLike,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
    tz: _dt.tzinfo | None = None,
    scheduler: Any = None,
    progress: Callable[[int, int], None] | None = None,
    sun_angle: float = 0.0,
    sun_samples: int | None = None,
    opacity: ArrayLike | None = None,
) -> SunStudies:
    """:func:`sun_study` for each calendar day (in ``tz``, UTC by default) of ``times``.

    ``scheduler``: None runs the days one after another in this process; a
    ``dask.distributed.Client``, a scheduler address (``"tcp://host:8786"``) or
    ``"local"`` (a ``LocalCluster`` on this machine, started and closed here)
    runs them on Dask, one task a day, the caster sent to the workers once.
    Results are identical either way. ``progress(done, total)`` is called as
    days finish. ``sun_angle`` and ``sun_samples``: the sun's disc, and
    ``opacity``: each caster face's, as :func:`sun_study` takes them.
    """
    options = dict(latitude=latitude, longitude=longitude, step=step, up=up, north=north)
    options.update(sun_angle=sun_angle, sun_samples=sun_samples, opacity=opacity)
    return SunStudies(
        _by_day(sun_study, casters, plane, region, times, tz, scheduler, progress, options)
    )


def sun_summaries_by_day(
    casters: Any,
    plane: Plane,
    region: ArrayLike,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
    tz: _dt.tzinfo | None = None,
    scheduler: Any = None,
    progress: Callable[[int, int], None] | None = None,
    sun_angle: float = 0.0,
    sun_samples: int | None = None,
    opacity: ArrayLike | None = None,
) -> dict[_dt.date, DaySummary]:
    """:func:`sun_study_by_day`'s figures without its polygons, a
    :class:`DaySummary` a day made where the day is studied: the level sets'
    areas only (no difference of regions, no polygon taken out of Clipper2:
    a third less time on a summer day over a city), and on Dask only the
    summaries travel back, so memory holds one day's shadows at a time
    however many days. The areas agree with the full studies' to rounding
    (about 1e-15 of the region); serial and Dask runs are identical."""
    options = dict(latitude=latitude, longitude=longitude, step=step, up=up, north=north)
    options.update(sun_angle=sun_angle, sun_samples=sun_samples, opacity=opacity)
    return _by_day(_summary, casters, plane, region, times, tz, scheduler, progress, options)


def _summary(
    casters: Any,
    plane: Plane,
    region: ArrayLike,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
    sun_angle: float = 0.0,
    sun_samples: int | None = None,
    opacity: ArrayLike | None = None,
) -> DaySummary:
    """A day's :class:`DaySummary`, from the areas of its levels only
    (:func:`shadowgeo.levels.cover_level_areas`: no level polygon is made)."""
    step = step or _dt.timedelta(hours=1)
    disc = _Disc.of(sun_angle, sun_samples, up, north)
    cast = _day_shadows(
        casters, plane, region, times, latitude, longitude, up, north, disc, opacity
    )
    count, frame = cast.count, cast.frame
    unit = 1.0 / (frame.scale * frame.scale)  # a local area in plane units
    covered = cover_level_areas(cast.local_regions(), cast.region)
    per_sample = disc.samples * cast.units
    level_areas = {_hours(count - m, step, per_sample): area * unit for m, area in covered.items()}
    area = _area(frame.polygons(cast.region))
    return DaySummary(len(cast.kept), area, dict(sorted(level_areas.items())))


def _by_day(
    function: Callable[..., Any],
    casters: Any,
    plane: Plane,
    region: ArrayLike,
    times: Sequence[_dt.datetime],
    tz: _dt.tzinfo | None,
    scheduler: Any,
    progress: Callable[[int, int], None] | None,
    options: dict[str, Any],
) -> dict[_dt.date, Any]:
    """``function`` (:func:`sun_study` or :func:`_summary`) of each calendar
    day of ``times`` with the keywords ``options`` (the site, step and
    frame), here or on Dask (see :func:`sun_study_by_day`)."""
    name = "sun-study" if function is sun_study else "sun-summary"
    return each_day(
        function,
        (_one_caster(casters), plane, region),
        times,
        tz=tz,
        scheduler=scheduler,
        progress=progress,
        name=name,
        options=options,
    )
