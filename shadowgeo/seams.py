"""Seamless triangulation of per-face regions on a triangle mesh.

Each receiver face's shadow region is computed in that face's own 2-D frame,
so the point where a shadow edge crosses a mesh edge comes out a few units in
the last place apart from the two faces' sides. :func:`stitch` makes the two
sides agree exactly:

1. region corners within ``eps`` of a face corner become that mesh vertex;
   those within ``eps`` of a face edge become a point of that edge, given by
   one parameter along the edge from its lower vertex index to its higher one;
2. the parameters found on an edge, from both faces, are merged where they
   lie within ``eps`` of each other, and each cluster gets one 3-D point;
3. where a region's boundary runs along an edge, every point of that edge
   between its two ends is inserted, so neither side leaves a T-junction.

The regions are then triangulated with those shared points, face by face.
"""

from __future__ import annotations

import numpy as np
from manifold3d import triangulate


def stitch(
    vertices: np.ndarray,
    faces: np.ndarray,
    face_ids: np.ndarray,
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
    regions: list[list[np.ndarray]],
    eps: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangulate regions given per face so shared edges split identically.

    Parameters
    ----------
    vertices : (n, 3) float64
        Mesh vertices, merged (one index per position).
    faces : (m, 3) int64
        Mesh faces, wound counter-clockwise about their frame normal.
    face_ids : (r,) int64
        The face of each region.
    frames : three (m, 3) float64
        Each face's frame: origin, ``u``, ``v`` (``u x v`` its normal).
    regions : list of r lists of (k, 2) float64
        Each region's loops in its face's frame (outer loops counter-clockwise,
        holes clockwise), lying in the face.
    eps : float
        Distance below which a point is on an edge or two points are one.

    Returns
    -------
    points : (p, 3) float64
        Mesh vertices first, then edge points, then interior points.
    triangles : (t, 3) int64
        Into ``points``, counter-clockwise about their face's normal.
    face_index : (t,) int64
        The face each triangle lies in.
    """
    origin, u, v = frames
    if not regions:
        return vertices.copy(), np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    loop_sizes = np.array([len(loop) for region in regions for loop in region], dtype=np.int64)
    loop_region = np.repeat(np.arange(len(regions)), [len(region) for region in regions])
    flat = np.concatenate([loop for region in regions for loop in region])
    point_face = np.repeat(face_ids[loop_region], loop_sizes)
    corners = _corners_2d(vertices, faces, origin, u, v, face_ids)  # (r, 3, 2)
    point_corners = np.repeat(corners[loop_region], loop_sizes, axis=0)  # (P, 3, 2)

    # Distance of each point to each face edge j (corner j to j + 1), inside positive.
    start = point_corners
    edge = np.roll(point_corners, -1, axis=1) - start
    length = np.linalg.norm(edge, axis=2)
    relative = flat[:, None, :] - start
    distance = (edge[..., 0] * relative[..., 1] - edge[..., 1] * relative[..., 0]) / length
    on_edge = np.abs(distance) <= eps
    along = np.einsum("pjk,pjk->pj", relative, edge) / length**2

    n_points = len(flat)
    edge_of = np.full(n_points, -1, dtype=np.int64)
    param = np.zeros(n_points)
    # A face corner first: near two edge lines is not enough in a sliver.
    corner_distance = np.linalg.norm(flat[:, None, :] - point_corners, axis=2)
    nearest_corner = np.argmin(corner_distance, axis=1)
    at_corner = corner_distance[np.arange(n_points), nearest_corner] <= eps
    corner = np.where(at_corner, nearest_corner, -1)
    inside = (along > 0) & (along < 1)
    closeness = np.where(on_edge & inside, np.abs(distance), np.inf)
    nearest_edge = np.argmin(closeness, axis=1)
    one = np.flatnonzero(~at_corner & np.isfinite(closeness.min(axis=1)))
    edge_of[one] = nearest_edge[one]
    param[one] = along[one, nearest_edge[one]]

    face_vertices = faces[point_face]  # (P, 3)
    n_vertices = np.int64(len(vertices))
    ids = np.full(n_points, -1, dtype=np.int64)
    is_corner = corner >= 0
    ids[is_corner] = face_vertices[is_corner, corner[is_corner]]

    # Edge points: one canonical parameter per cluster, from the lower index.
    on = np.flatnonzero(edge_of >= 0)
    j = edge_of[on]
    a = face_vertices[on, j]
    b = face_vertices[on, (j + 1) % 3]
    low, high = np.minimum(a, b), np.maximum(a, b)
    t = np.where(a == low, param[on], 1.0 - param[on])
    key = low * n_vertices + high
    order = np.lexsort((t, key))
    key_sorted, t_sorted = key[order], t[order]
    span = np.linalg.norm(vertices[high] - vertices[low], axis=1)[order]
    new = np.ones(len(order), dtype=bool)
    new[1:] = (key_sorted[1:] != key_sorted[:-1]) | (
        (t_sorted[1:] - t_sorted[:-1]) * span[1:] > eps
    )
    cluster = np.cumsum(new) - 1
    cluster_t = t_sorted[new]
    cluster_key = key_sorted[new]
    cluster_low, cluster_high = cluster_key // n_vertices, cluster_key % n_vertices
    edge_points = vertices[cluster_low] + cluster_t[:, None] * (
        vertices[cluster_high] - vertices[cluster_low]
    )
    point_cluster = np.empty(len(on), dtype=np.int64)
    point_cluster[order] = cluster
    ids[on] = n_vertices + point_cluster

    inner = np.flatnonzero(ids < 0)
    base = n_vertices + len(cluster_t)
    ids[inner] = base + np.arange(len(inner))
    frame_origin, frame_u, frame_v = (
        origin[point_face[inner]],
        u[point_face[inner]],
        v[point_face[inner]],
    )
    inner_points = frame_origin + flat[inner, :1] * frame_u + flat[inner, 1:] * frame_v
    points = np.concatenate([vertices, edge_points, inner_points])

    # Each edge's points sorted by parameter, for the insertions.
    edge_keys, edge_start = np.unique(cluster_key, return_index=True)
    edge_stop = np.append(edge_start[1:], len(cluster_key))
    by_key = {
        int(k): (cluster_t[s:e], n_vertices + np.arange(s, e))
        for k, s, e in zip(edge_keys, edge_start, edge_stop, strict=True)
    }

    triangles, owners = [], []
    splits = np.cumsum(loop_sizes)[:-1]
    loop_ids = np.split(ids, splits)
    loop_edge = np.split(edge_of, splits)
    loop_param = np.split(param, splits)
    loop_corner = np.split(corner, splits)
    loop_index = 0
    for region_index, region in enumerate(regions):
        face = int(face_ids[region_index])
        corners_ids = faces[face]
        loops = []
        for _ in region:
            loop = _with_edge_points(
                loop_ids[loop_index],
                loop_edge[loop_index],
                loop_param[loop_index],
                loop_corner[loop_index],
                corners_ids,
                n_vertices,
                by_key,
            )
            loop_index += 1
            if len(loop) >= 3:
                loops.append(loop)
        if not loops:
            continue
        relative = points[np.concatenate(loops)] - origin[face]
        flat2d = np.column_stack([relative @ u[face], relative @ v[face]])
        pieces = np.split(flat2d, np.cumsum([len(loop) for loop in loops])[:-1])
        local = np.asarray(triangulate(pieces), dtype=np.int64).reshape(-1, 3)
        found = np.concatenate(loops)[local]
        # A loop that touches itself names one point twice: drop the slivers
        # between its two copies.
        found = found[
            (found[:, 0] != found[:, 1])
            & (found[:, 1] != found[:, 2])
            & (found[:, 2] != found[:, 0])
        ]
        if len(found):
            triangles.append(found)
            owners.append(np.full(len(found), face, dtype=np.int64))
    if not triangles:
        return points, np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    return points, np.concatenate(triangles), np.concatenate(owners)


def _corners_2d(vertices, faces, origin, u, v, face_ids) -> np.ndarray:
    corners = vertices[faces[face_ids]] - origin[face_ids][:, None, :]
    return np.stack(
        [
            np.einsum("rkd,rd->rk", corners, u[face_ids]),
            np.einsum("rkd,rd->rk", corners, v[face_ids]),
        ],
        axis=2,
    )


def _with_edge_points(ids, edge_of, param, corner, corner_ids, n_vertices, by_key) -> np.ndarray:
    """A loop of point ids with the repeated ids dropped and, where it runs
    along a face edge, the edge's other points inserted in order."""
    keep = np.ones(len(ids), dtype=bool)
    keep[1:] = ids[1:] != ids[:-1]
    if len(ids) > 1 and ids[-1] == ids[0]:
        keep[-1] = False
    ids, edge_of, param, corner = ids[keep], edge_of[keep], param[keep], corner[keep]
    if len(ids) < 3:
        return ids
    if not np.any((edge_of >= 0) | (corner >= 0)):
        return ids
    out = []
    count = len(ids)
    for i in range(count):
        out.append(int(ids[i]))
        k = (i + 1) % count
        shared = _shared_edge(edge_of[i], param[i], corner[i], edge_of[k], param[k], corner[k])
        if shared is None:
            continue
        j, s_from, s_to = shared
        a, b = int(corner_ids[j]), int(corner_ids[(j + 1) % 3])
        low, high = min(a, b), max(a, b)
        entry = by_key.get(low * int(n_vertices) + high)
        if entry is None:
            continue
        t_values, point_ids = entry
        s_values = t_values if a == low else 1.0 - t_values
        lo, hi = min(s_from, s_to), max(s_from, s_to)
        between = np.flatnonzero((s_values > lo) & (s_values < hi))
        if len(between) == 0:
            continue
        between = between[np.argsort(s_values[between])]
        if s_to < s_from:
            between = between[::-1]
        out.extend(int(p) for p in point_ids[between] if p != ids[i] and p != ids[k])
    return np.array(out, dtype=np.int64)


def _edge_params(edge_of, param, corner) -> dict[int, float]:
    """The face edges a loop point lies on, with its parameter along each."""
    if corner >= 0:
        return {int(corner): 0.0, int((corner - 1) % 3): 1.0}
    if edge_of >= 0:
        return {int(edge_of): float(param)}
    return {}


def _shared_edge(edge_a, param_a, corner_a, edge_b, param_b, corner_b):
    first = _edge_params(edge_a, param_a, corner_a)
    if not first:
        return None
    second = _edge_params(edge_b, param_b, corner_b)
    for j, s in first.items():
        if j in second:
            return j, s, second[j]
    return None
