"""Hours of sunlight written back into a CityJSON file, on its semantic
surfaces.

CityJSON (1.1 and 2.0, section "Semantics of geometric primitives") lets a
semantic surface carry attributes of its own beside ``type``, ``parent``
and ``children``, as plain key-value pairs (``{"type": "RoofSurface",
"slope": 33.4}``). Polygons often share one semantic surface (every wall
of a building one ``WallSurface``), so a polygon given hours gets a surface
of its own: a copy of its old one (``parent`` kept, ``children`` left with
the original) with the hours added, appended to the geometry's surfaces;
its ``values`` entry points at the copy. Polygons given no hours keep their
surface. A polygon with no semantic surface (``values`` null, or a geometry
with no ``semantics``) has no type to carry the hours: it is left as it is
and counted. Everything else in the file is copied unchanged.

:func:`surface_polygons` lists the polygons in the order :func:`write_surface_hours`
takes hours: object by object in the file's order, of each object the
geometries of its highest level of detail (as :mod:`.cityjson` reads it),
polygons in boundary order; each with its semantic type and its outer ring
in the file's coordinates (the ``transform`` applied). Geometry instances
(templates) are not listed. Plain CityJSON only (not CityJSONSeq).
"""

from __future__ import annotations

import copy
import json
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from .atomic import atomic_path
from .cityjson import DEPTHS
from .x3d import parse as x3d_parse

__all__ = [
    "ATTRIBUTE",
    "SurfacePolygon",
    "object_types",
    "polygon_values",
    "surface_polygons",
    "write_surface_hours",
]

ATTRIBUTE = "sunlight_hours"


@dataclass(frozen=True)
class SurfacePolygon:
    """One polygon of a city object: ``kind`` its semantic type (None: it
    has none), ``outer`` its outer ring, (k, 3) float64 file coordinates."""

    object_id: str
    kind: str | None
    outer: np.ndarray


def _document(path: Path) -> dict[str, Any]:
    if path.name.lower().endswith(".jsonl"):
        raise SceneError("hours are written to CityJSON, not CityJSONSeq", path=str(path))
    try:
        document = json.loads(x3d_parse.read_bytes(path))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise SceneError(f"not JSON: {error}", path=str(path)) from None
    if not isinstance(document, dict) or document.get("type") != "CityJSON":
        raise SceneError("not a CityJSON file", path=str(path))
    return document


def _vertices(document: dict[str, Any]) -> np.ndarray:
    points = np.asarray(document.get("vertices", []), dtype=np.float64).reshape(-1, 3)
    transform = document.get("transform")
    if transform:
        points = points * np.asarray(transform["scale"]) + np.asarray(transform["translate"])
    return points


def _lod(geometry: dict[str, Any]) -> tuple[int, ...]:
    try:
        return tuple(int(part) for part in str(geometry.get("lod")).split("."))
    except ValueError:
        return (-1,)


def _chosen(body: dict[str, Any]) -> list[dict[str, Any]]:
    """The object's geometries with polygons, of its highest level of detail."""
    found = [item for item in body.get("geometry", []) or [] if item.get("type") in DEPTHS]
    if not found:
        return []
    top = max(_lod(item) for item in found)
    return [item for item in found if _lod(item) == top]


def _surfaces(boundaries: Any, values: Any, depth: int) -> Iterator[tuple[list[Any], Any, int]]:
    """Each polygon (its rings) with the ``values`` list holding its entry and
    the entry's index (``values`` None: no semantics)."""
    for index, item in enumerate(boundaries):
        if depth == 0:
            yield item, values, index
        else:
            inner = None if values is None else values[index]
            yield from _surfaces(item, inner, depth - 1)


def _polygons(
    document: dict[str, Any],
) -> Iterator[tuple[str, dict[str, Any], list[Any], Any, int]]:
    for name, body in document.get("CityObjects", {}).items():
        for geometry in _chosen(body):
            semantics = geometry.get("semantics")
            values = None if semantics is None else semantics.get("values")
            depth = DEPTHS[geometry["type"]]
            for rings, holder, index in _surfaces(geometry["boundaries"], values, depth):
                yield str(name), geometry, rings, holder, index


def object_types(path: str | os.PathLike[str]) -> dict[str, str]:
    """Each city object's id -> its type (``Building``, ``PlantCover``, ...)
    as the file gives it; SceneError for a file that is not CityJSON."""
    objects = _document(Path(path)).get("CityObjects", {})
    return {
        str(name): str(body.get("type")) for name, body in objects.items() if isinstance(body, dict)
    }


def surface_polygons(path: str | os.PathLike[str]) -> list[SurfacePolygon]:
    """The file's polygons, in the order :func:`write_surface_hours` takes
    hours (see the module notes)."""
    source = Path(path)
    document = _document(source)
    points = _vertices(document)
    listed = []
    for name, geometry, rings, holder, index in _polygons(document):
        value = None if holder is None else holder[index]
        surfaces = (geometry.get("semantics") or {}).get("surfaces", [])
        kind = None if value is None else surfaces[value].get("type")
        listed.append(SurfacePolygon(name, kind, points[np.asarray(rings[0], dtype=np.int64)]))
    return listed


def polygon_values(
    polygons: Sequence[SurfacePolygon], values: Mapping[tuple[str, int], tuple[str, float]]
) -> tuple[list[float | None], int]:
    """Per polygon of ``polygons`` (:func:`surface_polygons`), the value
    ``values`` gives its (object id, number within the object, counting
    from 0 in the file's order), as :func:`write_surface_hours` takes them
    (None: none given), and how many given values were left out because
    the kind they were found for is not the polygon's semantic type (a
    reader and this module reading the object's geometry differently).

    Examples
    --------
    >>> wall = SurfacePolygon("b", "WallSurface", np.zeros((3, 3)))
    >>> roof = SurfacePolygon("b", "RoofSurface", np.zeros((3, 3)))
    >>> polygon_values([wall, roof], {("b", 1): ("RoofSurface", 9.5)})
    ([None, 9.5], 0)
    """
    listed: list[float | None] = []
    numbers: dict[str, int] = {}
    mismatched = 0
    for polygon in polygons:
        number = numbers.get(polygon.object_id, 0)
        numbers[polygon.object_id] = number + 1
        found = values.get((polygon.object_id, number))
        if found is not None and found[0] != polygon.kind:
            mismatched += 1
            found = None
        listed.append(None if found is None else found[1])
    return listed, mismatched


def write_surface_hours(
    source: str | os.PathLike[str],
    target: str | os.PathLike[str],
    hours: Sequence[float | None],
    *,
    attribute: str = ATTRIBUTE,
) -> int:
    """Copy ``source`` to ``target`` with ``hours[i]`` on the semantic surface
    of :func:`surface_polygons`' ``i``-th polygon (None: left as it is),
    atomically. Returns how many polygons given hours have no semantic
    surface to carry them (left as they are).

    Raises
    ------
    SceneError
        Not a CityJSON file, ``hours`` not one per polygon, a value that is
        not finite, or a file that cannot be written.
    """
    document = _document(Path(source))
    listed = list(_polygons(document))
    if len(hours) != len(listed):
        raise SceneError(f"{len(hours)} hours for {len(listed)} polygons", path=str(source))
    untyped = 0
    for (_, geometry, _, holder, index), value in zip(listed, hours, strict=True):
        if value is None:
            continue
        if not np.isfinite(value):
            raise SceneError(f"hours {value!r} are not finite", path=str(source))
        if holder is None or holder[index] is None:
            untyped += 1
            continue
        surfaces = geometry["semantics"]["surfaces"]
        own = copy.deepcopy(surfaces[holder[index]])
        own.pop("children", None)
        own[attribute] = float(value)
        surfaces.append(own)
        holder[index] = len(surfaces) - 1
    out = Path(target)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(out) as temporary:
            temporary.write_text(json.dumps(document, separators=(",", ":")))
    except OSError as error:
        raise SceneError(f"cannot write: {error.strerror or error}", path=str(target)) from None
    return untyped
