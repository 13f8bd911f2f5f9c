"""Building footprints with heights (GeoJSON ``.geojson`` or ``.json``,
GeoPackage ``.gpkg``, Shapefile ``.shp``), extruded into closed prisms.

pyogrio (GDAL) reads the features and shapely their polygons (``pip install
"shadowgeo[city]"``). Each feature whose geometry is a Polygon or
MultiPolygon becomes one shape, named by its feature id: every part of it
extruded from its base to its base plus its height, a closed, outward-wound
prism (walls, roof with the footprint's holes, bottom), so a building casts
as one closed caster; its faces' kinds (:attr:`Shape.semantics`) are
``RoofSurface``, ``WallSurface`` and ``GroundSurface``. Any z of the
footprint is ignored: the base is 0 or the ``base`` attribute.

The height is the attribute ``height`` names (default ``"height"``), in the
scene's unit (metres but in a projected CRS in feet); where it is missing or
not above zero and ``floors`` names an attribute, that number of storeys
times ``storey_height`` (3 m). A feature with neither is left out, with a
note; a layer with neither attribute is an error. Coordinates follow
:mod:`.city_crs`: a projected CRS is kept, longitude and latitude are
projected to a transverse Mercator centred on the data before any geometry,
and the scene's :attr:`Scene.site` records both and the location.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..limits import MAX_DOCUMENT_BYTES
from ..scene.model import Scene
from .city_crs import city_scene, georeference
from .city_surfaces import GROUND, ROOF, WALL, CityObject, Surfaces, city_shapes

__all__ = ["prism", "read"]

_POLYGONAL = ("Polygon", "MultiPolygon")


def _libraries(path: Path) -> tuple[Any, Any]:
    try:
        import pyogrio
        import shapely
    except ImportError:  # pragma: no cover - the test extra installs them
        raise SceneError(
            'reading footprints needs pyogrio: pip install "shadowgeo[city]"', path=str(path)
        ) from None
    return pyogrio, shapely


def _features(
    path: Path, layer: str | int | None
) -> tuple[dict[str, Any], np.ndarray, np.ndarray, list[np.ndarray]]:
    """(meta, fids, shapely geometries, field arrays) of the layer; a
    SceneError naming the file for what GDAL cannot read."""
    pyogrio, shapely = _libraries(path)
    size = path.stat().st_size
    if size > MAX_DOCUMENT_BYTES:
        raise SceneError(
            f"{size:,} bytes, more than {MAX_DOCUMENT_BYTES:,}; refused", path=str(path)
        )
    try:
        meta, fids, wkb, fields = pyogrio.raw.read(path, layer=layer, return_fids=True)
    except (pyogrio.errors.DataSourceError, pyogrio.errors.DataLayerError) as problem:
        raise SceneError(f"cannot read as a GIS layer: {problem}", path=str(path)) from None
    except (pyogrio.errors.FieldError, pyogrio.errors.FeatureError) as problem:
        raise SceneError(f"malformed feature: {problem}", path=str(path)) from None
    except UnicodeDecodeError as problem:  # a field name or value GDAL hands over undecoded
        byte = problem.object[problem.start : problem.start + 1].hex()
        raise SceneError(
            f"a field name or text value is not UTF-8 (byte 0x{byte}); refused", path=str(path)
        ) from None
    geometries = shapely.from_wkb(wkb, on_invalid="ignore") if wkb is not None else None
    if geometries is None:
        raise SceneError("the layer has no geometry", path=str(path))
    return meta, np.asarray(fids), geometries, list(fields)


def _attribute(
    meta: dict[str, Any], fields: list[np.ndarray], name: str | None, count: int
) -> np.ndarray | None:
    """(count,) float64 of the attribute ``name`` (NaN where missing or not a
    number), or None when the layer has no such attribute."""
    if name is None:
        return None
    names = [str(field) for field in meta["fields"]]
    if name not in names:
        return None
    values = fields[names.index(name)]
    out = np.full(count, np.nan)
    for index, value in enumerate(values):
        try:
            out[index] = float(value)
        except (TypeError, ValueError):
            pass  # a text or empty value: no height here (noted with the feature)
    return out


def _heights(
    meta: dict[str, Any],
    fields: list[np.ndarray],
    count: int,
    height: str | None,
    floors: str | None,
    storey_height: float,
    path: Path,
) -> np.ndarray:
    """(count,) each feature's height, NaN where it has none."""
    given = _attribute(meta, fields, height, count)
    stories = _attribute(meta, fields, floors, count)
    if given is None and stories is None:
        names = ", ".join(str(field) for field in meta["fields"]) or "none"
        raise SceneError(
            f"no height attribute {height!r}"
            + (f" nor floors attribute {floors!r}" if floors else "")
            + f" (the attributes are {names}); name one with height= or floors=",
            path=str(path),
        )
    heights = np.full(count, np.nan) if given is None else given
    if stories is not None:
        missing = ~(heights > 0)
        heights[missing] = stories[missing] * storey_height
    heights[~(np.isfinite(heights) & (heights > 0))] = np.nan
    return heights


def prism(
    rings: list[np.ndarray], base: float, top: float, surfaces: Surfaces, start: int
) -> np.ndarray:
    """The points (2 k, 3) of one polygon's ``rings`` ((k_i, 2): the exterior
    counter-clockwise seen from above, then its holes clockwise, none closed)
    at ``base`` and at ``top``, its walls, roof and bottom added to
    ``surfaces`` (indices from ``start``): a closed prism, every face wound
    counter-clockwise seen from outside."""
    sizes = [len(ring) for ring in rings]
    flat = np.concatenate(rings)
    total = len(flat)
    bottom = [
        start + offset + np.arange(size)
        for offset, size in zip(np.cumsum([0, *sizes[:-1]]), sizes, strict=True)
    ]
    top_rings = [ring + total for ring in bottom]
    for low, high in zip(bottom, top_rings, strict=True):
        # along an exterior run counter-clockwise the solid is on the left:
        # (a, b, b', a') turns outward, as it does along a clockwise hole
        walls = np.column_stack([low, np.roll(low, -1), np.roll(high, -1), high])
        surfaces.add_each([[wall] for wall in walls], WALL)
    surfaces.add(top_rings, ROOF)
    surfaces.add([ring[::-1] for ring in bottom], GROUND)
    return np.concatenate(
        [
            np.column_stack([flat, np.full(total, base)]),
            np.column_stack([flat, np.full(total, top)]),
        ]
    )


def read(
    path: str | os.PathLike[str],
    *,
    height: str | None = "height",
    floors: str | None = None,
    storey_height: float = 3.0,
    base: str | None = None,
    layer: str | int | None = None,
    **options: Any,
) -> Scene:
    """Read building footprints into a Z-up :class:`Scene` of closed prisms.

    Parameters
    ----------
    path : str or Path
        ``.geojson`` / ``.json`` (GeoJSON), ``.gpkg``, ``.shp``.
    height : str, optional
        The attribute holding each building's height above its base.
    floors : str, optional
        The attribute holding its number of storeys, used where ``height``
        gives none (e.g. ``"Floor"``).
    storey_height : float
        The height of one storey, for ``floors``.
    base : str, optional
        The attribute holding the height of the building's base (default 0).
    layer : str or int, optional
        The layer of a GeoPackage holding several (default the first).

    Returns
    -------
    Scene
        One shape per footprint feature, with ``semantics``; ``site`` from
        the layer's CRS (None without one); ``up_axis="Z"``.

    Raises
    ------
    SceneError
        A file GDAL cannot read, a layer with neither height attribute, a
        CRS pyproj does not know, no footprint with a height; the message
        names the file.
    """
    path = Path(path)
    if options:
        raise SceneError(
            "the footprint reader takes height, floors, storey_height, base and layer, "
            f"got {sorted(options)}",
            path=str(path),
        )
    if not (math.isfinite(storey_height) and storey_height > 0):
        raise SceneError(f"storey_height must be > 0, got {storey_height!r}", path=str(path))
    _, shapely = _libraries(path)
    meta, fids, geometries, fields = _features(path, layer)
    count = len(geometries)
    heights = _heights(meta, fields, count, height, floors, storey_height, path)
    bases = _attribute(meta, fields, base, count)
    if base is not None and bases is None:
        raise SceneError(f"no base attribute {base!r}", path=str(path))
    kinds = shapely.get_type_id(geometries)
    polygonal = np.isin(kinds, [shapely.GeometryType.POLYGON, shapely.GeometryType.MULTIPOLYGON])
    polygonal &= ~shapely.is_empty(geometries)
    notes = _notes(path, fids, polygonal, heights)
    chosen = np.flatnonzero(polygonal & np.isfinite(heights))
    if not len(chosen):
        raise SceneError("no polygon footprint with a height in the file", path=str(path))
    footprints = geometries[chosen]
    located = None
    if meta.get("crs"):
        low_x, low_y, high_x, high_y = shapely.total_bounds(footprints)
        located = georeference(
            str(meta["crs"]), np.array([low_x, low_y]), np.array([high_x, high_y]), str(path)
        )
    if located is not None:
        flat = shapely.get_coordinates(footprints)
        moved = located.to_scene(np.column_stack([flat, np.zeros(len(flat))]), str(path))
        footprints = shapely.set_coordinates(footprints.copy(), moved[:, :2])
    invalid = ~shapely.is_valid(footprints)
    if invalid.any():
        footprints[invalid] = shapely.make_valid(footprints[invalid])
        notes.append(f"{path.name}: {int(invalid.sum())} footprints crossed themselves; mended")
    footprints = shapely.orient_polygons(footprints, exterior_cw=False)
    objects = []
    for index, footprint in zip(chosen.tolist(), footprints, strict=True):
        name = str(fids[index]) if len(fids) else str(index)
        floor = 0.0 if bases is None or not np.isfinite(bases[index]) else float(bases[index])
        building = _building(footprint, floor, floor + float(heights[index]), name, shapely)
        if building is not None:
            objects.append(building)
    shapes = city_shapes(objects, path=path, kind="feature")
    return city_scene(shapes, path, located, notes)


def _building(
    footprint: Any, floor: float, roof: float, name: str, shapely: Any
) -> CityObject | None:
    """The closed prism of every polygon of one footprint, one object."""
    surfaces, pieces, start = Surfaces(), [], 0
    parts = shapely.get_parts(shapely.get_parts(footprint))  # a mended one may nest
    polygons = [part for part in parts if shapely.get_type_id(part) == 3]
    for polygon in polygons:
        if len(polygon.exterior.coords) < 4:
            continue
        rings = [np.asarray(polygon.exterior.coords)[:-1, :2]]
        rings += [np.asarray(hole.coords)[:-1, :2] for hole in polygon.interiors]
        rings = [ring for ring in rings if len(ring) >= 3]
        points = prism(rings, floor, roof, surfaces, start)
        pieces.append(points)
        start += len(points)
    if not pieces:
        return None
    return CityObject(name, np.concatenate(pieces), surfaces, solid=True)


def _notes(path: Path, fids: np.ndarray, polygonal: np.ndarray, heights: np.ndarray) -> list[str]:
    """Notes naming the features left out: not polygons, or without a height."""
    notes = []
    for mask, why in (
        (~polygonal, "not a polygon"),
        (polygonal & ~np.isfinite(heights), "no height"),
    ):
        left = np.flatnonzero(mask)
        if len(left):
            names = [str(fids[i]) if len(fids) else str(i) for i in left[:10]]
            more = f", and {len(left) - 10} more" if len(left) > 10 else ""
            notes.append(f"{path.name}: left out ({why}): features {', '.join(names)}{more}")
    return notes
