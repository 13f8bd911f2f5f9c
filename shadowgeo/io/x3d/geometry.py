"""X3D geometry nodes to triangles in the node's own frame.

:func:`geometry` turns one geometry element into a :class:`Mesh` (explicit
vertices: IndexedFaceSet, the triangle and quad sets, ElevationGrid, Extrusion) or a
:class:`Primitive` (Box, Sphere, Cone, Cylinder), which the reader tessellates
once it knows the scene's size and hence the chord tolerance. Faces are
counter-clockwise (``ccw="false"`` is flipped here).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ... import limits
from ...errors import GeometryError
from ...plane2d import polygons_triangles
from ...scene import Material, primitives
from .extrusion import extrusion
from .fields import Context, Element, local_name
from .tables import DEFAULTS

__all__ = [
    "COORDINATES",
    "GEOMETRY",
    "Instance",
    "MESHES",
    "Mesh",
    "PRIMITIVES",
    "PRIMITIVE_CREASE",
    "Primitive",
    "UNMODELLED_GEOMETRY",
    "coordinates",
    "geometry",
]

PRIMITIVES = {"Box", "Sphere", "Cone", "Cylinder"}
# Smooth across a curved primitive's facets (a few degrees apart), sharp at a
# Cylinder's or Cone's rim (90 degrees or more).
PRIMITIVE_CREASE = 0.5
MESHES = {
    "IndexedFaceSet", "IndexedTriangleSet", "TriangleSet", "IndexedQuadSet", "QuadSet",
    "ElevationGrid", "IndexedTriangleFanSet", "IndexedTriangleStripSet", "TriangleFanSet",
    "TriangleStripSet", "Extrusion",
}  # fmt: skip
GEOMETRY = PRIMITIVES | MESHES
COORDINATES = {"Coordinate", "CoordinateDouble", "GeoCoordinate"}
# Geometry that has no area to cast a shadow with, or that shadowgeo does not model.
UNMODELLED_GEOMETRY = {
    "Text", "IndexedLineSet", "LineSet", "PointSet", "Arc2D", "ArcClose2D",
    "Circle2D", "Disk2D", "Polyline2D", "Polypoint2D", "Rectangle2D", "TriangleSet2D",
    "NurbsPatchSurface", "NurbsTrimmedSurface", "GeoElevationGrid", "ParticleSystem",
}  # fmt: skip


@dataclass
class Mesh:
    """Explicit triangles: (n, 3) float64 vertices, (m, 3) int64 faces."""

    vertices: np.ndarray
    faces: np.ndarray
    solid: bool = True
    notes: list[str] = field(default_factory=list)
    crease_angle: float = 0.0  # X3D creaseAngle: how the browser smooths its normals


@dataclass
class Instance:
    """One rendered Shape: its geometry under a world transform (4x4);
    ``casts_shadow`` False for X3D 4's ``castShadow="false"`` or Castle's
    ``Appearance { shadowCaster FALSE }``. ``within``: the ids of the
    grouping node instances (Inline's too) it lies in, outermost first (see
    :attr:`~shadowgeo.SceneLight.scope`)."""

    geometry: Mesh | Primitive
    transform: np.ndarray
    material: Material
    name: str | None
    source: str
    role: str = "geometry"
    group: str | None = None
    casts_shadow: bool = True
    within: tuple[int, ...] = ()


@dataclass
class Primitive:
    """A primitive to tessellate later: ``kind`` and the keyword arguments of
    :mod:`shadowgeo.scene.primitives`; ``radius`` bounds it around the origin."""

    kind: str
    parameters: dict[str, Any]
    radius: float
    solid: bool = True

    @property
    def key(self) -> tuple[Any, ...]:
        """Equal for equal primitives (which share one tessellation)."""
        return (self.kind, tuple(sorted(self.parameters.items())))

    def tessellate(self, chord: float) -> Mesh:
        if self.kind == "Box":
            vertices, faces = primitives.box(**self.parameters)
        else:
            make: dict[str, Callable[..., tuple[np.ndarray, np.ndarray]]] = {
                "Sphere": primitives.sphere,
                "Cone": primitives.cone,
            }
            build: Callable[..., tuple[np.ndarray, np.ndarray]]
            build = make.get(self.kind, primitives.cylinder)
            vertices, faces = build(chord=chord, **self.parameters)
        notes = []
        if self.kind == "Sphere":
            reached = primitives.inscribed_deviation(vertices, faces, self.radius)
            if reached > chord:
                notes.append(f"Sphere tessellation capped: within {reached:.3g}, not {chord:.3g}")
        # Browsers shade Sphere, Cone and Cylinder with the true surface's
        # normals: smooth across the tessellation, sharp at the rims.
        crease = 0.0 if self.kind == "Box" else PRIMITIVE_CREASE
        return Mesh(vertices, faces, self.solid, notes, crease)


def geometry(context: Context, element: Element) -> Mesh | Primitive:
    """Geometry of one X3D geometry element (USE already resolved)."""
    tag = local_name(element)
    solid = context.field(element, "solid")
    if tag in PRIMITIVES:
        return _primitive(context, element, tag, solid)
    if tag not in ("ElevationGrid", "Extrusion") and not context.children(element, COORDINATES):
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64), solid, ["no Coordinate node"])
    mesh = _MESH_BUILDERS[tag](context, element)
    if context.field(element, "ccw") is False:
        mesh.faces = mesh.faces[:, ::-1].copy()
    mesh.solid = solid
    if "creaseAngle" in DEFAULTS.get(tag, {}):
        mesh.crease_angle = float(context.field(element, "creaseAngle"))
    return mesh


def _primitive(context: Context, element: Element, tag: str, solid: bool) -> Primitive:
    def positive(name: str) -> float:
        value = context.field(element, name)
        if not value > 0:
            raise context.error(element, f"field {name}: {value!r} must be > 0")
        try:
            return limits.check_length(value, f"field {name}:")
        except GeometryError as problem:
            raise context.error(element, str(problem)) from None

    if tag == "Box":
        size = context.field(element, "size")
        if not np.all(size > 0):
            raise context.error(element, f"field size: {size.tolist()} must be > 0")
        if float(size.min()) < limits.SMALLEST_LENGTH:
            raise context.error(
                element,
                f"field size: {float(size.min())!r} is below the smallest supported length "
                f"{limits.SMALLEST_LENGTH:g}",
            )
        return Primitive(tag, {"size": tuple(size)}, float(np.linalg.norm(size)) / 2, solid)
    if tag == "Sphere":
        radius = positive("radius")
        return Primitive(tag, {"radius": radius}, radius, solid)
    height = positive("height")
    if tag == "Cone":
        radius = positive("bottomRadius")
        flags = {key: context.field(element, key) for key in ("side", "bottom")}
        parameters = {"bottom_radius": radius, "height": height, **flags}
    else:
        radius = positive("radius")
        flags = {key: context.field(element, key) for key in ("side", "top", "bottom")}
        parameters = {"radius": radius, "height": height, **flags}
    return Primitive(tag, parameters, float(np.hypot(radius, height / 2)), solid)


def coordinates(context: Context, element: Element) -> np.ndarray:
    """(n, 3) points of the element's Coordinate or CoordinateDouble child."""
    nodes = context.children(element, COORDINATES)
    if not nodes:
        return np.zeros((0, 3))
    node = nodes[0]
    if local_name(node) == "GeoCoordinate":
        raise context.error(node, "GeoCoordinate is not supported (no geospatial frames)")
    points: np.ndarray = context.field(node, "point").reshape(-1, 3)
    return points


def _checked(
    context: Context, element: Element, name: str, indices: np.ndarray, n_points: int
) -> np.ndarray:
    if not indices.size or (indices.max() < n_points and indices.min() >= -1):
        return indices
    bad = (indices >= n_points) | (indices < -1)
    if np.any(bad):
        first = int(indices[np.argmax(bad)])
        raise context.error(element, f"{name} {first} is out of range ({n_points} points)")
    return indices


def _polygons(indices: np.ndarray) -> list[np.ndarray]:
    """Split an index list at -1 separators; empty pieces dropped."""
    cuts = np.flatnonzero(indices == -1)
    pieces = np.split(indices, cuts)
    return [piece[piece != -1] for piece in pieces if np.count_nonzero(piece != -1)]


def _polygon_blocks(indices: np.ndarray) -> dict[int, np.ndarray]:
    """Polygons of a -1 separated index list grouped by size: size -> (m, size)."""
    separator = indices == -1
    polygon = np.cumsum(separator)[~separator]
    kept = indices[~separator]
    if not len(kept):
        return {}
    _, starts, sizes = np.unique(polygon, return_index=True, return_counts=True)
    return {
        int(size): kept[starts[sizes == size][:, None] + np.arange(size)]
        for size in np.unique(sizes)
    }


def _indexed_face_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    indices = _checked(
        context, element, "coordIndex", context.field(element, "coordIndex"), len(points)
    )
    convex = context.field(element, "convex")
    faces, notes, short = [], [], 0
    for size, block in _polygon_blocks(indices).items():
        if size < 3:
            short += len(block)
            continue
        # convex="false" says only that some may not be: fan those that are
        faces.append(polygons_triangles(points, block, convex=bool(convex))[0])
    if short:
        notes.append(f"{short} polygon(s) with fewer than 3 points skipped")
    return Mesh(points, _stack(faces), notes=notes)


def _stack(faces: list[np.ndarray]) -> np.ndarray:
    return np.concatenate(faces).astype(np.int64) if faces else np.zeros((0, 3), np.int64)


def _indexed_triangle_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    index = _checked(context, element, "index", context.field(element, "index"), len(points))
    notes = [f"{len(index) % 3} trailing index value(s) ignored"] if len(index) % 3 else []
    return Mesh(points, index[: len(index) // 3 * 3].reshape(-1, 3), notes=notes)


def _triangle_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    count = len(points) // 3 * 3
    notes = [f"{len(points) - count} trailing point(s) ignored"] if len(points) - count else []
    return Mesh(points, np.arange(count, dtype=np.int64).reshape(-1, 3), notes=notes)


def _indexed_quad_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    index = _checked(context, element, "index", context.field(element, "index"), len(points))
    notes = [f"{len(index) % 4} trailing index value(s) ignored"] if len(index) % 4 else []
    quads = index[: len(index) // 4 * 4].reshape(-1, 4)
    return Mesh(points, primitives.quads_to_triangles(quads), notes=notes)


def _quad_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    count = len(points) // 4 * 4
    notes = [f"{len(points) - count} trailing point(s) ignored"] if len(points) - count else []
    quads = np.arange(count, dtype=np.int64).reshape(-1, 4)
    return Mesh(points, primitives.quads_to_triangles(quads), notes=notes)


def _fans(runs: list[np.ndarray]) -> np.ndarray:
    fans = [
        np.column_stack([run[0].repeat(len(run) - 2), run[1:-1], run[2:]])
        for run in runs
        if len(run) >= 3
    ]
    return _stack(fans)


def _strips(runs: list[np.ndarray]) -> np.ndarray:
    out = []
    for run in runs:
        if len(run) < 3:
            continue
        tri = np.column_stack([run[:-2], run[1:-1], run[2:]])
        tri[1::2] = tri[1::2][:, [1, 0, 2]]  # every other triangle of a strip is reversed
        out.append(tri)
    return _stack(out)


def _runs_from_counts(
    context: Context, element: Element, name: str, n_points: int
) -> list[np.ndarray]:
    counts = context.field(element, name)
    if np.any(counts < 3) or counts.sum() > n_points:
        raise context.error(
            element, f"{name} {counts.tolist()[:8]} needs counts >= 3 summing to <= {n_points}"
        )
    return np.split(np.arange(int(counts.sum())), np.cumsum(counts)[:-1])


def _indexed_fan_or_strip(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    index = _checked(context, element, "index", context.field(element, "index"), len(points))
    runs = _polygons(index)
    fan = local_name(element) == "IndexedTriangleFanSet"
    return Mesh(points, _fans(runs) if fan else _strips(runs))


def _fan_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    return Mesh(points, _fans(_runs_from_counts(context, element, "fanCount", len(points))))


def _strip_set(context: Context, element: Element) -> Mesh:
    points = coordinates(context, element)
    return Mesh(points, _strips(_runs_from_counts(context, element, "stripCount", len(points))))


def _elevation_grid(context: Context, element: Element) -> Mesh:
    nx, nz = context.field(element, "xDimension"), context.field(element, "zDimension")
    heights = context.field(element, "height")
    if nx < 0 or nz < 0 or len(heights) < nx * nz:
        needed = max(nx, 0) * max(nz, 0)
        message = f"height has {len(heights)} values; xDimension {nx} x zDimension {nz} needs"
        raise context.error(element, f"{message} {needed}")
    if nx < 2 or nz < 2:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    dx, dz = context.field(element, "xSpacing"), context.field(element, "zSpacing")
    j, i = np.meshgrid(np.arange(nz), np.arange(nx), indexing="ij")  # height[i + j * nx]
    vertices = np.column_stack([i.ravel() * dx, heights[: nx * nz], j.ravel() * dz])
    corner = (i[:-1, :-1] + j[:-1, :-1] * nx).ravel()
    # (i, j) -> (i, j+1) -> (i+1, j+1) -> (i+1, j): Z x X = +Y, CCW seen from above
    quads = np.column_stack([corner, corner + nx, corner + nx + 1, corner + 1])
    return Mesh(vertices, primitives.quads_to_triangles(quads).astype(np.int64))


def _extrusion(context: Context, element: Element) -> Mesh:
    return Mesh(*extrusion(context, element))


_MESH_BUILDERS = {
    "Extrusion": _extrusion,
    "IndexedFaceSet": _indexed_face_set,
    "IndexedTriangleSet": _indexed_triangle_set,
    "TriangleSet": _triangle_set,
    "IndexedQuadSet": _indexed_quad_set,
    "QuadSet": _quad_set,
    "ElevationGrid": _elevation_grid,
    "IndexedTriangleFanSet": _indexed_fan_or_strip,
    "IndexedTriangleStripSet": _indexed_fan_or_strip,
    "TriangleFanSet": _fan_set,
    "TriangleStripSet": _strip_set,
}
