"""2-D regions: union by winding, intersection, decomposition, triangulation.

One thin wrapper over manifold3d's ``CrossSection`` (Clipper2 in C++). Clipper2
rounds coordinates to 1e-8, so callers work in a *local frame* whose units make
the region as large as Clipper2 handles safely (``MAX_COORDINATE``); rounding
then costs about 1e-16 of the region's size.
"""

from __future__ import annotations

import numpy as np
from manifold3d import CrossSection, FillRule, triangulate

from .plane import Plane

# Coordinates handed to Clipper2 stay below this (it accepts about 4e10 before
# its 1e8 fixed-point scaling overflows int64's safe range).
MAX_COORDINATE = 1e8


def local_scale(extent: float) -> float:
    """Units per length that put the largest coordinate that will occur,
    ``extent``, at ``MAX_COORDINATE``: Clipper2's fixed 1e-8 grid is then
    about 1e-16 of the region's size."""
    return MAX_COORDINATE / extent


def signed_areas(loops: list[np.ndarray]) -> np.ndarray:
    """Shoelace signed area of each (k, 2) loop, positive counter-clockwise."""
    out = np.empty(len(loops))
    for i, loop in enumerate(loops):
        x, y = loop[:, 0], loop[:, 1]
        out[i] = 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    return out


def fill(loops: list[np.ndarray], rule: str = "positive") -> CrossSection:
    """The region of points whose winding number over ``loops`` passes ``rule``
    (``"positive"``: > 0, ``"nonzero"``, ``"evenodd"``)."""
    if not loops:
        return CrossSection()
    fill_rule = {
        "positive": FillRule.Positive,
        "nonzero": FillRule.NonZero,
        "evenodd": FillRule.EvenOdd,
    }[rule]
    return CrossSection([np.ascontiguousarray(loop, dtype=np.float64) for loop in loops], fill_rule)


def intersect(region: CrossSection, other: CrossSection) -> CrossSection:
    return region ^ other


def components(region: CrossSection) -> list[list[np.ndarray]]:
    """Connected parts of ``region``, each ``[outer, hole, ...]``: outer loop
    counter-clockwise, holes clockwise, as (k, 2) float64 arrays.

    Every part has a positive area. Clipper2 rounds to its fixed grid, and a
    sliver thinner than the grid can come back inside out (a negative area):
    such a part has no area worth the name and is dropped.
    """
    parts = []
    for part in region.decompose():
        loops = [np.asarray(loop, dtype=np.float64) for loop in part.to_polygons()]
        loops = [loop for loop in loops if len(loop) >= 3]
        if not loops:
            continue
        areas = signed_areas(loops)
        if areas.max() <= 0 or areas.sum() <= 0:
            continue
        order = np.argsort(-areas)  # the outer loop has the largest (positive) area
        parts.append([loops[i] for i in order])
    return parts


def parts_area(parts: list[list[np.ndarray]]) -> float:
    """Area of :func:`components`' parts (outer loops minus holes), >= 0."""
    return float(sum(signed_areas(loops).sum() for loops in parts))


def triangulate_parts(parts: list[list[np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate polygons with holes into non-overlapping counter-clockwise
    triangles. Returns (n, 2) vertices and (m, 3) faces."""
    vertices, faces, base = [], [], 0
    for loops in parts:
        tris = np.asarray(triangulate(loops), dtype=np.int64).reshape(-1, 3)
        points = np.concatenate(loops)
        vertices.append(points)
        faces.append(tris + base)
        base += len(points)
    if not vertices:
        return np.zeros((0, 2)), np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(vertices), np.concatenate(faces)


def polygon_triangles(points: np.ndarray) -> np.ndarray:
    """Triangulate one simple polygon (k, 3), convex or not, in its own plane.

    Returns (m, 3) indices into ``points``, wound as the polygon is (its Newell
    normal). A polygon with no area gives no triangles.
    """
    shifted = np.roll(points, -1, axis=0)
    normal = np.array(
        [
            np.sum((points[:, 1] - shifted[:, 1]) * (points[:, 2] + shifted[:, 2])),
            np.sum((points[:, 2] - shifted[:, 2]) * (points[:, 0] + shifted[:, 0])),
            np.sum((points[:, 0] - shifted[:, 0]) * (points[:, 1] + shifted[:, 1])),
        ]
    )
    length = float(np.linalg.norm(normal))
    if length == 0.0 or not np.isfinite(length):
        return np.zeros((0, 3), dtype=np.int64)
    u, v = Plane(normal).basis  # u x v = normal: the polygon runs CCW in (u, v)
    centred = points - points.mean(axis=0)
    flat = np.column_stack([centred @ u, centred @ v])
    return np.asarray(triangulate([flat]), dtype=np.int64).reshape(-1, 3)
