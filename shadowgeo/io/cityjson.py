"""CityJSON 1.0, 1.1 and 2.0 (``.city.json``, or ``.json`` whose ``type`` is
``CityJSON``) and CityJSONSeq (``.city.jsonl``) input.

Each city object with geometry (a Building, a BuildingPart, a Road, ...)
becomes one shape named by its id, with a kind per face from the file's
semantic surfaces (:mod:`.city_surfaces`); an object with no geometry of its
own (a Building made of BuildingParts) adds none. Of an object's geometries,
those of its highest level of detail are read (``lod="1.2"`` picks that
LoD, ``lod="2"`` the highest of 2.x; an object without it is left out, with a
note). Read: MultiSurface, CompositeSurface, Solid, MultiSolid and
CompositeSolid (a Solid's shells bound a volume: the shape is one-sided;
surfaces are one-sided when they close up or their semantics show them wound
outward, :mod:`.city_surfaces`), and GeometryInstance of a
geometry template (the template's points through the instance's 4x4 matrix,
then moved to its reference point). MultiPoint and MultiLineString have no
faces: skipped, with a note.

Vertices are decompressed by the file's ``transform`` (``scale`` and
``translate``) in float64, then placed by :mod:`.city_crs` from
``metadata.referenceSystem``: a projected CRS is kept, geographic
coordinates are projected first, and the scene's :attr:`Scene.site` records
both and the location; with no CRS the site is None. The scene is Z up.

The file is untrusted: at most ``limits.MAX_DOCUMENT_BYTES``, JSON parsed by
the standard library (NaN and Infinity refused), every index checked against
the vertices it names and every nesting against its geometry type before
any array is built, and at most ``limits.MAX_TEMPLATE_POINTS`` points placed
from templates; a SceneError names the file and the city object.
"""

from __future__ import annotations

import json
import os
from collections.abc import Collection, Iterator
from dataclasses import dataclass
from itertools import chain
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..limits import MAX_TEMPLATE_POINTS
from ..scene.model import Scene
from .city_crs import Georeference, city_scene, georeference, place
from .city_surfaces import CityObject, Surfaces, city_shapes
from .x3d import parse as x3d_parse
from .x3d.json import json_kind

__all__ = ["DEPTHS", "NO_FACES", "SOLIDS", "VERSIONS", "read"]

VERSIONS = ("1.0", "1.1", "2.0")
# Levels of list above one surface (a list of rings) in each geometry type's
# boundaries: MultiSurface [surface], Solid [shell][surface], MultiSolid
# [solid][shell][surface].
DEPTHS = {
    "MultiSurface": 0,
    "CompositeSurface": 0,
    "Solid": 1,
    "MultiSolid": 2,
    "CompositeSolid": 2,
}
SOLIDS = {"Solid", "MultiSolid", "CompositeSolid"}
NO_FACES = {"MultiPoint", "MultiLineString"}


class _Error:
    """SceneErrors naming the file and, where there is one, the object."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __call__(self, message: str, where: str | None = None) -> SceneError:
        return SceneError(message, path=str(self.path), node=where)


def _refuse_constant(name: str) -> float:
    raise ValueError(f"{name} is not a JSON number")


def _decode(text: bytes | str, error: _Error, line: int | None = None) -> Any:
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as problem:
        at = line if line is not None else problem.lineno
        raise SceneError(f"malformed JSON: {problem.msg}", path=str(error.path), line=at) from None
    except RecursionError:
        raise error("malformed JSON: nested too deeply") from None
    except ValueError as problem:  # NaN, Infinity, an integer of 4,300 digits, bad UTF-8
        raise error(f"malformed JSON: {problem}") from None


@dataclass
class _Model:
    """What every city object of a file (or of one CityJSONSeq feature) is
    read against: its decompressed vertices (file coordinates) and the
    file's geometry templates."""

    vertices: np.ndarray
    objects: dict[str, Any]
    templates: list[Any]
    template_vertices: np.ndarray


@dataclass
class _Budget:
    """Points placed from templates so far, against ``MAX_TEMPLATE_POINTS``."""

    placed: int = 0

    def spend(self, count: int, where: str, error: _Error) -> None:
        self.placed += count
        if self.placed > MAX_TEMPLATE_POINTS:
            raise error(
                f"geometry templates placed more than {MAX_TEMPLATE_POINTS:,} points "
                "(shadowgeo.limits.MAX_TEMPLATE_POINTS); refused",
                where,
            )


def _numbers(value: Any, size: int, what: str, error: _Error) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise error(f"{what} must be {size} numbers, got {str(value)[:60]}") from None
    if array.shape != (size,) or not np.all(np.isfinite(array)):
        raise error(f"{what} must be {size} finite numbers, got {str(value)[:60]}")
    return array


def _points(value: Any, what: str, error: _Error) -> np.ndarray:
    """(n, 3) float64 of a JSON list of [x, y, z]."""
    if not isinstance(value, list):
        raise error(f"{what} must be a list of [x, y, z]")
    if not value:
        return np.zeros((0, 3))
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise error(f"{what} must be a list of [x, y, z] numbers") from None
    if array.ndim != 2 or array.shape[1] != 3:
        raise error(f"{what} must be a list of [x, y, z] numbers")
    return array


def _vertices(document: dict[str, Any], header: dict[str, Any], error: _Error) -> np.ndarray:
    """The document's vertices decompressed by ``header``'s transform."""
    points = _points(document.get("vertices", []), "vertices", error)
    transform = header.get("transform")
    if transform is None:
        return points
    if not isinstance(transform, dict):
        raise error("transform must be an object with scale and translate")
    scale = _numbers(transform.get("scale"), 3, "transform scale", error)
    translate = _numbers(transform.get("translate"), 3, "transform translate", error)
    with np.errstate(over="ignore", invalid="ignore"):  # checked per object
        decompressed: np.ndarray = points * scale + translate
    return decompressed


def _templates(header: dict[str, Any], error: _Error) -> tuple[list[Any], np.ndarray]:
    section = header.get("geometry-templates")
    if section is None:
        return [], np.zeros((0, 3))
    if not isinstance(section, dict) or not isinstance(section.get("templates"), list):
        raise error("geometry-templates must be an object with a templates list")
    points = _points(section.get("vertices-templates", []), "vertices-templates", error)
    return section["templates"], points


def _header(document: Any, error: _Error) -> dict[str, Any]:
    if not isinstance(document, dict) or document.get("type") != "CityJSON":
        raise error('not CityJSON: the top-level "type" is not "CityJSON"')
    version = str(document.get("version", ""))
    if not version.startswith(VERSIONS):
        raise error(f"CityJSON version {version!r} is not read (1.0, 1.1, 2.0 are)")
    return document


def _models(path: Path, error: _Error) -> tuple[dict[str, Any], list[_Model]]:
    """The file's header and its models: one for a CityJSON file, one per
    CityJSONFeature for a CityJSONSeq (each with its own vertices)."""
    data = x3d_parse.read_bytes(path)
    if not path.name.lower().endswith(".jsonl"):
        header = _header(_decode(data, error), error)
        features: Iterator[tuple[dict[str, Any], int]] = iter([(header, 1)])
    else:
        lines = [
            (number, line)
            for number, line in enumerate(data.splitlines(), 1)
            if line.strip(b" \t\r\x1e")  # RFC 7464's record separator
        ]
        if not lines:
            raise error("empty CityJSONSeq")
        first, text = lines[0]
        header = _header(_decode(text.strip(b"\x1e"), error, first), error)
        features = (
            (_decode(text.strip(b"\x1e"), error, number), number) for number, text in lines[1:]
        )
    templates, template_vertices = _templates(header, error)
    models = []
    for feature, number in features:
        if feature is not header and (
            not isinstance(feature, dict) or feature.get("type") != "CityJSONFeature"
        ):
            raise SceneError("not a CityJSONFeature", path=str(path), line=number)
        objects = feature.get("CityObjects", {})
        if not isinstance(objects, dict):
            raise SceneError("CityObjects must be an object", path=str(path), line=number)
        vertices = _vertices(feature, header, error)
        models.append(_Model(vertices, objects, templates, template_vertices))
    return header, models


def _crs(header: dict[str, Any], error: _Error) -> str | None:
    metadata = header.get("metadata") or {}
    if not isinstance(metadata, dict):
        raise error("metadata must be an object")
    system = metadata.get("referenceSystem")
    if system is None:
        return None
    if not isinstance(system, str):
        raise error(f"metadata referenceSystem must be a string, got {str(system)[:60]}")
    return system


def _lod_key(lod: Any) -> tuple[int, ...]:
    """``"2.2"`` -> (2, 2); a LoD that is not numbers sorts lowest."""
    try:
        return tuple(int(part) for part in str(lod).split("."))
    except ValueError:
        return (-1,)


def _wanted(lod: Any, chosen: str | None) -> bool:
    if chosen is None:
        return True
    text = str(lod)
    return text == chosen or ("." not in chosen and text.split(".")[0] == chosen)


def _resolved(
    geometry: Any, model: _Model, budget: _Budget, where: str, error: _Error
) -> tuple[Any, np.ndarray]:
    """(geometry with boundaries, its points in file coordinates): the
    geometry and the model's vertices, or for a GeometryInstance its
    template and the template's points placed by the instance."""
    if not isinstance(geometry, dict):
        raise error("a geometry must be an object", where)
    if geometry.get("type") != "GeometryInstance":
        return geometry, model.vertices
    template = geometry.get("template")
    if not isinstance(template, int) or not 0 <= template < len(model.templates):
        raise error(f"GeometryInstance template {template!r} is not one of the file's", where)
    matrix = _numbers(geometry.get("transformationMatrix"), 16, "transformationMatrix", error)
    reference = geometry.get("boundaries")
    if (
        not isinstance(reference, list)
        or len(reference) != 1
        or not isinstance(reference[0], int)
        or not 0 <= reference[0] < len(model.vertices)
    ):
        raise error("GeometryInstance boundaries must be one vertex index", where)
    budget.spend(len(model.template_vertices), where, error)
    rows = matrix.reshape(4, 4)  # row-major, for column vectors
    placed = model.template_vertices @ rows[:3, :3].T + rows[:3, 3] + model.vertices[reference[0]]
    found = model.templates[template]
    if not isinstance(found, dict):
        raise error(f"geometry template {template} must be an object", where)
    return found, placed


def _surface_kind(index: Any, surfaces: list[Any], where: str, error: _Error) -> str | None:
    if index is None:
        return None
    if not isinstance(index, int) or not 0 <= index < len(surfaces):
        raise error(f"semantics value {index!r} is not one of its {len(surfaces)} surfaces", where)
    kind = surfaces[index].get("type") if isinstance(surfaces[index], dict) else None
    if not isinstance(kind, str):
        raise error(f"semantic surface {index} has no type", where)
    return kind


def _walk(
    boundaries: Any, values: Any, depth: int, where: str, error: _Error
) -> Iterator[tuple[list[list[Any]], Any]]:
    """Each surface (a list of rings, as the file has them) of
    ``boundaries`` ``depth`` list levels above the surfaces, with its
    semantics value (from ``values``, the same nesting, or None); the rings'
    contents and the value are checked by the caller."""
    if not isinstance(boundaries, list):
        raise error("boundaries do not nest as the geometry type says", where)
    if values is not None and (not isinstance(values, list) or len(values) != len(boundaries)):
        raise error("semantics values do not match the boundaries", where)
    for number, item in enumerate(boundaries):
        value = None if values is None else values[number]
        if depth > 0:
            yield from _walk(item, value, depth - 1, where, error)
            continue
        if not isinstance(item, list) or not all(isinstance(ring, list) for ring in item):
            raise error("a surface must be a list of rings of vertex indices", where)
        if item:
            yield item, value


def _ring(ring: list[Any], count: int, where: str, error: _Error) -> np.ndarray:
    """A ring's vertex indices, checked to be integers below ``count``."""
    if not all(type(index) is int for index in ring):
        raise error("a ring must be a list of vertex indices", where)
    outside = [index for index in ring if not 0 <= index < count]
    if outside:  # (checked as Python integers: one may pass int64's range)
        bad = str(outside[0])
        shown = bad if len(bad) <= 20 else f"{bad[:12]}... ({len(bad)} digits)"
        raise error(f"vertex index {shown} is out of range ({count} vertices)", where)
    return np.array(ring, dtype=np.int64) if ring else np.zeros(0, np.int64)


@dataclass(frozen=True)
class _Polygons:
    """A geometry's polygons: every ring's vertex indices end to end, how
    many each ring has, how many rings each polygon has, and each polygon's
    semantic kind."""

    indices: np.ndarray
    ring_sizes: list[int]
    polygon_sizes: list[int]
    kinds: list[str | None]


def _polygons(
    geometry: Any, listed: list[Any], values: Any, count: int, where: str, error: _Error
) -> _Polygons:
    """The polygons of ``geometry`` (whose points number ``count``), checked:
    all the rings' indices at once, as one array. On any problem the checks
    run again one surface at a time, in the file's order, for the message
    naming the first."""
    try:
        surfaces = list(
            _walk(geometry.get("boundaries"), values, DEPTHS[geometry.get("type")], where, error)
        )
        kinds = [_surface_kind(value, listed, where, error) for _, value in surfaces]
        rings = [ring for item, _ in surfaces for ring in item]
        flat = list(chain.from_iterable(rings))
        integers = set(map(type, flat)) <= {int}
        indices = np.array(flat if integers else [], dtype=np.int64)
    except (SceneError, OverflowError):
        integers = False
    if not integers or (len(indices) and (indices.min() < 0 or indices.max() >= count)):
        raise _first_problem(geometry, listed, values, count, where, error)
    return _Polygons(
        indices, [len(ring) for ring in rings], [len(item) for item, _ in surfaces], kinds
    )


def _first_problem(
    geometry: Any, listed: list[Any], values: Any, count: int, where: str, error: _Error
) -> Exception:
    """The error that checking ``geometry``'s surfaces one at a time (each
    one's rings, then its semantics) raises first."""
    try:
        for item, value in _walk(
            geometry.get("boundaries"), values, DEPTHS[geometry.get("type")], where, error
        ):
            for ring in item:
                _ring(ring, count, where, error)
            _surface_kind(value, listed, where, error)
    except SceneError as problem:
        return problem
    raise AssertionError("the whole check failed where the surfaces one at a time pass")


def _gather(
    chosen: list[tuple[Any, np.ndarray]], where: str, error: _Error
) -> tuple[np.ndarray, Surfaces, bool]:
    """The object's points (file coordinates; only those its polygons use),
    its polygons indexing them, and whether every geometry is a solid."""
    surfaces, pieces, base = Surfaces(), [], 0
    for geometry, points in chosen:
        semantics = geometry.get("semantics") or {}
        if not isinstance(semantics, dict):
            raise error("semantics must be an object", where)
        listed = semantics.get("surfaces", [])
        if not isinstance(listed, list):
            raise error("semantics surfaces must be a list", where)
        polygons = _polygons(geometry, listed, semantics.get("values"), len(points), where, error)
        if not polygons.ring_sizes:
            continue
        keep = np.unique(polygons.indices)
        moved = np.searchsorted(keep, polygons.indices) + base
        ends = np.cumsum(polygons.ring_sizes).tolist()
        rings = [
            moved[end - size : end] for end, size in zip(ends, polygons.ring_sizes, strict=True)
        ]
        first = 0
        for size, kind in zip(polygons.polygon_sizes, polygons.kinds, strict=True):
            surfaces.add(rings[first : first + size], kind)
            first += size
        pieces.append(points[keep])
        base += len(keep)
    solid = all(geometry.get("type") in SOLIDS for geometry, _ in chosen)
    points = np.concatenate(pieces) if pieces else np.zeros((0, 3))
    return points, surfaces, solid


def _object_geometry(
    name: str,
    body: Any,
    model: _Model,
    lod: str | None,
    budget: _Budget,
    notes: list[str],
    error: _Error,
) -> list[tuple[Any, np.ndarray]]:
    """The geometries of object ``name`` to read (its chosen LoD), resolved."""
    where = f"CityObject {name!r}"
    if not isinstance(body, dict):
        raise error("a city object must be an object", where)
    listed = body.get("geometry", [])
    if not isinstance(listed, list):
        raise error("geometry must be a list", where)
    resolved = [_resolved(geometry, model, budget, where, error) for geometry in listed]
    faces = _with_faces(resolved, where, notes, error)
    wanted = [item for item in faces if _wanted(item[0].get("lod"), lod)]
    if faces and not wanted:
        notes.append(f"{error.path.name}: {where}: no LoD {lod} geometry; left out")
    if not wanted:
        return []
    top = max(_lod_key(geometry.get("lod")) for geometry, _ in wanted)
    return [item for item in wanted if _lod_key(item[0].get("lod")) == top]


def _with_faces(
    resolved: list[tuple[Any, np.ndarray]], where: str, notes: list[str], error: _Error
) -> list[tuple[Any, np.ndarray]]:
    """The geometries of ``resolved`` that have faces (points and lines
    skipped with a note); a type that is none of them is an error."""
    faces = []
    for geometry, points in resolved:
        kind = geometry.get("type")
        if not isinstance(kind, str):
            raise error(f"a geometry's type must be a string, got {json_kind(kind)}", where)
        if kind in DEPTHS:
            faces.append((geometry, points))
        elif kind in NO_FACES:
            notes.append(f"{error.path.name}: {where}: skipped a {kind} (no faces)")
        else:
            raise error(f"unknown geometry type {kind!r}", where)
    return faces


def read(
    path: str | os.PathLike[str],
    *,
    lod: str | None = None,
    types: Collection[str] | None = None,
    **options: Any,
) -> Scene:
    """Read a CityJSON or CityJSONSeq file into a Z-up :class:`Scene`.

    Parameters
    ----------
    path : str or Path
        ``.city.json`` / ``.json`` (CityJSON), ``.city.jsonl`` (CityJSONSeq).
    lod : str, optional
        The level of detail to read (``"2.2"``, or ``"2"`` for the highest
        2.x); default the highest each object has.
    types : collection of str, optional
        City object types to read (``{"Building", "BuildingPart"}``);
        default all.

    Returns
    -------
    Scene
        One shape per city object with geometry, named by its id, with
        :attr:`Shape.semantics`; ``site`` from the file's CRS (None without
        one); ``up_axis="Z"``.

    Raises
    ------
    SceneError
        A file that is not CityJSON, malformed JSON, a geometry whose
        boundaries, indices or semantics do not fit its type, a CRS pyproj
        does not know; the message names the file and the city object.
    """
    path = Path(path)
    error = _Error(path)
    if options:
        raise error(f"the CityJSON reader takes lod and types, got {sorted(options)}")
    header, models = _models(path, error)
    notes: list[str] = []
    budget = _Budget()
    gathered: list[tuple[str, np.ndarray, Surfaces, bool]] = []
    for model in models:
        for name, body in model.objects.items():
            kind = body.get("type") if isinstance(body, dict) else None
            if types is not None and not (isinstance(kind, str) and kind in types):
                continue
            chosen = _object_geometry(str(name), body, model, lod, budget, notes, error)
            if chosen:
                gathered.append((str(name), *_gather(chosen, f"CityObject {name!r}", error)))
    located = _georeference(header, [points for _, points, _, _ in gathered], error)
    objects = [
        CityObject(name, points, surfaces, solid or None)
        for name, points, surfaces, solid in gathered
    ]
    if located is not None:
        place(objects, located, path)
    shapes = city_shapes(objects, path=path, kind="CityObject")
    if not shapes:
        raise error("no city object with faces in the file")
    return city_scene(shapes, path, located, notes)


def _georeference(
    header: dict[str, Any], points: list[np.ndarray], error: _Error
) -> Georeference | None:
    """The file's georeference, from the box of the points read."""
    system = _crs(header, error)
    if system is None or not points:
        return None
    stacked = np.concatenate(points)
    finite = stacked[np.all(np.isfinite(stacked), axis=1)]
    if not len(finite):
        return None
    return georeference(system, finite.min(axis=0), finite.max(axis=0), str(error.path))
