"""X3D's primitives as triangle meshes within a chord tolerance.

Each function returns ``(vertices (n, 3) float64, faces (m, 3) int64)`` in the
primitive's own frame as X3D defines it (centred on the origin, axis +Y),
faces counter-clockwise seen from outside. Curved surfaces are inscribed:
every vertex lies on the true surface and no point of any triangle is farther
than ``chord`` from it. ``chord`` is an absolute length in the primitive's own
units; the X3D reader derives it from :attr:`Tolerance.chord_length` and the
shape's world scale. The segment count comes from :meth:`Tolerance.segments`,
never a fixed number.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import GeometryError
from ..limits import MAX_SPHERE_SEGMENTS, check_length
from ..tolerance import Tolerance

__all__ = ["box", "cone", "cylinder", "inscribed_deviation", "quads_to_triangles", "sphere"]

# A sphere gets at most MAX_SPHERE_SEGMENTS segments around (8.4 million
# triangles): a chord below about 1e-6 of its radius is then not met (the
# reader warns). Sizes must lie in shadowgeo.limits' range.


def _segments(radius: float, chord: float, sweep: float = 2 * math.pi, minimum: int = 8) -> int:
    if not (chord > 0 and math.isfinite(chord)):
        raise GeometryError(f"chord tolerance must be finite and > 0, got {chord!r}")
    # A tolerance whose chord_length is exactly ``chord``.
    return Tolerance(scale=chord, chord=1.0).segments(radius, sweep, minimum)


def _positive(value: float, name: str) -> float:
    return check_length(value, name)


def box(size: Sequence[float] = (2.0, 2.0, 2.0)) -> tuple[np.ndarray, np.ndarray]:
    """X3D Box: 8 corners at ``+-size / 2``, 12 triangles.

    Examples
    --------
    >>> vertices, faces = box((2, 4, 6))
    >>> vertices.max(axis=0).tolist(), len(faces)
    ([1.0, 2.0, 3.0], 12)
    """
    half = np.array([_positive(s, "Box size") for s in size]) / 2.0
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    # corner index = 4 * (x > 0) + 2 * (y > 0) + (z > 0); each quad CCW from outside
    quads = np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    )
    return signs * half, quads_to_triangles(quads).astype(np.int64)


def quads_to_triangles(quads: np.ndarray) -> np.ndarray:
    """(m, 4) quads to (2m, 3) triangles wound as the quads are; (0, 3) for none."""
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def _ring(radius: float, height: float, count: int) -> np.ndarray:
    """``count`` points on the circle of ``radius`` at ``y = height``; angle 0
    on +Z, increasing towards +X (so a ring seen from +Y runs clockwise)."""
    angle = np.arange(count) * (2 * math.pi / count)
    return np.column_stack([radius * np.sin(angle), np.full(count, height), radius * np.cos(angle)])


def _cap(center: int, start: int, count: int, upward: bool) -> np.ndarray:
    """Fan from ``center`` over a ring stored at ``start``; facing +Y if upward."""
    i = np.arange(count)
    a, b = start + i, start + (i + 1) % count
    fan = np.column_stack([np.full(count, center), a, b])
    return fan if upward else fan[:, [0, 2, 1]]


def cylinder(
    radius: float = 1.0,
    height: float = 2.0,
    chord: float = 1e-3,
    *,
    side: bool = True,
    top: bool = True,
    bottom: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """X3D Cylinder from ``y = -height/2`` to ``height/2``; the side and caps
    are inscribed polygons whose sagitta ``r (1 - cos(pi / n))`` is at most ``chord``.

    Parameters
    ----------
    radius, height : float
        > 0.
    chord : float
        Largest distance of the mesh from the true surface (absolute).
    side, top, bottom : bool
        Which parts to make (X3D's fields of the same names).

    Returns
    -------
    vertices : (n, 3) float64
    faces : (m, 3) int64

    Examples
    --------
    >>> vertices, faces = cylinder(1.0, 2.0, chord=0.01)
    >>> n = len(vertices) // 2 - 1  # two rings and two cap centres
    >>> n, round(1 - math.cos(math.pi / n), 4) <= 0.01
    (23, True)
    """
    radius, height = _positive(radius, "Cylinder radius"), _positive(height, "Cylinder height")
    count = _segments(radius, chord)
    lower, upper = _ring(radius, -height / 2, count), _ring(radius, height / 2, count)
    vertices = np.concatenate([lower, upper, [[0, -height / 2, 0], [0, height / 2, 0]]])
    i = np.arange(count)
    j = (i + 1) % count
    parts = []
    if side:
        # Ring angle grows from +Z to +X: outward CCW is lower[i], lower[j], upper[j].
        parts += [np.column_stack([i, j, count + j]), np.column_stack([i, count + j, count + i])]
    if bottom:
        parts.append(_cap(2 * count, 0, count, upward=False))
    if top:
        parts.append(_cap(2 * count + 1, count, count, upward=True))
    return _compact(vertices, parts)


def cone(
    bottom_radius: float = 1.0,
    height: float = 2.0,
    chord: float = 1e-3,
    *,
    side: bool = True,
    bottom: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """X3D Cone: base circle at ``y = -height/2``, apex at ``height/2``. Each
    side triangle is flat along its rulings, so its largest deviation is the
    base sagitta, at most ``chord``.

    Returns ``(vertices (n, 3) float64, faces (m, 3) int64)``.

    Examples
    --------
    >>> vertices, faces = cone(1.0, 2.0, chord=0.01, bottom=False)
    >>> len(faces), float(vertices[:, 1].max())
    (23, 1.0)
    """
    radius = _positive(bottom_radius, "Cone bottomRadius")
    height = _positive(height, "Cone height")
    count = _segments(radius, chord)
    base = _ring(radius, -height / 2, count)
    vertices = np.concatenate([base, [[0, height / 2, 0], [0, -height / 2, 0]]])
    i = np.arange(count)
    parts = []
    if side:
        parts.append(np.column_stack([i, (i + 1) % count, np.full(count, count)]))
    if bottom:
        parts.append(_cap(count + 1, 0, count, upward=False))
    return _compact(vertices, parts)


def sphere(radius: float = 1.0, chord: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """X3D Sphere as a latitude-longitude mesh; every vertex on the sphere.

    Each quad between two latitudes and two longitudes is an isosceles
    trapezoid, hence planar and inscribed; its largest deviation from the
    sphere is ``r - d`` with ``d`` the distance of its plane from the centre.
    The counts start from :meth:`Tolerance.segments` and grow until that bound
    is at most ``chord`` for every face, or reach :data:`MAX_SPHERE_SEGMENTS`.

    Returns ``(vertices (n, 3) float64, faces (m, 3) int64)``.

    Examples
    --------
    >>> import numpy as np
    >>> vertices, faces = sphere(2.0, chord=0.01)
    >>> bool(np.allclose(np.linalg.norm(vertices, axis=1), 2.0)), len(faces)
    (True, 1980)
    """
    radius = _positive(radius, "Sphere radius")
    _segments(radius, chord)  # checks the chord
    # Work on the unit sphere: the counts depend on chord / radius alone, so
    # the cost is bounded by the tolerance, whatever the numbers in the file.
    relative = chord / radius
    # a quad dips by about the sum of its two edges' sagittas: start at half the chord
    around = min(_segments(1.0, relative / 2), MAX_SPHERE_SEGMENTS)
    while True:
        rings = max(2, math.ceil(around / 2))
        vertices, faces = _uv_sphere(1.0, around, rings)
        if inscribed_deviation(vertices, faces, 1.0) <= relative or around >= MAX_SPHERE_SEGMENTS:
            return vertices * radius, faces
        around = min(math.ceil(around * 1.05), MAX_SPHERE_SEGMENTS)


def _uv_sphere(radius: float, around: int, rings: int) -> tuple[np.ndarray, np.ndarray]:
    polar = np.arange(1, rings) * (math.pi / rings)  # from +Y down, poles excluded
    azimuth = np.arange(around) * (2 * math.pi / around)
    sin_p, cos_p = np.sin(polar)[:, None], np.cos(polar)[:, None]
    body = np.stack(
        [
            radius * sin_p * np.sin(azimuth),
            radius * cos_p * np.ones_like(azimuth),
            radius * sin_p * np.cos(azimuth),
        ],
        axis=-1,
    ).reshape(-1, 3)
    north, south = len(body), len(body) + 1
    vertices = np.concatenate([body, [[0, radius, 0], [0, -radius, 0]]])
    i = np.arange(around)
    j = (i + 1) % around
    parts = [np.column_stack([np.full(around, north), i, j])]  # seen from +Y, azimuth is CW
    for ring in range(rings - 2):
        upper, lower = ring * around, (ring + 1) * around
        parts.append(np.column_stack([upper + i, lower + i, lower + j]))
        parts.append(np.column_stack([upper + i, lower + j, upper + j]))
    last = (rings - 2) * around
    parts.append(np.column_stack([np.full(around, south), last + j, last + i]))
    return vertices, np.concatenate(parts).astype(np.int64)


def inscribed_deviation(vertices: np.ndarray, faces: np.ndarray, radius: float) -> float:
    """Upper bound of how far the triangles of a sphere mesh centred on the
    origin dip inside the sphere of ``radius`` (computed on the unit sphere:
    no product of three coordinates to underflow)."""
    corners = vertices[faces] / radius
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    distances = np.einsum("ij,ij->i", normals, corners[:, 0]) / lengths
    return float(radius * (1.0 - distances.min()))


def _compact(vertices: np.ndarray, parts: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Keep only vertices the faces use (a Cylinder without caps drops its centres)."""
    if not parts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    faces = np.concatenate(parts).astype(np.int64)
    used, inverse = np.unique(faces, return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3).astype(np.int64)
