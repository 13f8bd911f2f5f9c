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

from dataclasses import dataclass
from typing import Literal, cast

import numpy as np
from manifold3d import triangulate

from .cells import column_cells
from .limits import TINY
from .plane2d import add, local_scale, region_loops, subtract, unite
from .simplify import Loops, loops_of
from .topology import unique_integers

__all__ = ["face_regions", "stitch"]


def face_regions(
    one: tuple[Loops, np.ndarray],
    other: tuple[Loops, np.ndarray],
    operation: Literal["subtract", "unite"],
) -> tuple[Loops, np.ndarray]:
    """Two sets of per-face regions (each :data:`Loops` and the sorted faces
    of its regions, in the same face frames) combined face by face: one's
    region less the other's, or the two united, where a face has both;
    where it has one only, that one's region for a union, ``one``'s or
    nothing for a difference. Faces whose region comes out empty are
    dropped."""
    (points, sizes, region), faces = one
    (other_points, other_sizes, other_region), other_faces = other
    uniting = operation == "unite"
    combine = add if uniting else subtract
    own = _split(points, sizes, region, len(faces))
    theirs = _split(other_points, other_sizes, other_region, len(other_faces))
    slot = {int(face): k for k, face in enumerate(faces.tolist())}
    other_slot = {int(face): k for k, face in enumerate(other_faces.tolist())}
    wanted = sorted(set(slot) | set(other_slot)) if uniting else sorted(slot)
    regions: list[list[np.ndarray]] = []
    kept: list[int] = []
    for face in wanted:
        mine, yours = slot.get(face), other_slot.get(face)
        if yours is None or mine is None:
            loops = own[mine] if mine is not None else theirs[cast(int, yours)]
        else:
            both = np.concatenate(own[mine] + theirs[yours])
            scale = local_scale(2.0 * float(np.abs(both).max()))
            result = combine(
                unite([loop * scale for loop in own[mine]]),
                unite([loop * scale for loop in theirs[yours]]),
            )
            loops = [loop / scale for loop in region_loops(result)]
        if loops:
            regions.append(loops)
            kept.append(face)
    return loops_of(regions), np.array(kept, dtype=np.int64)


def _split(
    points: np.ndarray, sizes: np.ndarray, region: np.ndarray, n_regions: int
) -> list[list[np.ndarray]]:
    """:data:`Loops` as a list of regions, each a list of (k, 2) loops."""
    regions: list[list[np.ndarray]] = [[] for _ in range(n_regions)]
    starts = np.cumsum(sizes) - sizes
    for start, size, owner in zip(starts.tolist(), sizes.tolist(), region.tolist(), strict=True):
        regions[owner].append(points[start : start + size])
    return regions


def stitch(
    vertices: np.ndarray,
    faces: np.ndarray,
    face_ids: np.ndarray,
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
    regions: Loops,
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
    regions : Loops
        The regions' loops, each in its face's frame (outer loops
        counter-clockwise, holes clockwise), lying in the face; regions are
        numbered as ``face_ids``.
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
    flat, loop_sizes, loop_region = regions
    if len(loop_sizes) == 0:
        return vertices.copy(), np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    point_face = np.repeat(face_ids[loop_region], loop_sizes)
    point_region = np.repeat(loop_region, loop_sizes)
    corners = _corners_2d(vertices, faces, origin, u, v, face_ids)  # (r, 3, 2)
    placed = _on_edges(flat, corners, point_region, eps)
    face_vertices = faces[point_face]  # (P, 3)
    clusters = _edge_clusters(vertices, face_vertices, placed, eps)
    ids, points = _point_ids(vertices, frames, flat, point_face, face_vertices, placed, clusters)
    # Each point's canonical parameter on its edge: the cluster's, exactly.
    canonical = placed.param.copy()
    cluster_t = clusters.t[clusters.point_cluster]
    canonical[clusters.on] = np.where(clusters.forward, cluster_t, 1.0 - cluster_t)
    loop_of = np.repeat(np.arange(len(loop_sizes)), loop_sizes)
    ids, loop_of, point_face, edge_of, canonical, corner = _drop_repeats(
        loop_of, ids, point_face, placed.edge_of, canonical, placed.corner
    )
    sequence, sequence_loop = _insert_edge_points(
        ids,
        loop_of,
        faces[point_face],
        edge_of,
        canonical,
        corner,
        (clusters.key, clusters.t),
        np.int64(len(vertices)),
    )
    walk = _walk(points, frames, face_ids, regions, sequence, sequence_loop)
    if len(walk.sequence) == 0:
        return points, np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    direct, walk = _direct_triangles(walk, loop_region, len(loop_sizes), len(face_ids))
    direct_owners = face_ids[direct[1]]
    if len(walk.sequence) == 0:
        return points, direct[0], direct_owners
    found, owners = _cell_triangles(walk, len(face_ids))
    return (
        points,
        np.concatenate([direct[0], found]),
        np.concatenate([direct_owners, face_ids[owners]]),
    )


@dataclass(frozen=True)
class _OnEdges:
    """Where each region point (P of them) lies on its face: ``corner`` the
    face corner it is at (-1: none), ``edge_of`` the edge ``j`` (corner j to
    j + 1) it lies on otherwise (-1: none), ``param`` its parameter along
    that edge from corner j."""

    corner: np.ndarray
    edge_of: np.ndarray
    param: np.ndarray


def _on_edges(
    flat: np.ndarray, corners: np.ndarray, point_region: np.ndarray, eps: float
) -> _OnEdges:
    """Step 1: region corners within ``eps`` of a face corner, else of a face
    edge."""
    # Distance of each point to each face edge j (corner j to j + 1), inside
    # positive, component by component: (P, 3) arrays, one column per edge.
    edge = np.roll(corners, -1, axis=1) - corners
    edge_x, edge_y = edge[:, :, 0][point_region], edge[:, :, 1][point_region]
    length = np.sqrt(edge_x * edge_x + edge_y * edge_y)
    relative_x = flat[:, :1] - corners[:, :, 0][point_region]
    relative_y = flat[:, 1:] - corners[:, :, 1][point_region]
    distance = (edge_x * relative_y - edge_y * relative_x) / length
    on_edge = np.abs(distance) <= eps
    along = (relative_x * edge_x + relative_y * edge_y) / length**2

    n_points = len(flat)
    edge_of = np.full(n_points, -1, dtype=np.int64)
    param = np.zeros(n_points)
    # A face corner first: near two edge lines is not enough in a sliver.
    corner_distance = np.sqrt(relative_x * relative_x + relative_y * relative_y)
    nearest_corner = _first_smallest(corner_distance)
    at_corner = corner_distance[np.arange(n_points), nearest_corner] <= eps
    corner = np.where(at_corner, nearest_corner, -1)
    inside = (along > 0) & (along < 1)
    closeness = np.where(on_edge & inside, np.abs(distance), np.inf)
    nearest_edge = _first_smallest(closeness)
    smallest = np.minimum(np.minimum(closeness[:, 0], closeness[:, 1]), closeness[:, 2])
    one = np.flatnonzero(~at_corner & np.isfinite(smallest))
    edge_of[one] = nearest_edge[one]
    param[one] = along[one, nearest_edge[one]]
    return _OnEdges(corner, edge_of, param)


@dataclass(frozen=True)
class _EdgeClusters:
    """The points on mesh edges, merged: ``on`` the region points on an edge,
    ``forward`` whether their face runs that edge from its lower vertex
    index, ``point_cluster`` each one's cluster; per cluster its edge ``key``
    (low * n_vertices + high), parameter ``t`` from the lower vertex and 3-D
    ``points``."""

    on: np.ndarray
    forward: np.ndarray
    point_cluster: np.ndarray
    key: np.ndarray
    t: np.ndarray
    points: np.ndarray


def _edge_clusters(
    vertices: np.ndarray, face_vertices: np.ndarray, placed: _OnEdges, eps: float
) -> _EdgeClusters:
    """Step 2: the parameters found on an edge, from both faces, merged where
    they lie within ``eps``; one canonical parameter per cluster, from the
    lower index."""
    n_vertices = np.int64(len(vertices))
    on = np.flatnonzero(placed.edge_of >= 0)
    j = placed.edge_of[on]
    a = face_vertices[on, j]
    b = face_vertices[on, (j + 1) % 3]
    low, high = np.minimum(a, b), np.maximum(a, b)
    t = np.where(a == low, placed.param[on], 1.0 - placed.param[on])
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
    return _EdgeClusters(on, a == low, point_cluster, cluster_key, cluster_t, edge_points)


def _point_ids(
    vertices: np.ndarray,
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
    flat: np.ndarray,
    point_face: np.ndarray,
    face_vertices: np.ndarray,
    placed: _OnEdges,
    clusters: _EdgeClusters,
) -> tuple[np.ndarray, np.ndarray]:
    """Each region point's index into the points: mesh vertices first, then
    edge points, then interior points (lifted from their face's frame)."""
    origin, u, v = frames
    n_vertices = np.int64(len(vertices))
    ids = np.full(len(flat), -1, dtype=np.int64)
    corner = placed.corner
    is_corner = corner >= 0
    ids[is_corner] = face_vertices[is_corner, corner[is_corner]]
    ids[clusters.on] = n_vertices + clusters.point_cluster
    inner = np.flatnonzero(ids < 0)
    base = n_vertices + len(clusters.t)
    ids[inner] = base + np.arange(len(inner))
    frame_origin, frame_u, frame_v = (
        origin[point_face[inner]],
        u[point_face[inner]],
        v[point_face[inner]],
    )
    inner_points = frame_origin + flat[inner, :1] * frame_u + flat[inner, 1:] * frame_v
    return ids, np.concatenate([vertices, clusters.points, inner_points])


@dataclass(frozen=True)
class _Walk:
    """The loops as point sequences: each entry's point index ``sequence``,
    its ``loop``, its region and its point in the face's frame (``flat``)."""

    sequence: np.ndarray
    loop: np.ndarray
    region: np.ndarray
    flat: np.ndarray

    def taken(self, keep: np.ndarray) -> _Walk:
        """The entries ``keep`` (a mask) only."""
        return _Walk(self.sequence[keep], self.loop[keep], self.region[keep], self.flat[keep])


def _walk(
    points: np.ndarray,
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
    face_ids: np.ndarray,
    regions: Loops,
    sequence: np.ndarray,
    sequence_loop: np.ndarray,
) -> _Walk:
    """The stitched loops back in their faces' frames, loops below three
    points dropped."""
    origin, u, v = frames
    loop_sizes, loop_region = regions[1], regions[2]
    sequence_face = face_ids[loop_region[sequence_loop]]
    relative = points[sequence] - origin[sequence_face]
    flat2d = np.column_stack(
        [
            np.einsum("ij,ij->i", relative, u[sequence_face]),
            np.einsum("ij,ij->i", relative, v[sequence_face]),
        ]
    )
    sizes = np.bincount(sequence_loop, minlength=len(loop_sizes))
    keep = sizes[sequence_loop] >= 3
    return _Walk(sequence, sequence_loop, loop_region[sequence_loop], flat2d).taken(keep)


def _direct_triangles(
    walk: _Walk, loop_region: np.ndarray, n_loops: int, n_regions: int
) -> tuple[tuple[np.ndarray, np.ndarray], _Walk]:
    """A region that is one triangle (a face wholly in shadow, most often) is
    its own triangulation: those triangles and their regions, and the walk
    left."""
    loop_sizes_kept = np.bincount(walk.loop, minlength=n_loops)
    loops_per_region = np.bincount(loop_region[loop_sizes_kept > 0], minlength=n_regions)
    entry_region_loops = loops_per_region[walk.region]
    single = (entry_region_loops == 1) & (loop_sizes_kept[walk.loop] == 3)
    first_of = np.flatnonzero(single & (np.diff(walk.loop, prepend=-1) != 0))
    flat2d = walk.flat
    corner_a, corner_b, corner_c = flat2d[first_of], flat2d[first_of + 1], flat2d[first_of + 2]
    doubled = (corner_b[:, 0] - corner_a[:, 0]) * (corner_c[:, 1] - corner_a[:, 1]) - (
        corner_b[:, 1] - corner_a[:, 1]
    ) * (corner_c[:, 0] - corner_a[:, 0])
    first_of = first_of[doubled > 0]
    direct = walk.sequence[first_of[:, None] + np.arange(3)]
    rest = np.ones(len(walk.sequence), dtype=bool)
    rest[(first_of[:, None] + np.arange(3)).reshape(-1)] = False
    return (direct, walk.region[first_of]), walk.taken(rest)


def _cell_triangles(walk: _Walk, n_regions: int) -> tuple[np.ndarray, np.ndarray]:
    """Every other region triangulated in one call: each in its own cell of
    one column (an affine stretch, which keeps a valid triangulation valid).
    The triangles and their regions."""
    region_of, flat2d = walk.region, walk.flat
    # Entries run region by region: each region's box by one reduction per column.
    starts = np.flatnonzero(np.diff(region_of, prepend=-1) != 0)
    present = region_of[starts]
    low = np.zeros((n_regions, 2))
    high = np.zeros((n_regions, 2))
    for column in range(2):
        values = flat2d[:, column]
        low[present, column] = np.minimum.reduceat(values, starts)
        high[present, column] = np.maximum.reduceat(values, starts)
    middle = 0.5 * (low + high)
    reach = np.maximum(0.5 * np.maximum(high[:, 0] - low[:, 0], high[:, 1] - low[:, 1]), TINY)
    tiled = column_cells(reach, middle).place(flat2d, region_of)
    bounds = np.flatnonzero(np.diff(walk.loop)) + 1
    local = np.asarray(triangulate(np.split(tiled, bounds)), dtype=np.int64).reshape(-1, 3)
    found = walk.sequence[local]
    # A loop that touches itself names one point twice: drop the slivers
    # between its two copies.
    proper = (
        (found[:, 0] != found[:, 1]) & (found[:, 1] != found[:, 2]) & (found[:, 2] != found[:, 0])
    )
    return found[proper], region_of[local[:, 0]][proper]


def _drop_repeats(
    loop_of: np.ndarray, ids: np.ndarray, *others: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Drop each point equal to the one before it in its (cyclic) loop."""
    count = len(ids)
    if count == 0:
        return (ids, loop_of, *others)
    first = np.ones(count, dtype=bool)
    first[1:] = loop_of[1:] != loop_of[:-1]
    starts = np.flatnonzero(first)
    ends = np.append(starts[1:], count) - 1
    previous = np.arange(count) - 1
    previous[starts] = ends
    keep = ids != ids[previous]
    return (ids[keep], loop_of[keep], *(other[keep] for other in others))


def _insert_edge_points(
    ids: np.ndarray,
    loop_of: np.ndarray,
    corner_ids: np.ndarray,
    edge_of: np.ndarray,
    canonical: np.ndarray,
    corner: np.ndarray,
    clusters: tuple[np.ndarray, np.ndarray],
    n_vertices: np.int64,
) -> tuple[np.ndarray, np.ndarray]:
    """The loops with, after each point whose segment to the next runs along a
    face edge, the edge's shared points strictly between the two, in order.
    Returns the new point sequence and the loop of each entry."""
    cluster_key, cluster_t = clusters
    count = len(ids)
    if count == 0 or len(cluster_key) == 0:
        return ids, loop_of
    first = np.ones(count, dtype=bool)
    first[1:] = loop_of[1:] != loop_of[:-1]
    starts = np.flatnonzero(first)
    following = np.arange(count) + 1
    following[np.append(starts[1:], count) - 1] = starts
    # Parameter along face edge j (corner j to j + 1) of each point on it.
    along = np.full((count, 3), np.nan)
    rows = np.flatnonzero(edge_of >= 0)
    along[rows, edge_of[rows]] = canonical[rows]
    rows = np.flatnonzero(corner >= 0)
    along[rows, corner[rows]] = 0.0
    along[rows, (corner[rows] - 1) % 3] = 1.0
    shared = ~np.isnan(along) & ~np.isnan(along[following])
    segment = np.flatnonzero(shared.any(axis=1))
    if len(segment) == 0:
        return ids, loop_of
    j = np.argmax(shared[segment], axis=1)
    a = corner_ids[segment, j]
    b = corner_ids[segment, (j + 1) % 3]
    low, high = np.minimum(a, b), np.maximum(a, b)
    forward = a == low
    s_from, s_to = along[segment, j], along[following[segment], j]
    t_from = np.where(forward, s_from, 1.0 - s_from)
    t_to = np.where(forward, s_to, 1.0 - s_to)
    # One sorted scale over all edges: rank * 4 + t (t in [0, 1]).
    edge_keys = unique_integers(cluster_key)
    cluster_value = np.searchsorted(edge_keys, cluster_key) * 4.0 + cluster_t
    key = low * n_vertices + high
    rank = np.searchsorted(edge_keys, key)
    known = (rank < len(edge_keys)) & (edge_keys[np.minimum(rank, len(edge_keys) - 1)] == key)
    lower = rank * 4.0 + np.minimum(t_from, t_to)
    upper = rank * 4.0 + np.maximum(t_from, t_to)
    first_in = np.searchsorted(cluster_value, lower, side="right")
    stop_in = np.searchsorted(cluster_value, upper, side="left")
    added = np.where(known, np.maximum(stop_in - first_in, 0), 0)
    extra = np.zeros(count, dtype=np.int64)
    extra[segment] = added
    block = np.concatenate([[0], np.cumsum(1 + extra)])
    sequence = np.empty(block[-1], dtype=np.int64)
    sequence[block[:-1]] = ids
    sequence_loop = np.repeat(loop_of, 1 + extra)
    total = int(added.sum())
    if total:
        owner = np.repeat(np.arange(len(segment)), added)
        k = np.arange(total) - np.repeat(np.cumsum(added) - added, added)
        ascending = t_to >= t_from
        cluster = np.where(ascending[owner], first_in[owner] + k, stop_in[owner] - 1 - k)
        sequence[block[segment[owner]] + 1 + k] = n_vertices + cluster
    return sequence, sequence_loop


def _first_smallest(values: np.ndarray) -> np.ndarray:
    """``np.argmin(values, axis=1)`` for (n, 3) values, column by column
    (numpy reduces a short axis many times slower)."""
    first, second, third = values[:, 0], values[:, 1], values[:, 2]
    smallest: np.ndarray = np.where(
        (first <= second) & (first <= third), 0, np.where(second <= third, 1, 2)
    )
    return smallest


def _corners_2d(
    vertices: np.ndarray,
    faces: np.ndarray,
    origin: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    face_ids: np.ndarray,
) -> np.ndarray:
    corners = vertices[faces[face_ids]] - origin[face_ids][:, None, :]
    return np.stack(
        [
            np.einsum("rkd,rd->rk", corners, u[face_ids]),
            np.einsum("rkd,rd->rk", corners, v[face_ids]),
        ],
        axis=2,
    )
