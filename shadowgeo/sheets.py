"""Mesh helpers for shadows on a surface: its shape, not its shadows.

* :func:`merge_positions` -- one index per vertex position, so faces that
  share a corner position share their edge;
* :func:`face_frames` -- an in-plane basis for every face;
* :func:`single_sheet` -- whether an open mesh is one sheet over a convex
  region, which lets a surface shadow itself through its faces turned away
  from the light only;
* :func:`lift_directions` -- how to move shadow points off the surface so
  that neighbouring faces' lifted shadows still meet;
* :func:`surface_geometry` -- all of that per-mesh work, done once per mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import GeometryError
from .limits import ANGLE_SLACK, PRODUCT_ROUNDING, RELATIVE_ROUNDING, SINGULAR_SHARE, TINY
from .silhouette import chain
from .topology import Caster

__all__ = [
    "SurfaceGeometry",
    "face_frames",
    "lift_directions",
    "merge_positions",
    "single_sheet",
    "surface_geometry",
]


def lift_directions(triangles: np.ndarray, normals: np.ndarray, n_points: int) -> np.ndarray:
    """(p, 3) the direction ``m`` to move each point by ``offset * m``: the
    least-squares solution of ``n . m = 1`` over the unit normals of the
    triangles that use it. A point inside one face moves along its normal; a
    point on an edge two faces share lands on both faces' offset planes (the
    miter), so the lifted shadow keeps its shared vertices and has no cracks;
    at a mesh vertex of three or more faces it is the closest compromise."""
    corners = triangles.reshape(-1)
    each = np.repeat(normals, 3, axis=0)
    moments = np.zeros((n_points, 3, 3))
    np.add.at(moments, corners, each[:, :, None] * each[:, None, :])
    sums = np.zeros((n_points, 3))
    np.add.at(sums, corners, each)
    direction = np.einsum("pij,pj->pi", np.linalg.pinv(moments, rcond=SINGULAR_SHARE), sums)
    # A sharp concave crease would push its miter far out: keep it bounded.
    length = np.linalg.norm(direction, axis=1, keepdims=True)
    lifted: np.ndarray = direction * np.minimum(1.0, 4.0 / np.maximum(length, TINY))
    return lifted


def single_sheet(caster: Caster) -> bool:
    """True for an open mesh that is one sheet over a convex region: every
    face turns to one direction ``up`` and the border is a single loop that
    runs once around a convex region, seen along ``up``. ``up`` is tried as
    the world axis nearest the mean normal (a terrain's), then that normal.

    Then every line along ``up`` meets the sheet at most once, so it splits the
    space over the region into a front and a back side; a ray from a point of
    the sheet, leaving on its front side, can only reach the back side by
    crossing a face from front to back -- one turned away from the ray's end.
    """
    if caster.is_closed or caster.n_faces < 2 or np.any(caster.edge_face_count > 2):
        return False
    normals = caster.face_normals
    mean = normals.sum(axis=0)
    if not np.linalg.norm(mean) > 0:
        return False
    border = caster.edge_face_count[caster.face_edges] == 1  # (m, 3) face edges
    face, corner = np.nonzero(border)
    try:
        loops = chain(caster.faces[face, corner], caster.faces[face, (corner + 1) % 3])
    except GeometryError:
        return False
    if len(loops) != 1:
        return False
    axis = np.zeros(3)
    axis[int(np.argmax(np.abs(mean)))] = np.sign(mean[int(np.argmax(np.abs(mean)))])
    points = caster.vertices[loops[0]]
    return any(_sheet_along(up, normals, points) for up in (axis, mean / np.linalg.norm(mean)))


def _sheet_along(up: np.ndarray, normals: np.ndarray, border: np.ndarray) -> bool:
    """Every face turns to ``up`` and the border loop, seen along ``up``, turns
    left or goes straight on at every corner and winds once."""
    length = np.linalg.norm(normals, axis=1)
    proper = length > 0
    if np.any(normals[proper] @ up <= RELATIVE_ROUNDING * length[proper]):
        return False
    first, second = face_frames(up[None])
    flat = np.column_stack([border @ first[0], border @ second[0]])
    steps = np.roll(flat, -1, axis=0) - flat
    following = np.roll(steps, -1, axis=0)
    turn = steps[:, 0] * following[:, 1] - steps[:, 1] * following[:, 0]
    ahead = np.einsum("ij,ij->i", steps, following)
    scale = np.linalg.norm(steps, axis=1) * np.linalg.norm(following, axis=1)
    if np.any(scale == 0):
        return False
    if np.any(turn < -PRODUCT_ROUNDING * scale) or np.any(
        (np.abs(turn) <= PRODUCT_ROUNDING * scale) & (ahead <= 0)
    ):
        return False
    return bool(abs(np.arctan2(turn, ahead).sum() - 2 * np.pi) < ANGLE_SLACK)


def merge_positions(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique vertex positions and the index of each vertex among them."""
    order = np.lexsort(vertices.T[::-1])
    ordered = vertices[order]
    first = np.ones(len(ordered), dtype=bool)
    first[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    inverse = np.empty(len(vertices), dtype=np.int64)
    inverse[order] = np.cumsum(first) - 1
    return ordered[first], inverse


def face_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) unit ``u`` and ``v`` with ``u x v = normal`` for unit normals."""
    axis = np.zeros_like(normals)
    axis[np.arange(len(normals)), np.argmin(np.abs(normals), axis=1)] = 1.0
    u = axis - np.einsum("ij,ij->i", axis, normals)[:, None] * normals
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), TINY)
    return u, np.cross(normals, u)


@dataclass(frozen=True)
class SurfaceGeometry:
    """A receiving surface's shape, in a frame centred on its own bounds.

    Attributes
    ----------
    positions : (n, 3) float64
        Unique vertex positions, minus the mesh's ``center``.
    faces : (m, 3) int64
        The faces, indexing ``positions``.
    length : (m,) float64
        Twice each face's area.
    unit : (m, 3) float64
        Unit face normals (zero where ``length`` is).
    u, v : (m, 3) float64
        In-plane frames, ``u x v = unit``.
    centroid : (m, 3) float64
        Face centroids in the same frame.
    single_sheet : bool
        :func:`single_sheet` of the mesh.
    """

    positions: np.ndarray
    faces: np.ndarray
    length: np.ndarray
    unit: np.ndarray
    u: np.ndarray
    v: np.ndarray
    centroid: np.ndarray
    single_sheet: bool


def surface_geometry(surface: Caster) -> SurfaceGeometry:
    """The per-mesh part of receiving shadows on ``surface``: computed once
    and kept on the mesh (``surface.derived``) by the caller, so a second
    light, or a second call with other casters, does not redo it."""
    positions, inverse = merge_positions(surface.vertices)
    positions = positions - surface.center
    faces = inverse.reshape(-1)[surface.faces]
    first, second, third = positions[faces[:, 0]], positions[faces[:, 1]], positions[faces[:, 2]]
    a, b = second - first, third - first
    # Component by component: np.cross and norms over a short axis are slow.
    normals = np.column_stack(
        [
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        ]
    )
    length = np.sqrt(normals[:, 0] ** 2 + normals[:, 1] ** 2 + normals[:, 2] ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = np.where(length[:, None] > 0, normals / length[:, None], 0.0)
    u, v = face_frames(unit)
    centroid = (first + second + third) / 3.0
    return SurfaceGeometry(positions, faces, length, unit, u, v, centroid, single_sheet(surface))
