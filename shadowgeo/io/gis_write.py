"""GIS output of a sun study: polygons with attributes, in the input's CRS.

A sun study of city data runs in the scene's frame: metres, x east, y north
(:mod:`.city_crs`: a projected CRS kept as it is, geographic coordinates
projected to a transverse Mercator centred on the data). Here its polygons go
back, through the inverse of that projection (pyproj, ``always_xy``), to:

- GeoPackage (``.gpkg``): the input's own CRS (``Site.source_crs``), one layer
  per :class:`Layer`; a compound CRS (RD New + NAP, ``EPSG:7415``) is kept
  whole, its heights unused (the polygons are flat);
- GeoJSON (``.geojson``): RFC 7946's only CRS, longitude and latitude on
  WGS 84 (``OGC:CRS84``), whatever the input's; a GeoJSON file holds one
  layer, so every layer's features go in it with a ``layer`` attribute.

Polygons with heights (the faces of walls and roofs) are written in 3-D
(``MultiPolygon Z``), their heights as the scene has them (metres up).
A scene with no site (a file naming no CRS) is written to GeoPackage in its
own coordinates with no CRS; GeoJSON, whose coordinates must be longitude
and latitude, is refused for it. Files are written through pyogrio (GDAL)
to a temporary path and renamed (:mod:`.atomic`): a GeoPackage is an SQLite
database, never left half-written.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from ..errors import SceneError
from ..scene.model import Site
from .atomic import atomic_path

__all__ = [
    "CRS84",
    "Layer",
    "SUFFIXES",
    "axis_names",
    "is_gis_path",
    "output_crs",
    "to_output",
    "write_layers",
]

SUFFIXES = {".gpkg": "GPKG", ".geojson": "GeoJSON"}
CRS84 = "OGC:CRS84"
_INSTALL = 'pip install "shadowgeo[city]"'


@dataclass(frozen=True)
class Layer:
    """Polygons and their attributes, in the scene's plan coordinates.

    ``polygons``: one shapely (Multi)Polygon a feature; ``fields``: name ->
    one value a feature (str, float, int or bool)."""

    polygons: list[Any]
    fields: dict[str, list[Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name, values in self.fields.items():
            if len(values) != len(self.polygons):
                raise ValueError(
                    f"field {name!r} has {len(values)} values for {len(self.polygons)} polygons"
                )


def is_gis_path(path: str | os.PathLike[str]) -> bool:
    """Whether :func:`write_layers` writes a file named ``path``."""
    return Path(path).suffix.lower() in SUFFIXES


def output_crs(site: Site | None, path: str | os.PathLike[str]) -> str | None:
    """The CRS a file named ``path`` is written in (see the module notes);
    SceneError for GeoJSON of a scene with no CRS."""
    driver = _driver(path)
    if driver == "GeoJSON":
        if site is None:
            raise SceneError(
                "the input names no coordinate reference system, and GeoJSON's coordinates "
                "are longitude and latitude (RFC 7946): write a .gpkg instead",
                path=str(path),
            )
        return CRS84
    return None if site is None else site.source_crs


def to_output(polygons: list[Any], site: Site | None, crs: str | None) -> list[Any]:
    """``polygons`` (scene plan coordinates) in ``crs``: the inverse of the
    reader's projection, then on to ``crs``; unchanged without a site or when
    the scene is already in ``crs``'s horizontal coordinates."""
    if site is None or crs is None:
        return list(polygons)
    import pyproj

    source = pyproj.CRS.from_user_input(site.crs)
    target = pyproj.CRS.from_user_input(crs)
    horizontal = target.sub_crs_list[0] if target.is_compound else target
    if source.equals(horizontal, ignore_axis_order=True):
        return list(polygons)
    transformer = pyproj.Transformer.from_crs(source, horizontal, always_xy=True)

    def move(points: np.ndarray) -> np.ndarray:
        x, y = transformer.transform(points[:, 0], points[:, 1])
        return np.column_stack([x, y, *points.T[2:]])  # heights, if any, kept

    items = np.asarray(polygons, dtype=object)
    moved = shapely.transform(items, move, include_z=bool(shapely.has_z(items).any()))
    return list(moved)


def axis_names(crs: str | None, meters_per_unit: float) -> tuple[tuple[str, str], bool]:
    """The labels of a map's two axes in ``crs`` (name and unit, east then
    north) and whether it is in degrees; ``x``, ``y`` in the scene's unit
    without a CRS."""
    if crs is None:
        unit = "m" if meters_per_unit == 1.0 else f"{meters_per_unit:g} m"
        return (f"x ({unit})", f"y ({unit})"), False
    import pyproj

    found = pyproj.CRS.from_user_input(crs)
    horizontal = found.sub_crs_list[0] if found.is_compound else found
    axes = sorted(horizontal.axis_info[:2], key=lambda axis: axis.direction.lower() != "east")
    labels = tuple(f"{axis.name} ({axis.unit_name})" for axis in axes)
    return (labels[0], labels[1]), bool(horizontal.is_geographic)


def write_layers(
    path: str | os.PathLike[str], layers: Mapping[str, Layer], site: Site | None
) -> str | None:
    """Write ``layers`` (scene plan coordinates) to a GeoPackage or GeoJSON
    file, atomically, in :func:`output_crs`; return that CRS.

    Raises
    ------
    SceneError
        An extension other than ``.gpkg`` or ``.geojson``, GeoJSON without a
        CRS, pyogrio missing, or a file that cannot be written (naming it).
    """
    crs = output_crs(site, path)
    try:
        import pyogrio.errors
        import pyogrio.raw
    except ImportError:  # pragma: no cover - the city extra installs it
        raise SceneError(f"GIS output needs pyogrio ({_INSTALL})", path=str(path)) from None
    moved = {name: (to_output(layer.polygons, site, crs), layer) for name, layer in layers.items()}
    if _driver(path) == "GeoJSON":
        moved = {"": _one_layer(moved)}
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(target) as temporary:
            temporary.unlink()  # GDAL makes the file itself: an empty one is no GeoPackage
            for number, (name, (polygons, layer)) in enumerate(moved.items()):
                layer_name = name or target.stem
                _write_one(pyogrio.raw, temporary, layer_name, polygons, layer, crs, number > 0)
    except OSError as error:
        raise SceneError(f"cannot write: {error.strerror or error}", path=str(path)) from None
    except (pyogrio.errors.DataSourceError, pyogrio.errors.DataLayerError) as error:
        # GDAL's own refusals (a full disk, a driver error) come as these
        raise SceneError(f"cannot write: {error}", path=str(path)) from None
    return crs


def _one_layer(moved: dict[str, tuple[list[Any], Layer]]) -> tuple[list[Any], Layer]:
    """Every layer's features in one, with a ``layer`` attribute (GeoJSON);
    a field a layer lacks is empty (None) on its features."""
    names = list(dict.fromkeys(name for _, layer in moved.values() for name in layer.fields))
    polygons: list[Any] = []
    fields: dict[str, list[Any]] = {"layer": [], **{name: [] for name in names}}
    for layer_name, (moved_polygons, layer) in moved.items():
        polygons.extend(moved_polygons)
        fields["layer"].extend([layer_name] * len(moved_polygons))
        for name in names:
            fields[name].extend(layer.fields.get(name, [None] * len(moved_polygons)))
    return polygons, Layer(polygons, fields)


def _write_one(
    raw: Any,
    path: Path,
    name: str,
    polygons: list[Any],
    layer: Layer,
    crs: str | None,
    append: bool,
) -> None:
    """One layer into ``path`` (appended to it after the first)."""
    multi = [
        item if isinstance(item, shapely.MultiPolygon) else shapely.MultiPolygon([item])
        for item in polygons
    ]
    solid = bool(shapely.has_z(np.asarray(multi, dtype=object)).any())  # 3-D faces
    geometry = shapely.to_wkb(np.asarray(multi, dtype=object), output_dimension=3 if solid else 2)
    arrays = [_column(values) for values in layer.fields.values()]
    with warnings.catch_warnings():
        # no CRS is what the input had (said in the module notes), not a slip
        warnings.filterwarnings("ignore", "'crs' was not provided", UserWarning)
        raw.write(
            str(path),
            np.asarray(geometry, dtype=object),
            arrays,
            list(layer.fields),
            layer=name,
            driver=_driver(path),
            geometry_type="MultiPolygon Z" if solid else "MultiPolygon",
            crs=crs,
            append=append,
        )


def _column(values: list[Any]) -> np.ndarray:
    """A field's values as the array pyogrio writes: float64, int64, bool or
    strings (object)."""
    kinds = {type(value) for value in values if value is not None}
    if kinds and kinds <= {float, int} and None not in values:
        return np.asarray(values, dtype=np.int64 if kinds == {int} else np.float64)
    if kinds == {bool} and None not in values:
        return np.asarray(values, dtype=bool)
    return np.asarray(values, dtype=object)


def _driver(path: str | os.PathLike[str]) -> str:
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise SceneError(
            f"GIS output is written as {' or '.join(SUFFIXES)}, not {suffix or 'no extension'!r}",
            path=str(path),
        )
    return SUFFIXES[suffix]
