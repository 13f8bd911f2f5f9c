"""One city object's polygons as one :class:`~shadowgeo.scene.model.Shape`,
for the city readers (:mod:`.cityjson`, :mod:`.footprints`).

A city object (a building, a building part, a road) is a set of planar
polygons, each an outer ring and perhaps holes (ring: vertex indices into the
object's points), each of a semantic kind (``RoofSurface``, ``WallSurface``,
``GroundSurface``, ...). It becomes one shape, so a building casts as one
caster: the polygons triangulated by :mod:`shadowgeo.plane2d` (fans for
convex ones, ear clipping for the rest and for those with holes), no vertex
added, so polygons that share corners in the file share them in the mesh and
a closed solid stays closed; each triangle keeps its polygon's kind in
:attr:`Shape.semantics`. The shape's vertices are relative to the corner of
its box, placed by its transform: real-world coordinates (RD New's are
400,000 m) would otherwise lose their last digits in float32 outputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import GeometryError, SceneError
from ..limits import check_coordinates
from ..plane2d import polygon_triangles, polygons_triangles
from ..scene.model import Semantics, Shape
from ..topology import closed_by_sort

__all__ = ["CityObject", "GROUND", "ROOF", "Surfaces", "WALL", "city_shapes", "triangles"]

ROOF, WALL, GROUND = "RoofSurface", "WallSurface", "GroundSurface"


@dataclass
class Surfaces:
    """A city object's polygons, gathered as a reader walks its geometry.

    ``rings``: per polygon, its rings (int64 arrays of indices into the
    reader's points), the outer one first; ``kinds``: per polygon an index
    into ``names`` or -1; ``names``: the semantic kinds met, each once.
    """

    rings: list[list[np.ndarray]] = field(default_factory=list)
    kinds: list[int] = field(default_factory=list)
    names: list[str] = field(default_factory=list)

    def add(self, rings: list[np.ndarray], kind: str | None) -> None:
        """Add one polygon of ``kind`` (None: the file gives it none)."""
        self.add_each([rings], kind)

    def add_each(self, polygons: list[list[np.ndarray]], kind: str | None) -> None:
        """Add polygons all of ``kind``."""
        if kind is not None and kind not in self.names:
            self.names.append(kind)
        self.rings.extend(polygons)
        self.kinds.extend([-1 if kind is None else self.names.index(kind)] * len(polygons))


def _cleaned(polygons: list[list[np.ndarray]], offsets: np.ndarray) -> list[list[np.ndarray]]:
    """Each polygon's rings, moved by its offset, without repeats in a row or
    a closing copy of the first index: an index is kept when it differs from
    the next one round its ring, all rings at once (a ring of one index
    becomes empty: like one of two, it has no area and is dropped all the same)."""
    rings = [ring for polygon in polygons for ring in polygon]
    if not rings:
        return [[] for _ in polygons]
    sizes = np.array([len(ring) for ring in rings], dtype=np.int64)
    per_ring = np.repeat(offsets, [len(polygon) for polygon in polygons])
    flat = np.concatenate(rings).astype(np.int64) + np.repeat(per_ring, sizes)
    starts = np.cumsum(sizes) - sizes
    following = np.arange(1, len(flat) + 1)
    closed = sizes > 0
    following[(starts + sizes - 1)[closed]] = starts[closed]  # the last index's next is the first
    keep = flat != flat[following] if len(flat) else np.zeros(0, dtype=bool)
    owner = np.repeat(np.arange(len(rings)), sizes)
    kept_sizes = np.bincount(owner[keep], minlength=len(rings))
    ends = np.cumsum(kept_sizes).tolist()
    kept = flat[keep]
    pieces = [kept[end - size : end] for end, size in zip(ends, kept_sizes.tolist(), strict=True)]
    bounds = np.cumsum([0] + [len(polygon) for polygon in polygons])
    return [pieces[bounds[n] : bounds[n + 1]] for n in range(len(polygons))]


def triangles(
    points: np.ndarray, surfaces: Surfaces, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(t, 3) int64 triangles of every polygon (indices into ``points``: the
    polygon's own moved by its ``offsets`` entry, (p,) int64; wound as their
    outer rings) and (t,) int64 the polygon each comes from. A ring of fewer
    than three corners is dropped (it has no area)."""
    plain: dict[int, list[tuple[int, np.ndarray]]] = {}  # corner count -> polygons
    found, owners = [], []
    for number, rings in enumerate(_cleaned(surfaces.rings, offsets)):
        outer = rings[0]
        if len(outer) < 3:
            continue  # no outer ring: nothing to fill
        kept = [outer, *(ring for ring in rings[1:] if len(ring) >= 3)]
        if len(kept) == 1:
            plain.setdefault(len(kept[0]), []).append((number, kept[0]))
            continue
        order = np.concatenate(kept)
        pieces = order[polygon_triangles(points[kept[0]], [points[hole] for hole in kept[1:]])]
        found.append(pieces)
        owners.append(np.full(len(pieces), number, dtype=np.int64))
    for group in plain.values():
        numbers = np.array([number for number, _ in group], dtype=np.int64)
        block = np.stack([ring for _, ring in group])
        pieces, rows = polygons_triangles(points, block)
        found.append(pieces)
        owners.append(numbers[rows])
    if not found:
        return np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(found), np.concatenate(owners)


@dataclass
class CityObject:
    """One city object as read: ``points`` (n, 3) float64 in scene
    coordinates, its ``surfaces`` indexing them, and ``solid``: the file says
    they bound a volume (a CityJSON Solid, an extruded footprint); None: the
    shape is one-sided exactly when its triangles close up (every edge met
    once each way), else it receives on both sides."""

    name: str
    points: np.ndarray
    surfaces: Surfaces
    solid: bool | None = None


def city_shapes(objects: list[CityObject], *, path: Path, kind: str) -> list[Shape]:
    """The shape of each object that has a polygon with an area, in order
    (``kind`` is the file's word for an object, e.g. ``CityObject`` or
    ``feature``, for messages). Every object's polygons are triangulated in
    one pass: the work per object is a few array operations.

    Raises
    ------
    SceneError
        A point that is not finite or past ``limits.LARGEST_COORDINATE``,
        naming the file and the object.
    """
    if not objects:
        return []
    sizes = np.array([len(item.points) for item in objects], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    counts = np.array([len(item.surfaces.rings) for item in objects], dtype=np.int64)
    # every object's polygons, each to be moved by its object's first point
    everything = Surfaces([rings for item in objects for rings in item.surfaces.rings])
    offsets = np.repeat(starts, counts)
    points = np.concatenate([item.points for item in objects])
    _check(points, objects, path, kind)  # before triangles: a NaN corner would drop its face
    faces, polygons = triangles(points, everything, offsets)
    owner = np.repeat(np.arange(len(objects)), counts)[polygons]
    order = np.argsort(owner, kind="stable")
    bounds = np.searchsorted(owner[order], np.arange(len(objects) + 1))
    kinds = np.concatenate(
        [np.asarray(item.surfaces.kinds, dtype=np.int64).reshape(-1) for item in objects]
    )[polygons]
    # each triangle's polygon numbered within its object, as the file lists them
    numbers = polygons - (np.cumsum(counts) - counts)[owner]
    shapes = []
    for number, item in enumerate(objects):
        chosen = order[bounds[number] : bounds[number + 1]]
        if len(chosen):
            cut = Semantics(tuple(item.surfaces.names), kinds[chosen], numbers[chosen])
            shapes.append(_shape(item, points, faces[chosen], cut, path, kind))
    return shapes


def _check(points: np.ndarray, objects: list[CityObject], path: Path, kind: str) -> None:
    """SceneError naming the first object with a point that is not finite or
    is past ``limits.LARGEST_COORDINATE`` (one check of all the points; the
    objects one by one only to name the culprit)."""
    try:
        check_coordinates(points, "the file's")
    except GeometryError:
        for item in objects:
            try:
                check_coordinates(item.points, "the object's")
            except GeometryError as error:
                raise SceneError(str(error), path=str(path), node=f"{kind} {item.name!r}") from None
        raise  # pragma: no cover - the points are the objects' points


def _wound_outward(triangles: np.ndarray, kinds: np.ndarray, names: list[str]) -> bool:
    """Whether an open surface's semantics show it wound outward, as a
    building's envelope is: some GroundSurface or RoofSurface faces, no
    GroundSurface face turned up and no RoofSurface face turned down (z up).
    Such a surface receives on its outside only, like a closed one: LoD2 data
    often leaves T-junctions where walls meet roofs, and two-sided, a
    building's floor would take the shadows meant for the street."""
    normal_up = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])[:, 2]
    ground = kinds == (names.index(GROUND) if GROUND in names else -2)
    roof = kinds == (names.index(ROOF) if ROOF in names else -2)
    if not (ground.any() or roof.any()):
        return False
    return bool(np.all(normal_up[ground] <= 0) and np.all(normal_up[roof] >= 0))


def _shape(
    item: CityObject,
    points: np.ndarray,
    faces: np.ndarray,
    semantics: Semantics,
    path: Path,
    kind: str,
) -> Shape:
    """One object's shape from its triangles (indices into ``points``) and
    their ``semantics`` (kinds, indices into its surfaces' names, and polygons)."""
    where = f"{kind} {item.name!r}"
    used, local_faces = np.unique(faces, return_inverse=True)
    corners = points[used]
    # Corners the file wrote twice (same coordinates, two indices) are one
    # vertex, so the mesh is closed where the surface is.
    corners, merged = np.unique(corners, axis=0, return_inverse=True)
    local_faces = merged.reshape(-1)[local_faces.reshape(-1, 3)]
    solid = item.solid
    if solid is None:
        solid = bool(closed_by_sort(local_faces, len(corners))) or _wound_outward(
            corners[local_faces], semantics.face_kind, item.surfaces.names
        )
    origin = corners.min(axis=0)
    transform = np.eye(4)
    transform[:3, 3] = origin
    return Shape(
        corners - origin,
        local_faces,
        transform,
        name=item.name,
        solid=solid,
        source=f"{path.name}, {where}",
        semantics=semantics,
    )
