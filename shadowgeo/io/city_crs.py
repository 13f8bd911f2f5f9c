"""Coordinate reference systems of city data, for the city readers
(:mod:`.cityjson`, :mod:`.footprints`).

The rule: geometry is computed in metres, z up. A projected CRS (RD New
``EPSG:28992``, its compound ``EPSG:7415`` with NAP heights, a UTM zone) is
kept as it is, x east and y north; geographic coordinates (longitude and
latitude in degrees: CRS84, ``EPSG:4326``) are never taken for lengths:
they are projected first, with pyproj, to a transverse Mercator centred on
the data (scale 1 on its central meridian, on the file's own datum), where
lengths and areas across a city are true to a few parts in a billion
(the scale grows as ``1 + d^2 / 2R^2`` a distance ``d`` off the meridian).
The data's x is always east (longitude) and y north (latitude), whatever
order the CRS's definition gives its axes: the order GIS files store.

:func:`georeference` gives the projection and the scene's
:class:`~shadowgeo.scene.model.Site`: the CRS the scene's coordinates are in,
the file's own (for outputs that go back to it), and the latitude, longitude
and true north of the centre of the data's bounding box, in the CRS's own
geodetic datum (within a few hundred metres of WGS 84 everywhere: nothing to a
sun study). A file with no CRS has no site (the caller gives the location).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SceneError
from ..scene.model import Scene, Shape, Site

if TYPE_CHECKING:
    from pathlib import Path

    import pyproj

    from .city_surfaces import CityObject

__all__ = ["Georeference", "city_scene", "georeference", "parse_crs", "place"]

# The step (degrees of latitude, about 10 m) between the two points whose
# projections give the direction of true north at the site.
_NORTH_STEP = 1e-4
_INSTALL = 'pip install "shadowgeo[city]"'


def _pyproj(path: str) -> Any:
    try:
        import pyproj
    except ImportError:  # pragma: no cover - the test extra installs it
        raise SceneError(f"a file with a CRS needs pyproj ({_INSTALL})", path=path) from None
    return pyproj


@dataclass(frozen=True)
class Georeference:
    """How a city file's coordinates become the scene's, and where it stands.

    ``projection``: pyproj's transformer from the file's (geographic)
    coordinates to the scene's transverse Mercator, x east and y north; None
    for a projected CRS, kept. ``z_scale`` turns the file's heights into the
    unit of its x and y (1 but for a compound CRS whose heights are in
    another unit). ``meters_per_unit``: the scene's unit.
    """

    site: Site
    projection: pyproj.Transformer | None
    z_scale: float
    meters_per_unit: float

    def to_scene(self, points: np.ndarray, path: str, where: str | None = None) -> np.ndarray:
        """(n, 3) float64 ``points`` of the file in scene coordinates; a
        SceneError naming ``path`` and ``where`` for a point pyproj cannot
        project (a latitude past 90 degrees, ...)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if self.projection is None and self.z_scale == 1.0:
            return points
        scene = points.copy()
        if self.projection is not None and len(points):
            x, y = self.projection.transform(points[:, 0], points[:, 1])
            scene[:, 0], scene[:, 1] = x, y
        scene[:, 2] *= self.z_scale
        if not np.all(np.isfinite(scene)):
            bad = int(np.flatnonzero(~np.all(np.isfinite(scene), axis=1))[0])
            raise SceneError(
                f"point {points[bad].tolist()} cannot be projected from the file's CRS",
                path=path,
                node=where,
            )
        return scene


def parse_crs(text: str, path: str) -> pyproj.CRS:
    """pyproj's CRS of what a file names (``EPSG:7415``, an OGC URL or URN,
    WKT, PROJ JSON); SceneError naming the file for one pyproj does not know."""
    _pyproj(path)
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    try:
        return CRS.from_user_input(text)
    except CRSError as error:
        message = f"unknown coordinate reference system {text!r}: {error}"
        raise SceneError(message, path=path) from None


def georeference(
    text: str | None, low: np.ndarray, high: np.ndarray, path: str
) -> Georeference | None:
    """The :class:`Georeference` of a file whose CRS is ``text`` and whose
    points span the box ``low``, ``high`` (x, y in the file's coordinates);
    None when the file names no CRS.

    Raises
    ------
    SceneError
        A CRS pyproj does not know, one that is neither geographic nor
        projected (geocentric, engineering), or one whose axes do not point
        east and north.
    """
    if text is None:
        return None
    crs = parse_crs(text, path)
    horizontal = crs.sub_crs_list[0] if crs.is_compound and crs.sub_crs_list else crs
    if not (horizontal.is_geographic or horizontal.is_projected):
        raise SceneError(
            f"CRS {horizontal.name!r} is neither geographic nor projected; refused", path=path
        )
    directions = {axis.direction.lower() for axis in horizontal.axis_info[:2]}
    if directions != {"east", "north"}:
        raise SceneError(
            f"CRS {horizontal.name!r} has axes pointing {sorted(directions)}; "
            "only east and north are read",
            path=path,
        )
    vertical = [axis for axis in crs.axis_info[2:] if axis.direction.lower() == "up"]
    if horizontal.is_geographic:
        return _projected(text, horizontal, vertical, low, high, path)
    unit = float(horizontal.axis_info[0].unit_conversion_factor)
    z_scale = float(vertical[0].unit_conversion_factor) / unit if vertical else 1.0
    pyproj = _pyproj(path)
    centre = (np.asarray(low, np.float64)[:2] + np.asarray(high, np.float64)[:2]) / 2
    to_degrees = pyproj.Transformer.from_crs(horizontal, horizontal.geodetic_crs, always_xy=True)
    longitude, latitude = (float(v) for v in to_degrees.transform(centre[0], centre[1]))
    to_grid = pyproj.Transformer.from_crs(horizontal.geodetic_crs, horizontal, always_xy=True)
    site = Site(
        crs=crs.to_wkt(),
        source_crs=text,
        latitude=latitude,
        longitude=longitude,
        north=_north(to_grid, latitude, longitude),
    )
    return Georeference(site, None, z_scale, unit)


def _projected(
    text: str,
    horizontal: pyproj.CRS,
    vertical: list[Any],
    low: np.ndarray,
    high: np.ndarray,
    path: str,
) -> Georeference:
    """The Georeference of geographic data: a transverse Mercator of scale 1
    whose origin is the centre of the data's box, on the data's datum."""
    pyproj = _pyproj(path)
    from pyproj.crs import ProjectedCRS
    from pyproj.crs.coordinate_operation import TransverseMercatorConversion

    west, south = float(low[0]), float(low[1])
    east, north = float(high[0]), float(high[1])
    if not (-90.0 <= south <= north <= 90.0 and -360.0 <= west <= east <= 360.0):
        raise SceneError(
            f"longitudes {west:g} to {east:g} and latitudes {south:g} to {north:g} are not "
            f"those of CRS {horizontal.name!r} (degrees)",
            path=path,
        )
    longitude = (west + east) / 2
    if east - west > 180.0:  # across the antimeridian: the centre of the short way round
        longitude += 180.0
    longitude = (longitude + 180.0) % 360.0 - 180.0
    latitude = (south + north) / 2
    local = ProjectedCRS(
        conversion=TransverseMercatorConversion(
            latitude_natural_origin=latitude,
            longitude_natural_origin=longitude,
            false_easting=0.0,
            false_northing=0.0,
            scale_factor_natural_origin=1.0,
        ),
        geodetic_crs=horizontal.geodetic_crs,
        name=f"shadowgeo local transverse Mercator at {latitude:.6f}, {longitude:.6f}",
    )
    projection = pyproj.Transformer.from_crs(horizontal, local, always_xy=True)
    z_scale = float(vertical[0].unit_conversion_factor) if vertical else 1.0
    site = Site(
        crs=local.to_wkt(),
        source_crs=text,
        latitude=latitude,
        longitude=longitude,
        north=_north(
            pyproj.Transformer.from_crs(horizontal.geodetic_crs, local, always_xy=True),
            latitude,
            longitude,
        ),
    )
    return Georeference(site, projection, z_scale, 1.0)


def _north(
    to_grid: pyproj.Transformer, latitude: float, longitude: float
) -> tuple[float, float, float]:
    """The unit vector in grid coordinates along the meridian through the
    site, towards the north pole (``to_grid``: longitude, latitude to grid)."""
    below = max(latitude - _NORTH_STEP, -90.0)
    above = min(latitude + _NORTH_STEP, 90.0)
    x, y = to_grid.transform([longitude, longitude], [below, above])
    dx, dy = float(x[1] - x[0]), float(y[1] - y[0])
    length = math.hypot(dx, dy)
    if not (math.isfinite(length) and length > 0):  # at a pole every way is south
        return (0.0, 1.0, 0.0)
    return (dx / length, dy / length, 0.0)


def place(objects: list[CityObject], located: Georeference, path: Path) -> None:
    """Every object's points put in scene coordinates, in one call of pyproj
    (per object only to name the one whose point cannot be projected)."""
    if not objects:
        return
    sizes = np.cumsum([len(item.points) for item in objects])[:-1]
    try:
        moved = located.to_scene(np.concatenate([item.points for item in objects]), str(path))
    except SceneError:
        for item in objects:
            located.to_scene(item.points, str(path), f"CityObject {item.name!r}")
        raise
    for item, points in zip(objects, np.split(moved, sizes), strict=True):
        item.points = points


def city_scene(
    shapes: list[Shape], path: Path, located: Georeference | None, notes: list[str]
) -> Scene:
    """The Z-up scene of a city file's shapes, in the unit and at the site
    its georeference gives (metres and no site for a file with none)."""
    return Scene(
        shapes=shapes,
        path=str(path),
        up_axis="Z",
        meters_per_unit=1.0 if located is None else located.meters_per_unit,
        warnings=notes,
        site=None if located is None else located.site,
    )
