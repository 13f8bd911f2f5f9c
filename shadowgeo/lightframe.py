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

from .errors import GeometryError
from .limits import MAX_SURFACE_PAIRS
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
    """One Sutherland-Hodgman step on rows that the plane cuts: (r, k', d)."""
    rows, width, size = points.shape
    inside = (side >= 0) & valid
    slots = np.arange(width)
    following = (slots[None, :] + 1) % np.maximum(counts[:, None], 1)
    side_next = np.take_along_axis(side, following, axis=1)
    inside_next = np.take_along_axis(inside, following, axis=1)
    crosses = valid & (inside != inside_next)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(crosses, side / np.where(crosses, side - side_next, 1.0), 0.0)
    nxt = np.take_along_axis(points, following[:, :, None], axis=1)
    crossing = points + t[:, :, None] * (nxt - points)
    candidates = np.stack([points, crossing], axis=2).reshape(rows, 2 * width, size)
    keep = np.stack([inside, crosses], axis=2).reshape(rows, 2 * width)
    counts = keep.sum(axis=1)
    position = np.cumsum(keep, axis=1) - 1
    row, col = np.nonzero(keep)
    out = np.zeros((rows, max(int(counts.max()), 1), size))
    out[row, position[row, col]] = candidates[row, col]
    return out, counts


def _directional_boxes(
    triangles: np.ndarray, direction: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray]]:
    """One frame, the plane across the rays: every triangle and its (n, 4) box."""
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(direction)))] = 1.0
    first = np.cross(direction, axis)
    first /= np.linalg.norm(first)
    second = np.cross(direction, first)
    x = triangles @ first
    y = triangles @ second
    boxes = np.column_stack([corner_min(x), corner_min(y), corner_max(x), corner_max(y)])
    return [(np.arange(len(triangles)), boxes)]


def _cube_boxes(triangles: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Six frames around a light at the origin: for each cube side, the
    triangles whose image reaches it and (k, 4) boxes of their images there."""
    # Each corner's side: its largest coordinate. A triangle with all three
    # corners on one side lies inside that side's pyramid (it is convex).
    largest = np.argmax(np.abs(triangles), axis=2)
    positive = np.take_along_axis(triangles, largest[:, :, None], axis=2)[:, :, 0] > 0
    side_of = 2 * largest + np.where(positive, 0, 1)  # index into _CUBE_SIDES
    whole = np.all(side_of == side_of[:, :1], axis=1)
    spanning = np.flatnonzero(~whole)
    out = []
    for index, (axis, sign) in enumerate(_CUBE_SIDES):
        across = [a for a in range(3) if a != axis]
        mine = np.flatnonzero(whole & (side_of[:, 0] == index))
        chunk = triangles[mine]
        w = sign * chunk[:, :, axis]
        u, v = chunk[:, :, across[0]] / w, chunk[:, :, across[1]] / w
        boxes = [np.column_stack([corner_min(u), corner_min(v), corner_max(u), corner_max(v)])]
        members = [mine]
        if len(spanning):
            found, box = _clipped_boxes(triangles[spanning], axis, sign, across)
            boxes.append(box)
            members.append(spanning[found])
        out.append((np.concatenate(members), np.concatenate(boxes)))
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


# Pairs one STRtree query may return (64 MB of indices), so that a query
# that would exceed the pair budget stops before filling memory.
_QUERY_PAIRS = 4_000_000


def overlapping_boxes(
    first: np.ndarray, second: np.ndarray, budget: int = MAX_SURFACE_PAIRS
) -> tuple[np.ndarray, np.ndarray]:
    """(i, j) index arrays of every box ``first[i]`` that overlaps ``second[j]``;
    boxes are (n, 4) ``(xmin, ymin, xmax, ymax)``.

    Two sets of very different sizes (a terrain against a few hundred caster
    triangles) go through a uniform grid in numpy; similar sizes through
    shapely's STRtree, whose cost is mostly making one box geometry per box.

    Raises
    ------
    GeometryError
        More than ``budget`` overlapping pairs (a soup of large triangles
        over one another: every pair would be clipped).
    """
    if 8 * min(len(first), len(second)) < max(len(first), len(second)):
        return _grid_pairs(first, second, budget)
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
        raise GeometryError(
            f"more than {budget:,} (receiving face, caster triangle) pairs overlap as seen "
            "from the light (shadowgeo.limits.MAX_SURFACE_PAIRS)"
        )


def _grid_pairs(
    first: np.ndarray, second: np.ndarray, budget: int
) -> tuple[np.ndarray, np.ndarray]:
    """Every (i, j) with box ``first[i]`` overlapping box ``second[j]``, by a
    uniform grid with cells twice a typical box: each box is listed in the
    cells it covers, boxes sharing a cell are paired, and the pairs are checked
    and made unique. Boxes covering very many cells meet every other box."""
    sizes = np.concatenate([first[:, 2:] - first[:, :2], second[:, 2:] - second[:, :2]])
    low = np.minimum(first[:, :2].min(axis=0), second[:, :2].min(axis=0))
    high = np.maximum(first[:, 2:].max(axis=0), second[:, 2:].max(axis=0))
    cell = np.maximum(np.median(sizes, axis=0) * 2.0, (high - low) / 4096)
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
    order = np.argsort(cell_b, kind="stable")
    owner_b, cell_b = owner_b[order], cell_b[order]
    begin = np.searchsorted(cell_b, cell_a, side="left")
    count = np.searchsorted(cell_b, cell_a, side="right") - begin
    # A pair shares at most 64 cells (boxes covering more are "big").
    candidates = int(count.sum()) + len(big_a) * len(second) + len(big_b) * len(first)
    _check_pairs(candidates // 64, budget)
    i = np.repeat(owner_a, count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    j = owner_b[np.repeat(begin, count) + k]
    i = np.concatenate(
        [i, np.repeat(big_a, len(second)), np.tile(np.arange(len(first)), len(big_b))]
    )
    j = np.concatenate(
        [j, np.tile(np.arange(len(second)), len(big_a)), np.repeat(big_b, len(first))]
    )
    overlap = np.all(first[i, :2] <= second[j, 2:], axis=1) & np.all(
        second[j, :2] <= first[i, 2:], axis=1
    )
    key = np.sort(i[overlap] * np.int64(len(second)) + j[overlap])
    key = key[np.append(True, key[1:] != key[:-1])[: len(key)]]
    _check_pairs(len(key), budget)
    return key // len(second), key % len(second)


def candidate_pairs(
    receivers: np.ndarray,
    casters: np.ndarray,
    light_position: np.ndarray | None,
    direction: np.ndarray | None,
    pad: float,
) -> tuple[np.ndarray, np.ndarray]:
    """(receiver index, caster index) pairs whose images from the light overlap.

    Parameters
    ----------
    receivers, casters : (n, 3, 3) float64
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
    if len(receivers) == 0 or len(casters) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    if light_position is None:
        # A directional light: the caller passes its direction.
        receiver_boxes = _directional_boxes(receivers, cast(np.ndarray, direction))
        caster_boxes = _directional_boxes(casters, cast(np.ndarray, direction))
    else:
        receiver_boxes = _cube_boxes(receivers - light_position)
        caster_boxes = _cube_boxes(casters - light_position)
    keys = []
    n_casters = np.int64(len(casters))
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

    def ahead(self, points: np.ndarray) -> np.ndarray:
        """(..., ) distance of points ahead of the light along the frame's axis
        (positive for a directional light)."""
        if self.light_point is None:
            return np.full(points.shape[:-1], np.inf)
        distance: np.ndarray = (points - self.light_point) @ self.axis
        return distance

    def may_reach(self, triangles: np.ndarray) -> np.ndarray:
        """(n,) bool for (n, 3, 3) triangles: False where the caster surely
        casts nothing on it -- the triangle lies ahead of the light and its
        image misses the outline's box (the caster's image lies in it)."""
        if len(triangles) == 0:
            return np.zeros(0, dtype=bool)
        ahead = corner_min(self.ahead(triangles)) > 0
        out = np.ones(len(triangles), dtype=bool)
        if not ahead.any():
            return out
        images = self.to_frame(triangles[ahead])
        low, high = np.array(self.region.bounds[:2]), np.array(self.region.bounds[2:])
        misses = np.any((corner_min(images) > high) | (corner_max(images) < low), axis=1)
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
