"""Independent references for shadow tests.

Nothing here calls shadowgeo's projection code: points are projected by
intersecting the ray from the light with the plane, regions are built with
shapely, and shadowing is decided by a brute-force segment/triangle test.
"""

from __future__ import annotations

import numpy as np
import shapely


def ray_plane(points, light_position, normal, offset):
    """Where the rays from a point light through ``points`` meet the plane
    ``normal . x + offset = 0`` (no check that the ray goes forwards)."""
    points = np.asarray(points, dtype=float)
    direction = points - light_position
    t = -(normal @ light_position + offset) / (direction @ normal)
    return light_position + t[:, None] * direction


def along_direction(points, direction, normal, offset):
    """Where lines through ``points`` along ``direction`` meet the plane."""
    points = np.asarray(points, dtype=float)
    t = -(points @ normal + offset) / (direction @ normal)
    return points + t[:, None] * direction


def basis(normal):
    """The plane frame documented by shadowgeo.Plane (re-derived here)."""
    normal = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(normal)))] = 1.0
    u = axis - (axis @ normal) * normal
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def hull_area_2d(points2d) -> float:
    return shapely.MultiPoint(np.asarray(points2d)).convex_hull.area


def textbook_shadow(vertices, faces, light_h, plane_vector):
    """The classic method: every vertex through the shadow matrix, divide by w,
    then each triangle as a polygon in the plane's 2-D frame. Returns the
    projected (n, 2) points (NaN/inf kept as they come) and the finite triangles."""
    matrix = (plane_vector @ light_h) * np.eye(4) - np.outer(light_h, plane_vector)
    homogeneous = np.column_stack([vertices, np.ones(len(vertices))]) @ matrix.T
    with np.errstate(divide="ignore", invalid="ignore"):
        projected = homogeneous[:, :3] / homogeneous[:, 3:]
    u, v = basis(plane_vector[:3])
    origin = -plane_vector[3] * plane_vector[:3] / np.linalg.norm(plane_vector[:3]) ** 2
    uv = np.column_stack([(projected - origin) @ u, (projected - origin) @ v])
    return uv, [shapely.Polygon(uv[f]) for f in faces if np.all(np.isfinite(uv[f]))]


def segment_hits_mesh(starts, end, triangles, eps=1e-12):
    """(n,) bool: does the segment from each of ``starts`` to ``end`` cross any
    triangle (Moller-Trumbore, brute force over all triangles)."""
    starts = np.asarray(starts, dtype=float)
    hits = np.zeros(len(starts), dtype=bool)
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    for i, start in enumerate(starts):
        direction = end - start
        p = np.cross(direction, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > eps
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = start - a
        bu = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        bv = (q @ direction) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        inside = ok & (bu >= 0) & (bv >= 0) & (bu + bv <= 1) & (t > eps) & (t < 1 - eps)
        hits[i] = bool(np.any(inside))
    return hits


def check_tiling(loop, faces) -> None:
    """Assert that ``faces`` tile the 2-D ``loop``: k - 2 counter-clockwise
    triangles of its corners whose areas add up to the loop's (shapely's)
    and whose union (GEOS) is the loop."""
    loop, faces = np.asarray(loop, dtype=float), np.asarray(faces)
    assert faces.shape == (len(loop) - 2, 3)
    corners = loop[faces]
    edge, other = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    doubled = edge[:, 0] * other[:, 1] - edge[:, 1] * other[:, 0]
    assert np.all(doubled > 0)
    polygon = shapely.Polygon(loop)
    assert abs(0.5 * doubled.sum() - polygon.area) <= 1e-12 * polygon.area
    union = shapely.union_all(shapely.polygons(corners))
    assert union.symmetric_difference(polygon).area < 1e-9 * polygon.area
