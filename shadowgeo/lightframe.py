"""The light's own 2-D frame: which caster triangles can reach which receiver faces.

Seen from the light, a caster triangle can only shadow a receiver face whose
image overlaps its own. Images are taken in the light's frame: for a
directional light the plane across its rays; for a point light the six sides
of a cube map around it (each side a square pyramid of rays, so every image is
bounded and nothing is divided by ``w <= 0``). A 2-D bounding-box index in that
frame (shapely's STRtree) then lists the candidate (face, triangle) pairs
without looking at every pair.

The triangles are clipped to each cube side in homogeneous coordinates by
:func:`clip_batch`, a Sutherland-Hodgman clipper that works on many convex
polygons at once; :mod:`shadowgeo.surface` uses the same clipper to cut
casters to the slab between a face and the light.

:class:`Outline` is a closed caster's silhouette in such a frame, computed
once per light: its shadow on every face wholly behind it.
"""

from __future__ import annotations

import warnings
from typing import cast

import numpy as np
import shapely

from .polygons import MAX_COORDINATE, components, fill

# The cube map around a point light: (axis, sign) of each side's central ray.
_CUBE_SIDES = [(axis, sign) for axis in range(3) for sign in (1.0, -1.0)]


def corner_min(values: np.ndarray) -> np.ndarray:
    """``values.min(axis=1)`` for (n, 3, ...) triangle corners, as two
    element-wise minima (numpy's reduction over a length-3 axis is slow)."""
    low: np.ndarray = np.minimum(np.minimum(values[:, 0], values[:, 1]), values[:, 2])
    return low


def corner_max(values: np.ndarray) -> np.ndarray:
    """``values.max(axis=1)`` for (n, 3, ...) triangle corners."""
    high: np.ndarray = np.maximum(np.maximum(values[:, 0], values[:, 1]), values[:, 2])
    return high


def clip_batch(
    points: np.ndarray, counts: np.ndarray, planes: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Clip many convex polygons to half-spaces ``plane . x >= 0``, at once.

    Parameters
    ----------
    points : (n, k, d) float64
        Polygon corners in homogeneous coordinates of any size ``d``; row
        ``i`` uses its first ``counts[i]`` slots.
    counts : (n,) int
    planes : (p, d) or (n, p, d) float64
        The same half-spaces for every polygon, or one set per polygon.

    Returns
    -------
    points : (n, k', d) float64
        The clipped polygons, padded with zeros past their counts.
    counts : (n,) int64
        0 for a polygon clipped away.
    """
    points = np.asarray(points, dtype=np.float64)
    counts = np.asarray(counts, dtype=np.int64).copy()
    n, width, size = points.shape
    planes = np.asarray(planes, dtype=np.float64)
    if planes.ndim == 2:
        planes = np.broadcast_to(planes, (n, *planes.shape))
    # Each plane adds at most one corner to a convex polygon.
    out = np.zeros((n, width + planes.shape[1], size))
    out[:, :width] = points
    for j in range(planes.shape[1]):
        used = int(counts.max()) if n else 0
        if used == 0:
            break
        side = np.einsum("nkd,nd->nk", out[:, :used], planes[:, j])
        slots = np.arange(used)
        valid = slots[None, :] < counts[:, None]
        rows = np.flatnonzero(np.any(valid & (side < 0), axis=1))
        if len(rows) == 0:
            continue
        new, counts[rows] = _clip_rows(out[rows, :used], counts[rows], side[rows], valid[rows])
        if new.shape[1] > out.shape[1]:  # rounding made a near-degenerate polygon non-convex
            out = np.pad(out, ((0, 0), (0, new.shape[1] - out.shape[1]), (0, 0)))
        out[rows, : new.shape[1]] = new
    used = max(int(counts.max()) if n else 0, 1)
    return out[:, :used], counts


def _clip_rows(
    points: np.ndarray, counts: np.ndarray, side: np.ndarray, valid: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One Sutherland-Hodgman step on rows that the plane cuts: (r, k', d).
    Each corner inside is kept, followed by the crossing on its edge to the
    next corner where the edge crosses the plane; only the crossings are
    computed."""
    rows, width, size = points.shape
    inside = (side >= 0) & valid
    slots = np.arange(width)
    following = (slots[None, :] + 1) % np.maximum(counts[:, None], 1)
    inside_next = np.take_along_axis(inside, following, axis=1)
    crosses = valid & (inside != inside_next)
    keep = np.stack([inside, crosses], axis=2).reshape(rows, 2 * width)
    position = np.cumsum(keep, axis=1) - 1
    counts = position[:, -1] + 1
    out_width = max(int(counts.max()), 1)
    out = np.zeros((rows * out_width, size))
    # Rows of the flattened arrays: one index per entry gathers fastest.
    flat_points = points.reshape(rows * width, size)
    flat_position = position.reshape(-1)
    entry = np.flatnonzero(inside)  # row * width + col
    row, col = np.divmod(entry, width)
    out[row * out_width + flat_position[row * 2 * width + 2 * col]] = flat_points[entry]
    entry = np.flatnonzero(crosses)
    row, col = np.divmod(entry, width)
    ahead = row * width + following.reshape(-1)[entry]
    flat_side = side.reshape(-1)
    here, there = flat_side[entry], flat_side[ahead]
    t = here / (here - there)
    start = flat_points[entry]
    target = row * out_width + flat_position[row * 2 * width + 2 * col + 1]
    out[target] = start + t[:, None] * (flat_points[ahead] - start)
    return out.reshape(rows, out_width, size), counts


# Triangles as (n, 3, 3) corners, or as (points (p, 3), faces (n, 3)) that
# share their corners: per-point work is then done once per point.
Triangles = np.ndarray | tuple[np.ndarray, np.ndarray]


def _indexed(triangles: Triangles) -> tuple[np.ndarray, np.ndarray]:
    """(points, faces) of triangles given either way; corners one by one
    where the faces use fewer corners than there are points."""
    if isinstance(triangles, tuple):
        points, faces = triangles
        if 3 * len(faces) >= len(points):
            return points, faces
        triangles = points[faces]
    corners = np.asarray(triangles).reshape(-1, 3)
    return corners, np.arange(len(corners)).reshape(-1, 3)


def _directional_boxes(
    points: np.ndarray, faces: np.ndarray, direction: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray]]:
    """One frame, the plane across the rays: every triangle and its (n, 4) box."""
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(direction)))] = 1.0
    first = np.cross(direction, axis)
    first /= np.linalg.norm(first)
    second = np.cross(direction, first)
    x = (points @ first)[faces]
    y = (points @ second)[faces]
    boxes = np.column_stack([corner_min(x), corner_min(y), corner_max(x), corner_max(y)])
    return [(np.arange(len(faces)), boxes)]


def _cube_boxes(points: np.ndarray, faces: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Six frames around a light at the origin: for each cube side, the
    triangles whose image reaches it and (k, 4) boxes of their images there."""
    # Each point's side: its largest coordinate. A triangle with all three
    # corners on one side lies inside that side's pyramid (it is convex).
    # Column by column: numpy reduces a short axis many times slower.
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    largest = np.where((ax >= ay) & (ax >= az), 0, np.where(ay >= az, 1, 2))
    coordinate = np.where(largest == 0, x, np.where(largest == 1, y, z))
    positive = coordinate > 0
    side = 2 * largest + np.where(positive, 0, 1)  # index into _CUBE_SIDES
    w = np.where(positive, coordinate, -coordinate)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(largest == 0, y, x) / w
        v = np.where(largest == 2, y, z) / w
    side_of = side[faces]
    whole = (side_of[:, 0] == side_of[:, 1]) & (side_of[:, 1] == side_of[:, 2])
    if whole.all():
        complete, spanning = np.arange(len(faces)), np.zeros(0, np.int64)
        face_u, face_v = u[faces], v[faces]
    else:
        complete, spanning = np.flatnonzero(whole), np.flatnonzero(~whole)
        face_u, face_v = u[faces[complete]], v[faces[complete]]
    all_boxes = np.column_stack(
        [corner_min(face_u), corner_min(face_v), corner_max(face_u), corner_max(face_v)]
    )
    which = side_of[complete, 0]
    # Side by side: sorted once (no copy when one side holds them all).
    if len(which) and np.all(which == which[0]):
        bounds = np.where(np.arange(7) > which[0], len(which), 0)
    else:
        order = np.argsort(which, kind="stable")
        complete, all_boxes, which = complete[order], all_boxes[order], which[order]
        bounds = np.searchsorted(which, np.arange(7))
    corners = points[faces[spanning]] if len(spanning) else None
    out = []
    for index, (axis, sign) in enumerate(_CUBE_SIDES):
        here = slice(bounds[index], bounds[index + 1])
        if corners is None:
            out.append((complete[here], all_boxes[here]))
            continue
        across = [a for a in range(3) if a != axis]
        found, box = _clipped_boxes(corners, axis, sign, across)
        out.append(
            (
                np.concatenate([complete[here], spanning[found]]),
                np.concatenate([all_boxes[here], box]),
            )
        )
    return out


def _clipped_boxes(
    triangles: np.ndarray, axis: int, sign: float, across: list[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Boxes of the triangles' images clipped to one cube side's pyramid of
    rays ``|x| <= w, |y| <= w``: the indices that reach it, and their boxes."""
    w = sign * triangles[:, :, axis]
    x, y = triangles[:, :, across[0]], triangles[:, :, across[1]]
    homogeneous = np.stack([x, y, w], axis=2)
    planes = np.array([[-1.0, 0, 1], [1.0, 0, 1], [0, -1.0, 1], [0, 1.0, 1]])
    clipped, counts = clip_batch(homogeneous, np.full(len(triangles), 3), planes)
    has = np.flatnonzero(counts > 0)
    clipped, counts = clipped[has], counts[has]
    slots = np.arange(clipped.shape[1])[None, :] < counts[:, None]
    weight = clipped[:, :, 2]
    # Only the light itself projects from w = 0; a box of the whole side covers it.
    finite = slots & (weight > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        cu = np.where(finite, clipped[:, :, 0] / weight, np.nan)
        cv = np.where(finite, clipped[:, :, 1] / weight, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN rows: the apex alone
        box = np.column_stack(
            [np.nanmin(cu, 1), np.nanmin(cv, 1), np.nanmax(cu, 1), np.nanmax(cv, 1)]
        )
    touches_apex = np.any(slots & (weight <= 0), axis=1)
    box[touches_apex] = [-1.0, -1.0, 1.0, 1.0]
    return has, box


def padded_loops(points: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """(n, k, 2) loops of ``sizes`` points each, taken in turn from ``points``,
    each padded to the longest by repeating its last point (repeated points
    add no edges)."""
    sizes = np.asarray(sizes, dtype=np.int64)
    if len(sizes) == 0:
        return np.zeros((0, 3, 2))
    width = max(int(sizes.max()), 3)
    starts = np.cumsum(sizes) - sizes
    index = starts[:, None] + np.minimum(np.arange(width)[None, :], sizes[:, None] - 1)
    loops: np.ndarray = points[index]
    return loops


def _perimeter(points: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(n,) position of points on their boxes' edges, counter-clockwise from
    the lower left corner: 0 to 1 along the bottom, 1 to 2 up the right side,
    2 to 3 along the top, 3 to 4 down the left side (the nearest side)."""
    x, y = points[:, 0], points[:, 1]
    width = np.maximum(high[:, 0] - low[:, 0], 1e-300)
    height = np.maximum(high[:, 1] - low[:, 1], 1e-300)
    distance = np.stack(
        [
            np.abs(y - low[:, 1]),
            np.abs(x - high[:, 0]),
            np.abs(y - high[:, 1]),
            np.abs(x - low[:, 0]),
        ],
        axis=1,
    )
    side = np.argmin(distance, axis=1)
    along = np.choose(
        side,
        [
            (x - low[:, 0]) / width,
            (y - low[:, 1]) / height,
            (high[:, 0] - x) / width,
            (high[:, 1] - y) / height,
        ],
    )
    position: np.ndarray = side + np.clip(along, 0.0, 1.0)
    return position


def _overall(boxes: np.ndarray) -> list[float]:
    """The (4,) box around (n, 4) boxes, column by column (numpy reduces a
    short axis of a 2-D array many times slower)."""
    return [
        float(boxes[:, 0].min()),
        float(boxes[:, 1].min()),
        float(boxes[:, 2].max()),
        float(boxes[:, 3].max()),
    ]


def _meets(boxes: np.ndarray, box: list[float]) -> np.ndarray:
    """(n,) bool: which of (n, 4) boxes meet one box."""
    meets: np.ndarray = (
        (boxes[:, 0] <= box[2])
        & (boxes[:, 1] <= box[3])
        & (boxes[:, 2] >= box[0])
        & (boxes[:, 3] >= box[1])
    )
    return meets


def overlapping_boxes(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(i, j) index arrays of every box ``first[i]`` that overlaps ``second[j]``;
    boxes are (n, 4) ``(xmin, ymin, xmax, ymax)``.

    Only boxes that meet the other set's overall box take part (a terrain
    against the few triangles of one caster keeps the faces under it). Those
    go through a uniform grid in numpy (:func:`_grid_pairs`), or through
    shapely's STRtree where the grid would pair too many boxes that cover
    many of its cells with everything.
    """
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if len(first) == 0 or len(second) == 0:
        return empty
    mine = np.flatnonzero(_meets(first, _overall(second)))
    theirs = np.flatnonzero(_meets(second, _overall(first)))
    if len(mine) == 0 or len(theirs) == 0:
        return empty
    found = _grid_pairs(first[mine], second[theirs])
    if found is None:
        tree = shapely.STRtree(shapely.box(*second[theirs].T))
        # The geometries are their own envelopes: the tree's box test is the whole test.
        found = tuple(tree.query(shapely.box(*first[mine].T)))
    return mine[found[0]], theirs[found[1]]


def _grid_pairs(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Every (i, j) with box ``first[i]`` overlapping box ``second[j]``, by a
    uniform grid with cells twice a typical box: each box is listed in the
    cells it covers, boxes sharing a cell are paired, and the pairs are checked
    and made unique. Boxes covering very many cells meet every other box;
    None where that, or crowded cells (images piled up along a grazing
    light), would make many more candidate pairs than boxes."""
    box_first, box_second = _overall(first), _overall(second)
    low = np.minimum(box_first[:2], box_second[:2])
    high = np.maximum(box_first[2:], box_second[2:])
    width = np.concatenate([first[:, 2] - first[:, 0], second[:, 2] - second[:, 0]])
    height = np.concatenate([first[:, 3] - first[:, 1], second[:, 3] - second[:, 1]])
    typical = np.array([np.median(width), np.median(height)])
    cell = np.maximum(typical * 2.0, (high - low) / 4096)
    cell = np.maximum(cell, 1e-300)
    columns = int(np.ceil((high[0] - low[0]) / cell[0])) + 1

    def cells(boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        start = np.floor((boxes[:, :2] - low) / cell).astype(np.int64)
        stop = np.floor((boxes[:, 2:] - low) / cell).astype(np.int64)
        span = stop - start + 1
        count = span[:, 0] * span[:, 1]
        big = count > 64
        ids = np.flatnonzero(~big)
        count = count[ids]
        owner = np.repeat(ids, count)
        k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        width = span[owner, 0]
        return (
            owner,
            (start[owner, 1] + k // width) * columns + start[owner, 0] + k % width,
            np.flatnonzero(big),
        )

    owner_a, cell_a, big_a = cells(first)
    owner_b, cell_b, big_b = cells(second)
    if len(big_a) * len(second) + len(big_b) * len(first) > 4 * (len(first) + len(second)):
        return None  # boxes too unlike in size for one grid
    order = np.argsort(cell_b, kind="stable")
    owner_b, cell_b = owner_b[order], cell_b[order]
    begin = np.searchsorted(cell_b, cell_a, side="left")
    count = np.searchsorted(cell_b, cell_a, side="right") - begin
    if int(count.sum()) > 8 * (len(first) + len(second)):
        return None  # crowded cells: most candidates would be repeats or misses
    i = np.repeat(owner_a, count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    j = owner_b[np.repeat(begin, count) + k]
    i = np.concatenate(
        [i, np.repeat(big_a, len(second)), np.tile(np.arange(len(first)), len(big_b))]
    )
    j = np.concatenate(
        [j, np.tile(np.arange(len(second)), len(big_a)), np.repeat(big_b, len(first))]
    )
    mine, theirs = first[i], second[j]
    overlap = (
        (mine[:, 0] <= theirs[:, 2])
        & (mine[:, 1] <= theirs[:, 3])
        & (theirs[:, 0] <= mine[:, 2])
        & (theirs[:, 1] <= mine[:, 3])
    )
    key = np.sort(i[overlap] * np.int64(len(second)) + j[overlap])
    key = key[np.append(True, key[1:] != key[:-1])[: len(key)]]
    return key // len(second), key % len(second)


def candidate_pairs(
    receivers: Triangles,
    casters: Triangles,
    light_position: np.ndarray | None,
    direction: np.ndarray | None,
    pad: float,
) -> tuple[np.ndarray, np.ndarray]:
    """(receiver index, caster index) pairs whose images from the light overlap.

    Parameters
    ----------
    receivers, casters : (n, 3, 3) float64, or (points (p, 3), faces (n, 3))
        Triangles, in any common frame.
    light_position : (3,) float64 or None
        A point light's position in that frame, or None for a directional light.
    direction : (3,) float64 or None
        A directional light's unit direction.
    pad : float
        Boxes grow by this much (relative for a point light's unit cube frame,
        scene units for a directional light) so that touching images pair.

    Returns
    -------
    (k,) int64 receiver indices and (k,) int64 caster indices, sorted by
    receiver, each pair once.
    """
    receiver_points, receiver_faces = _indexed(receivers)
    caster_points, caster_faces = _indexed(casters)
    if len(receiver_faces) == 0 or len(caster_faces) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    if light_position is None:
        # A directional light: the caller passes its direction.
        along = cast(np.ndarray, direction)
        receiver_boxes = _directional_boxes(receiver_points, receiver_faces, along)
        caster_boxes = _directional_boxes(caster_points, caster_faces, along)
    else:
        receiver_boxes = _cube_boxes(receiver_points - light_position, receiver_faces)
        caster_boxes = _cube_boxes(caster_points - light_position, caster_faces)
    keys = []
    n_casters = np.int64(len(caster_faces))
    grow = np.array([-pad, -pad, pad, pad])
    for (have_mine, mine), (have_theirs, theirs) in zip(receiver_boxes, caster_boxes, strict=True):
        if len(have_mine) == 0 or len(have_theirs) == 0:
            continue
        found = overlapping_boxes(mine + grow, theirs + grow)
        keys.append(have_mine[found[0]] * n_casters + have_theirs[found[1]])
    if not keys:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    unique = np.sort(np.concatenate(keys))
    unique = unique[np.append(True, unique[1:] != unique[:-1])[: len(unique)]]
    return unique // n_casters, unique % n_casters


class Outline:
    """A closed caster's shadow seen from the light: its silhouette loops
    projected once into a 2-D frame across the light's rays, and united.

    The caster's shadow on any plane wholly behind it (seen from the light) is
    this region mapped onto the plane; on a receiver face it is the region
    clipped to the face's own image in this frame.

    Attributes
    ----------
    region : shapely geometry
        The united outline in frame coordinates (after :meth:`unite`).
    cross_section : manifold3d.CrossSection
        The same, scaled by ``scale`` for Clipper2.
    """

    def __init__(
        self,
        light_point: np.ndarray | None,
        axis: np.ndarray,
        first: np.ndarray,
        second: np.ndarray,
        direction: np.ndarray | None,
    ) -> None:
        self.light_point = light_point
        self.axis, self.first, self.second = axis, first, second
        self.direction = direction

    def unite(self, points2d_loops: list[np.ndarray]) -> None:
        """Set the region: the positive-winding union of the projected loops."""
        extent = max(float(np.abs(np.concatenate(points2d_loops)).max()), 1e-300)
        self.scale = MAX_COORDINATE / extent / 4.0
        united = fill([loop * self.scale for loop in points2d_loops])
        self.parts = components(united)
        self.region = shapely.MultiPolygon(
            [
                shapely.Polygon(p[0] / self.scale, [h / self.scale for h in p[1:]])
                for p in self.parts
            ]
        )
        shapely.prepare(self.region)
        self.cross_section = united
        # The region's loops in frame coordinates, and each boundary
        # segment's (xmin, ymin, xmax, ymax) box.
        self.loops = [loop / self.scale for part in self.parts for loop in part]
        if self.loops:
            start = np.concatenate(self.loops)
            end = np.concatenate([np.roll(loop, -1, axis=0) for loop in self.loops])
        else:
            start = end = np.zeros((0, 2))
        self.segments = np.stack([start, end], axis=1)  # (s, 2, 2)
        sizes = np.array([len(loop) for loop in self.loops], dtype=np.int64)
        self.segment_loop = np.repeat(np.arange(len(sizes)), sizes)
        first = np.repeat(np.cumsum(sizes) - sizes, sizes)
        self.segment_next = np.arange(len(start)) + 1
        self.segment_next[np.cumsum(sizes) - 1] = first[np.cumsum(sizes) - 1]
        self.segment_boxes = np.column_stack([np.minimum(start, end), np.maximum(start, end)])

    def cut(
        self, images: np.ndarray, margin: float | np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The region cut to each of (f, 3, 2) triangles in the frame.

        1. Triangles whose box meets no boundary segment's box lie wholly
           inside or wholly outside the region, as their first corner does;
           the others are tested as polygons (shapely).
        2. A triangle the boundary crosses gets signed convex pieces: the
           region's winding number at a point ``p`` of the triangle is its
           winding number at a reference point ``r`` (the centroid) plus the
           signed count of boundary segments that the path from ``r`` to ``p``
           crosses. That path stays in the triangle, so only segments whose box
           meets the triangle's count, and segment ``ab`` is crossed exactly
           when ``p`` lies in the wedge from ``r`` through ``a`` and ``b``,
           beyond the line ``ab``: a convex piece of the triangle, wound
           counter-clockwise where ``r`` lies right of ``ab`` (+1) and
           clockwise where left (-1). With the whole triangle where ``r`` is
           inside, the pieces' winding numbers add up to the region's (0 or 1)
           at every point of the triangle off their edges, and the work per
           triangle grows with the boundary near it, not the whole outline.
        3. A triangle whose ``r`` lies within its ``margin`` of the boundary
           (its winding there is not sure) is cut by Clipper2 instead.

        Returns
        -------
        covered : (f,) bool
            Triangles wholly inside the region (they get no pieces).
        pieces : (n, k, 2) float64
            Polygons in the frame, padded by repeating the last corner, whose
            winding numbers add up to the region's inside their triangle.
        owners : (n,) int64
            The triangle of each piece.
        """
        count = len(images)
        covered = np.zeros(count, dtype=bool)
        nothing = (covered, np.zeros((0, 3, 2)), np.zeros(0, np.int64))
        if count == 0 or not self.loops:
            return nothing
        boxes = np.column_stack([corner_min(images), corner_max(images)])
        tri, seg = overlapping_boxes(boxes, self.segment_boxes)
        crossing = np.zeros(count, dtype=bool)
        crossing[tri] = True
        clear = np.flatnonzero(~crossing)
        covered[clear] = shapely.contains_xy(self.region, images[clear, 0, 0], images[clear, 0, 1])
        near = np.flatnonzero(crossing)
        polygons = shapely.polygons(images[near])
        inside = shapely.covers(self.region, polygons)
        covered[near] = inside
        touched = np.zeros(count, dtype=bool)
        touched[near] = shapely.intersects(self.region, polygons) & ~inside
        if not touched.any():
            return nothing
        x, y = images[:, :, 0], images[:, :, 1]
        clockwise = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1) < 0
        images = np.where(clockwise[:, None, None], images[:, ::-1], images)
        keep = touched[tri]
        tri, seg = tri[keep], seg[keep]

        # 2. each triangle's own stretch of the boundary, closed around it
        reference = images.mean(axis=1)
        a, b, r = self.segments[seg, 0], self.segments[seg, 1], reference[tri]
        ab, ar = b - a, r - a
        length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
        along = np.clip(np.einsum("ij,ij->i", ar, ab) / length2, 0.0, 1.0)
        gap = np.hypot(*(ar - along[:, None] * ab).T)  # from r to the segment
        unsure = np.zeros(count, dtype=bool)
        unsure[tri[gap <= np.broadcast_to(margin, (count,))[tri]]] = True
        sure = np.flatnonzero(touched & ~unsure)
        points, sizes, owners = self._local_cut(images, reference, sure, tri, seg)

        # 3. Clipper2 where the reference point is not sure
        exact, exact_owners = self.clip_to(images[unsure])
        if exact:
            points = np.concatenate([points, *exact])
            sizes = np.concatenate([sizes, [len(loop) for loop in exact]])
            owners = np.concatenate([owners, np.flatnonzero(unsure)[exact_owners]])
        return covered, padded_loops(points, sizes), owners.astype(np.int64)

    def _local_cut(
        self,
        images: np.ndarray,
        reference: np.ndarray,
        sure: np.ndarray,
        tri: np.ndarray,
        seg: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The region cut to each triangle ``sure`` (counter-clockwise in
        ``images``), from the boundary segments near it only (pairs ``tri``,
        ``seg``, sorted).

        Each segment is clipped to a box around the triangle; consecutive
        pieces of one loop are joined along the box's edge, counter-clockwise.
        Inside the box that polygon winds as the region does, up to one
        constant (the ways around the box it took or missed): the region's
        winding at the reference point, against the polygon's there, gives it,
        and as many loops of the box put it right. The triangle's part of that
        is then cut by Clipper2: every triangle in its own cell of one plane,
        one call. Returns the loops' points, their sizes, and their triangles.
        """
        if len(sure) == 0:
            return np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64)
        low, high = corner_min(images[sure]), corner_max(images[sure])
        pad = 0.05 * np.maximum(high[:, 0] - low[:, 0], high[:, 1] - low[:, 1])[:, None]
        box_low = np.zeros((len(images), 2))
        box_high = np.zeros((len(images), 2))
        box_low[sure], box_high[sure] = low - pad, high + pad
        is_sure = np.zeros(len(images), dtype=bool)
        is_sure[sure] = True
        keep = is_sure[tri]
        order = np.lexsort((seg[keep], tri[keep]))
        tri, seg = tri[keep][order], seg[keep][order]
        a, b = self.segments[seg, 0], self.segments[seg, 1]
        step = b - a
        # Liang-Barsky: the part a + t (b - a), t0 <= t <= t1, inside the box.
        t0, t1 = np.zeros(len(tri)), np.ones(len(tri))
        with np.errstate(divide="ignore", invalid="ignore"):
            for axis in range(2):
                first = (box_low[tri, axis] - a[:, axis]) / step[:, axis]
                second = (box_high[tri, axis] - a[:, axis]) / step[:, axis]
                flat = step[:, axis] == 0
                within = (a[:, axis] >= box_low[tri, axis]) & (a[:, axis] <= box_high[tri, axis])
                enter = np.where(flat, np.where(within, -np.inf, np.inf), np.minimum(first, second))
                leave = np.where(flat, np.where(within, np.inf, -np.inf), np.maximum(first, second))
                t0, t1 = np.maximum(t0, enter), np.minimum(t1, leave)
        keep = t0 < t1
        tri, seg, a, b, step, t0, t1 = (x[keep] for x in (tri, seg, a, b, step, t0, t1))
        start = np.where((t0 == 0)[:, None], a, a + t0[:, None] * step)
        end = np.where((t1 == 1)[:, None], b, a + t1[:, None] * step)
        # Pieces grouped by (triangle, loop); each followed by the next of its group.
        group_key = tri * len(self.loops) + self.segment_loop[seg]
        new_group = np.ones(len(tri), dtype=bool)
        new_group[1:] = group_key[1:] != group_key[:-1]
        group = np.cumsum(new_group) - 1
        group_start = np.flatnonzero(new_group)
        following = np.arange(len(tri)) + 1
        last = np.append(group_start[1:], len(tri)) - 1
        following[last] = group_start
        joined = (seg[following] == self.segment_next[seg]) & (t1 == 1)
        # The way along the box, counter-clockwise, from each piece's end to
        # the next piece's start: the box corners passed.
        lo, hi = box_low[tri], box_high[tri]
        leave_at = _perimeter(end, lo, hi)
        enter_at = _perimeter(start[following], lo, hi)
        travel = np.mod(enter_at - leave_at, 4.0)
        steps = np.floor(leave_at)[:, None] + np.arange(1, 5)[None, :]
        passed = ((steps - leave_at[:, None]) < travel[:, None]) & ~joined[:, None]
        corner = np.mod(steps, 4).astype(np.int64)
        corner_x = np.where((corner == 1) | (corner == 2), hi[:, :1], lo[:, :1])
        corner_y = np.where(corner >= 2, hi[:, 1:], lo[:, 1:])
        # Each piece: its start, its end, the corners it passes (masked).
        points = np.concatenate(
            [start[:, None], end[:, None], np.stack([corner_x, corner_y], axis=2)], axis=1
        )
        used = np.concatenate([np.ones((len(tri), 2), dtype=bool), passed], axis=1)
        flat_points = points[used]
        point_group = np.repeat(group, used.sum(axis=1))
        point_tri = tri[group_start][point_group]
        # The polygon's winding at each triangle's reference point.
        sizes = np.bincount(point_group, minlength=len(group_start))
        offsets = np.cumsum(sizes) - sizes
        successor = np.arange(len(flat_points)) + 1
        successor[offsets + sizes - 1] = offsets
        p, q = flat_points, flat_points[successor]
        rp = reference[point_tri]
        side = (q[:, 0] - p[:, 0]) * (rp[:, 1] - p[:, 1]) - (rp[:, 0] - p[:, 0]) * (
            q[:, 1] - p[:, 1]
        )
        up = (p[:, 1] <= rp[:, 1]) & (rp[:, 1] < q[:, 1]) & (side > 0)
        down = (q[:, 1] <= rp[:, 1]) & (rp[:, 1] < p[:, 1]) & (side < 0)
        winding = np.bincount(point_tri, weights=up.astype(float) - down, minlength=len(images))
        truth = shapely.contains_xy(self.region, reference[:, 0], reference[:, 1])
        boxes_needed = np.rint(truth - winding).astype(np.int64)
        # One Clipper2 call: triangle k in cell k of a square grid, scaled alike
        # along x and y, its box within the cell.
        columns = int(np.ceil(np.sqrt(len(sure))))
        cell = 2.0 * MAX_COORDINATE / columns
        slot = np.full(len(images), -1, dtype=np.int64)
        slot[sure] = np.arange(len(sure))
        centre = np.column_stack(
            [
                -MAX_COORDINATE + cell * (slot % columns + 0.5),
                -MAX_COORDINATE + cell * (slot // columns + 0.5),
            ]
        )
        middle = 0.5 * (box_low + box_high)
        size = np.maximum((box_high - box_low).max(axis=1), 1e-300)
        scale = 0.45 * cell / size
        mapped = (flat_points - middle[point_tri]) * scale[point_tri, None] + centre[point_tri]
        subject = [mapped[o : o + n] for o, n in zip(offsets.tolist(), sizes.tolist(), strict=True)]
        square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
        for k in np.flatnonzero(boxes_needed[sure] != 0):
            face = sure[k]
            half = 0.5 * (box_high[face] - box_low[face])
            loop = (square * half) * scale[face] + centre[face]
            count = int(boxes_needed[face])
            subject += [loop if count > 0 else loop[::-1]] * abs(count)
        clip = (images[sure] - middle[sure][:, None]) * scale[sure][:, None, None]
        clip = clip + centre[sure][:, None]
        region = fill(subject) ^ fill(list(clip))
        out = [loop for loop in region.to_polygons() if len(loop) >= 3]
        nothing = (np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64))
        if not out:
            return nothing
        out_sizes = np.array([len(loop) for loop in out], dtype=np.int64)
        out_points = np.concatenate(out)
        first_points = out_points[np.cumsum(out_sizes) - out_sizes]
        column = np.clip(np.floor((first_points[:, 0] + MAX_COORDINATE) / cell), 0, columns - 1)
        row = np.clip(np.floor((first_points[:, 1] + MAX_COORDINATE) / cell), 0, columns - 1)
        owner = sure[np.minimum((row * columns + column).astype(np.int64), len(sure) - 1)]
        point_owner = np.repeat(owner, out_sizes)
        out_points = (out_points - centre[point_owner]) / scale[point_owner, None] + middle[
            point_owner
        ]
        return out_points, out_sizes, owner

    def clip_to(self, images: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """The region cut to each of (f, 3, 2) counter-clockwise triangles in
        the frame: loops, and (n,) the triangle of each loop."""
        loops: list[np.ndarray] = []
        owners: list[int] = []
        for k, image in enumerate(images):
            piece = self.cross_section ^ fill([image * self.scale])
            for loop in piece.to_polygons():
                loops.append(np.asarray(loop) / self.scale)
                owners.append(k)
        return loops, np.array(owners, dtype=np.int64)

    def ahead(self, points: np.ndarray) -> np.ndarray:
        """(..., ) distance of points ahead of the light along the frame's axis
        (positive for a directional light)."""
        if self.light_point is None:
            return np.full(points.shape[:-1], np.inf)
        distance: np.ndarray = (points - self.light_point) @ self.axis
        return distance

    def may_reach(self, triangles: Triangles) -> np.ndarray:
        """(n,) bool for n triangles: False where the caster surely casts
        nothing on it -- the triangle lies ahead of the light and its image
        misses the outline's box (the caster's image lies in it)."""
        points, faces = _indexed(triangles)
        if len(faces) == 0:
            return np.zeros(0, dtype=bool)
        ahead = corner_min(self.ahead(points)[faces]) > 0
        out = np.ones(len(faces), dtype=bool)
        if not ahead.any():
            return out
        with np.errstate(divide="ignore", invalid="ignore"):
            images = self.to_frame(points)  # only the points ahead are used
        x, y = images[:, 0][faces[ahead]], images[:, 1][faces[ahead]]
        low_x, low_y, high_x, high_y = self.region.bounds
        misses = (
            (corner_min(x) > high_x)
            | (corner_min(y) > high_y)
            | (corner_max(x) < low_x)
            | (corner_max(y) < low_y)
        )
        out[np.flatnonzero(ahead)[misses]] = False
        return out

    def to_frame(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) points to (..., 2) frame coordinates (their rays)."""
        if self.light_point is None:
            return np.stack([points @ self.first, points @ self.second], axis=-1)
        relative = points - self.light_point
        depth = relative @ self.axis
        return np.stack([relative @ self.first / depth, relative @ self.second / depth], axis=-1)

    def onto_planes(self, flat: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """(n, 2) frame points to (n, 3) points where their rays meet the planes
        ``normals[i] . x + offsets[i] = 0``, one plane per point."""
        if self.light_point is None:
            base = np.outer(flat[:, 0], self.first) + np.outer(flat[:, 1], self.second)
            height = np.einsum("ij,ij->i", base, normals) + offsets
            # Without a light point the outline is a directional light's: it has a direction.
            direction = cast(np.ndarray, self.direction)
            lowered: np.ndarray = base - (height / (normals @ direction))[:, None] * direction
            return lowered
        rays = self.axis + np.outer(flat[:, 0], self.first) + np.outer(flat[:, 1], self.second)
        height = normals @ self.light_point + offsets
        along = -height / np.einsum("ij,ij->i", rays, normals)
        met: np.ndarray = self.light_point + rays * along[:, None]
        return met


def make_outline(
    vertices: np.ndarray,
    loops: list[np.ndarray],
    all_vertices: np.ndarray,
    light_point: np.ndarray | None,
    direction: np.ndarray | None,
    margin: float,
) -> Outline | None:
    """The :class:`Outline` of a caster whose silhouette ``loops`` index
    ``vertices``; None when a point light is not wholly behind one plane
    through the light and the caster (``all_vertices``), which a central
    projection needs."""
    if not loops:
        return None
    axis: np.ndarray
    if light_point is None:
        # A directional light: the caller passes its direction.
        axis = cast(np.ndarray, direction)
    else:
        axis = all_vertices.mean(axis=0) - light_point
        axis = axis / np.linalg.norm(axis)
        if float(((all_vertices - light_point) @ axis).min()) <= margin:
            return None
    helper = np.zeros(3)
    helper[int(np.argmin(np.abs(axis)))] = 1.0
    first = np.cross(axis, helper)
    first /= np.linalg.norm(first)
    # first x second = -axis: loops counter-clockwise seen from the light stay so.
    second = np.cross(first, axis)
    outline = Outline(light_point, axis, first, second, direction)
    outline.unite([outline.to_frame(vertices[loop]) for loop in loops])
    return outline
