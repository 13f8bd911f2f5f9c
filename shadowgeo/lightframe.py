"""The light's own 2-D frame: which caster triangles can reach which receiver faces.

Seen from the light, a caster triangle can only shadow a receiver face whose
image overlaps its own. Images are taken in the light's frame: for a
directional light the plane across its rays; for a point light the six sides
of a cube map around it (each side a square pyramid of rays, so every image is
bounded and nothing is divided by ``w <= 0``). A 2-D bounding-box index in that
frame (a uniform grid, or shapely's STRtree where the boxes pile up) then
lists the candidate (face, triangle) pairs without looking at every pair.

The triangles are clipped to each cube side in homogeneous coordinates by
:func:`clip_batch`, a Sutherland-Hodgman clipper that works on many convex
polygons at once; :mod:`shadowgeo.surface` uses the same clipper to cut
casters to the slab between a face and the light.

:class:`shadowgeo.outline.Outline` is a closed caster's silhouette in such a
frame, computed once per light.
"""

from __future__ import annotations

import warnings
from typing import cast

import numpy as np
import shapely

from .errors import BudgetError
from .limits import MAX_SURFACE_PAIRS, TINY

__all__ = [
    "Triangles",
    "candidate_pairs",
    "clip_batch",
    "clip_one",
    "corner_max",
    "corner_min",
    "indexed_triangles",
    "misses_boxes",
    "overlapping_boxes",
    "twice_areas",
]

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


def twice_areas(triangles: np.ndarray) -> np.ndarray:
    """(n,) twice the signed area of each (n, 3, 2) triangle, positive
    counter-clockwise (the shoelace sum, corner by corner)."""
    x, y = triangles[:, :, 0], triangles[:, :, 1]
    after = [1, 2, 0]  # each corner's next (np.roll's numbers, without its cost)
    doubled: np.ndarray = np.sum(x * y[:, after] - x[:, after] * y, axis=1)
    return doubled


def misses_boxes(images: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(n,) bool: whether each (n, 3, 2) triangle's box misses its box
    ``boxes[i]`` (xmin, ymin, xmax, ymax); NaN boxes are missed by none."""
    x, y = images[:, :, 0], images[:, :, 1]
    low_x, low_y, high_x, high_y = boxes.T
    misses: np.ndarray = (
        (corner_min(x) > high_x)
        | (corner_min(y) > high_y)
        | (corner_max(x) < low_x)
        | (corner_max(y) < low_y)
    )
    return misses


def clip_batch(
    points: np.ndarray, counts: np.ndarray, planes: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Clip many convex polygons to half-spaces ``plane . x >= 0``, at once.

    Sutherland-Hodgman over arrays: the one convex clipper of the package (a
    single polygon is a batch of one, see :func:`clip_one`). Only the rows a
    plane cuts are rebuilt.

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
    # Each plane adds at most one corner to a convex polygon.
    out = np.zeros((n, width + planes.shape[-2], size))
    out[:, :width] = points
    for j in range(planes.shape[-2]):
        used = int(counts.max()) if n else 0
        if used == 0:
            break
        side = _sides(out[:, :used], planes[..., j, :])
        valid = np.arange(used)[None, :] < counts[:, None]
        rows = np.flatnonzero(np.any(valid & (side < 0), axis=1))
        if len(rows) == 0:
            continue
        new, counts[rows] = _clip_rows(out[rows, :used], counts[rows], side[rows], valid[rows])
        if new.shape[1] > out.shape[1]:  # rounding made a near-degenerate polygon non-convex
            out = np.pad(out, ((0, 0), (0, new.shape[1] - out.shape[1]), (0, 0)))
        out[rows, : new.shape[1]] = new
    used = max(int(counts.max()) if n else 0, 1)
    return out[:, :used], counts


def clip_one(polygon: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """:func:`clip_batch` of one convex polygon (k, d) by half-spaces (p, d):
    its clipped corners (k', d), none when it is clipped away."""
    clipped, counts = clip_batch(polygon[None], np.array([len(polygon)]), planes)
    corners: np.ndarray = clipped[0, : counts[0]]
    return corners


def _sides(points: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """(n, k) ``plane . x`` of each corner: one plane (d,) for all rows, or
    one (n, d) a row."""
    if plane.ndim == 1:
        side: np.ndarray = points @ plane
    else:
        side = np.einsum("nkd,nd->nk", points, plane)
    return side


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


def indexed_triangles(triangles: Triangles) -> tuple[np.ndarray, np.ndarray]:
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


# Box pairs up to which overlapping_boxes tests every pair (a caster's outline
# against the few faces near it) rather than build a grid.
_DIRECT_PAIRS = 4096
# Pairs one STRtree query may return (64 MB of indices), so that a query
# that would exceed the pair budget stops before filling memory.
_QUERY_PAIRS = 4_000_000


def overlapping_boxes(
    first: np.ndarray, second: np.ndarray, budget: int = MAX_SURFACE_PAIRS
) -> tuple[np.ndarray, np.ndarray]:
    """(i, j) index arrays of every box ``first[i]`` that overlaps ``second[j]``;
    boxes are (n, 4) ``(xmin, ymin, xmax, ymax)``.

    Only boxes that meet the other set's overall box take part (a terrain
    against the few triangles of one caster keeps the faces under it). Those
    go through a uniform grid in numpy (:func:`_grid_pairs`, whose candidates
    are bounded by a few times the boxes), or through shapely's STRtree where
    the grid would pair too many boxes that cover many of its cells with
    everything, queried in chunks against ``budget``.

    Raises
    ------
    GeometryError
        More than ``budget`` overlapping pairs (a soup of large triangles
        over one another: every pair would be clipped).
    """
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if len(first) == 0 or len(second) == 0:
        return empty
    mine = np.flatnonzero(_meets(first, _overall(second)))
    theirs = np.flatnonzero(_meets(second, _overall(first)))
    if len(mine) == 0 or len(theirs) == 0:
        return empty
    if len(mine) * len(theirs) <= _DIRECT_PAIRS:  # few: every pair, no grid
        a, b = first[mine], second[theirs]
        overlap = (a[:, None, 0] <= b[None, :, 2]) & (a[:, None, 1] <= b[None, :, 3])
        overlap &= (b[None, :, 0] <= a[:, None, 2]) & (b[None, :, 1] <= a[:, None, 3])
        i, j = np.nonzero(overlap)  # sorted by i, then j, as the grid's pairs
        _check_pairs(len(i), budget)
        return mine[i], theirs[j]
    found = _grid_pairs(first[mine], second[theirs])
    if found is None:
        found = _tree_pairs(first[mine], second[theirs], budget)
    if len(found[0]) > budget:
        _check_pairs(len(found[0]), budget)
    return mine[found[0]], theirs[found[1]]


def _tree_pairs(
    first: np.ndarray, second: np.ndarray, budget: int
) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping box pairs by shapely's STRtree, a chunk of queries at a
    time so that too many pairs stop at the budget, not at memory."""
    tree = shapely.STRtree(shapely.box(*second.T))
    queries = shapely.box(*first.T)
    chunk = max(1, _QUERY_PAIRS // max(len(second), 1))
    found_first, found_second, total = [], [], 0
    for start in range(0, len(first), chunk):
        # The geometries are their own envelopes: the tree's box test is the whole test.
        found = tree.query(queries[start : start + chunk])
        total += found.shape[1]
        _check_pairs(total, budget)
        found_first.append(found[0] + start)
        found_second.append(found[1])
    if not found_first:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(found_first), np.concatenate(found_second)


def _check_pairs(count: int, budget: int) -> None:
    if count > budget:
        raise BudgetError(
            f"more than {budget:,} (receiving face, caster triangle) pairs overlap as seen "
            "from the light (shadowgeo.limits.MAX_SURFACE_PAIRS)"
        )


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
    cell = np.maximum(cell, TINY)
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
    receiver_points, receiver_faces = indexed_triangles(receivers)
    caster_points, caster_faces = indexed_triangles(casters)
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
