"""Triangulation of 2-D regions: parts with holes (:func:`triangulate_parts`),
one polygon in its own plane (:func:`polygon_triangles`), many polygons of
k corners (:func:`polygons_triangles`), and star-shaped loops in linear time
(:func:`star_triangles`).

Triangles are counter-clockwise and meet only at their sides. manifold3d's
ear clipping does most of the work; a loop of many reflex corners goes to
:func:`star_triangles` or the sweep of :mod:`shadowgeo.sweep` (ear clipping
is quadratic in such corners), and a part of many holes is cut into tiles
first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from manifold3d import triangulate

from ..errors import BudgetError
from ..limits import MAX_POLYGON_CORNERS
from ..orientation import MAX_COORDINATE, turn_sign
from ..plane import Plane
from ..simplify import without_collinear
from ..sweep import simple_triangles
from .nesting import components
from .predicates import (
    is_convex,
    loop_means,
    many_reflex,
    signed_areas,
    star_shaped_flat,
    swept_triangles,
)
from .union import intersect, unite

__all__ = [
    "STRAIGHT_SLACK",
    "fan",
    "polygon_triangles",
    "polygons_triangles",
    "star_triangles",
    "triangulate_parts",
]


# A corner this close (local units) to the straight run between its
# neighbours is dropped before triangulating: a few hundred units in the last
# place of MAX_COORDINATE, far below any length a shadow resolves.
STRAIGHT_SLACK = 64 * MAX_COORDINATE * float(np.finfo(np.float64).eps)


def star_triangles(loop: np.ndarray) -> np.ndarray | None:
    """(k - 2, 3) counter-clockwise triangles of corners of the (k, 2)
    ``loop``, meeting only at their sides, when it is certainly star-shaped
    round the mean ``c`` of its corners (:func:`star_shaped_flat`); None for
    any other loop. Linear in the corners, however many are reflex.

    Ears are cut in one pass with a stack, as a Graham scan walks a hull:
    corner ``b`` between ``a`` and ``d`` is cut when it turns left and ``c``
    lies left of ``a -> d``, both beyond rounding. Such a triangle is an
    ear: it lies in the wedge from ``c`` between ``a`` and ``d``, narrower
    than half a turn, and no other corner is in that wedge (the corners go
    round ``c`` once, in order); the loop left is again star-shaped round
    ``c``. Corners that no certain ear removes (a rectangle, whose diagonals
    run through ``c``) go to manifold3d's triangulation, a small remainder.

    The loop is first scaled by a power of two (exactly) so that its
    largest coordinate from ``c`` is about :data:`MAX_COORDINATE`, the range
    the rounding margins of :func:`turns` are set for.
    """
    local = _star_local(np.asarray(loop, dtype=np.float64))
    if local is None:
        return None
    n = len(local)
    starts, lengths = np.zeros(1, dtype=np.int64), np.array([n])
    cx, cy = (float(value) for value in loop_means(local, starts, lengths)[0])
    star = _StarLoop(local[:, 0].tolist(), local[:, 1].tolist(), cx, cy)
    triangles, rest = star.ears()
    if len(rest) == 3 and star.left(rest[0], rest[1], star.xs[rest[2]], star.ys[rest[2]]):
        triangles.append((rest[0], rest[1], rest[2]))
    elif len(rest) >= 3:
        remainder = np.asarray(triangulate([local[rest]]), dtype=np.int64).reshape(-1, 3)
        triangles.extend(map(tuple, np.asarray(rest, dtype=np.int64)[remainder].tolist()))
    result = np.array(triangles, dtype=np.int64).reshape(-1, 3)
    return result if len(result) == n - 2 else None


def _star_local(loop: np.ndarray) -> np.ndarray | None:
    """The (k, 2) ``loop`` scaled by a power of two (exactly) so that its
    largest coordinate from the mean of its corners is about
    :data:`MAX_COORDINATE`, when it is certainly star-shaped round that
    mean (:func:`star_shaped_flat`); None for any other loop."""
    n = len(loop)
    if n < 3:
        return None
    extent = float(np.abs(loop - loop.mean(axis=0)).max())
    if not (np.isfinite(extent) and extent > 0):
        return None
    local: np.ndarray = np.ldexp(loop, int(np.floor(np.log2(MAX_COORDINATE / extent))))
    if not np.all(np.isfinite(local)) or np.abs(local).max() > 4 * MAX_COORDINATE:
        return None
    starts, lengths = np.zeros(1, dtype=np.int64), np.array([n])
    if not star_shaped_flat(local, starts, lengths)[0]:
        return None
    return local


@dataclass(frozen=True)
class _StarLoop:
    """A loop's corners (``xs``, ``ys``, local units) star-shaped round
    (``cx``, ``cy``), for :func:`star_triangles`' ears."""

    xs: list[float]
    ys: list[float]
    cx: float
    cy: float

    def left(self, i: int, j: int, px: float, py: float) -> bool:
        """``i -> j -> p`` certainly turns left."""
        xs, ys = self.xs, self.ys
        return turn_sign(xs[j] - xs[i], ys[j] - ys[i], px - xs[i], py - ys[i]) == 1

    def ears(self) -> tuple[list[tuple[int, int, int]], list[int]]:
        """The certain ears, cut in one pass with a stack, and the corners
        of the loop they leave."""
        xs, ys, left = self.xs, self.ys, self.left
        triangles: list[tuple[int, int, int]] = []
        stack: list[int] = []
        for index in [*range(len(xs)), 0]:  # the first corner again closes the loop
            stack.append(index)
            while len(stack) >= 3:
                a, b, d = stack[-3], stack[-2], stack[-1]
                if not (left(a, b, xs[d], ys[d]) and left(a, d, self.cx, self.cy)):
                    break
                triangles.append((a, b, d))
                del stack[-2]
        return triangles, stack[:-1]  # (its first corner was pushed twice)


# A part with more loops than this is cut into tiles before triangulation:
# ear clipping with holes is quadratic in the holes.
_TILE_LOOPS = 64


def triangulate_parts(parts: list[list[np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate polygons with holes into non-overlapping counter-clockwise
    triangles. Returns (n, 2) vertices and (m, 3) faces.

    A part with many holes is first cut along a grid into pieces of a few
    holes each (exact cuts by Clipper2, whose new vertices on the grid lines
    are rounded to its 1e-8 grid), so the cost stays near linear.
    """
    vertices, faces, base = [], [], 0
    spiked = [len(part) == 1 and many_reflex(np.asarray(part[0], np.float64)) for part in parts]
    for part, is_spiked in _straightened(parts, spiked):
        for loops in _tiles(part) if len(part) > _TILE_LOOPS else [part]:
            tris = _spiked_triangles(loops[0]) if is_spiked else None
            if tris is None:
                tris = np.asarray(triangulate(loops), dtype=np.int64).reshape(-1, 3)
            points = np.concatenate(loops)
            vertices.append(points)
            faces.append(tris + base)
            base += len(points)
    if not vertices:
        return np.zeros((0, 2)), np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(vertices), np.concatenate(faces)


def _straightened(
    parts: list[list[np.ndarray]], spiked: list[bool]
) -> list[tuple[list[np.ndarray], bool]]:
    """``parts`` (local units) without the corners that lie on a straight run
    between their neighbours to within the window's rounding
    (:data:`STRAIGHT_SLACK`), all loops in one pass: a caster's edge cut
    into many collinear pieces (a box made of many small triangles) casts
    one straight shadow edge, not one triangle per piece. The same regions,
    to rounding; a part whose outer loop was a sliver goes. A part of one
    many-reflex loop (``spiked``: :func:`_spiked_triangles`' certified
    sweep) is left as it is. Returns each part left with its ``spiked``."""
    chosen = [k for k, flag in enumerate(spiked) if not flag]
    if not chosen:
        return list(zip(parts, spiked, strict=True))
    loops = _OwnedLoops.of(parts, chosen)
    sizes = np.array([len(loop) for loop in loops.loops], dtype=np.int64)
    points, sizes, left = without_collinear(
        (np.concatenate(loops.loops), sizes, np.arange(len(loops.loops))), STRAIGHT_SLACK
    )
    pieces = np.split(points, np.cumsum(sizes)[:-1]) if len(sizes) else []
    rebuilt = loops.regrouped(left.tolist(), pieces)
    kept = [k for k in range(len(parts)) if spiked[k] or k in rebuilt]
    return [(parts[k], True) if spiked[k] else (rebuilt[k], False) for k in kept]


@dataclass(frozen=True)
class _OwnedLoops:
    """The loops of some parts in one list, with each loop's part and
    whether it is the part's outer loop (its first)."""

    loops: list[np.ndarray]
    owner: np.ndarray
    outer: np.ndarray

    @classmethod
    def of(cls, parts: list[list[np.ndarray]], chosen: list[int]) -> _OwnedLoops:
        """The loops of ``parts[k]`` for each ``k`` in ``chosen``, in order."""
        counts = [len(parts[k]) for k in chosen]
        loops = [np.asarray(loop, dtype=np.float64) for k in chosen for loop in parts[k]]
        owner = np.repeat(np.array(chosen, dtype=np.int64), counts)
        outer = np.zeros(len(loops), dtype=bool)
        outer[np.cumsum([0, *counts])[:-1]] = True
        return cls(loops, owner, outer)

    def regrouped(self, left: list[int], pieces: list[np.ndarray]) -> dict[int, list[np.ndarray]]:
        """Part -> its loops, from the ``pieces`` left of loops ``left``: a
        part whose outer loop went goes, holes and all."""
        rebuilt: dict[int, list[np.ndarray]] = {}
        for index, piece in zip(left, pieces, strict=True):
            part = int(self.owner[index])
            if self.outer[index] or part in rebuilt:  # holes only under their outer loop
                rebuilt.setdefault(part, []).append(piece)
        return rebuilt


def _spiked_triangles(loop: np.ndarray) -> np.ndarray | None:
    """Triangles of a polygon that is one loop of :data:`_SPIKED_CORNERS`
    corners or more, many reflex (:func:`many_reflex`, which the caller has
    found), by :func:`star_triangles` or else the sweep of
    :func:`shadowgeo.sweep.simple_triangles`; None for one neither
    certifies. manifold3d's ear clipping is quadratic in such corners (a
    star of 50,000 spikes: 7 s; a comb of 12,000 teeth: 17 s; a circle of
    50,000 corners: 0.04 s)."""
    loop = np.asarray(loop, dtype=np.float64)
    triangles = star_triangles(loop)
    if triangles is not None:
        return triangles
    kept = swept_triangles(loop)
    if kept is not None:  # cut by the sweep that certified it (whole_loop)
        return kept
    return simple_triangles(loop)[1]


def _tiles(part: list[np.ndarray]) -> list[list[np.ndarray]]:
    """``part`` cut by a square grid into pieces of about 16 loops each."""
    region = unite(part)
    points = part[0]
    low, high = points.min(axis=0), points.max(axis=0)
    count = math.ceil(math.sqrt(len(part) / 16))
    xs = np.linspace(low[0], high[0], count + 1)
    ys = np.linspace(low[1], high[1], count + 1)
    xs[0], ys[0], xs[-1], ys[-1] = xs[0] - 1, ys[0] - 1, xs[-1] + 1, ys[-1] + 1
    pieces = []
    for i in range(count):
        for j in range(count):
            box = np.array(
                [[xs[i], ys[j]], [xs[i + 1], ys[j]], [xs[i + 1], ys[j + 1]], [xs[i], ys[j + 1]]]
            )
            pieces.extend(components(intersect(region, unite([box]))))
    return pieces


def polygon_triangles(points: np.ndarray, holes: Sequence[np.ndarray] = ()) -> np.ndarray:
    """Triangulate one simple polygon (k, 3), convex or not, in its own plane.

    ``holes``: (h, 3) loops inside it, in its plane, either way round (a
    city model's walls with windows, a footprint's courtyard).

    Returns (m, 3) indices into ``points`` followed by each hole's corners,
    wound as the polygon is (its Newell normal). A polygon with no area
    gives no triangles. BudgetError past
    :data:`~shadowgeo.limits.MAX_POLYGON_CORNERS` corners, holes included.

    Examples
    --------
    >>> square = np.array([[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]], float)
    >>> hole = np.array([[1, 1, 0], [3, 1, 0], [3, 3, 0], [1, 3, 0]], float)
    >>> corners = np.concatenate([square, hole])[polygon_triangles(square, [hole])]
    >>> float(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
    ...                               corners[:, 2] - corners[:, 0]), axis=1).sum() / 2)
    12.0
    """
    corners = len(points) + sum(len(hole) for hole in holes)
    if corners > MAX_POLYGON_CORNERS:
        raise BudgetError(
            f"a polygon of {corners:,} corners is past the budget of {MAX_POLYGON_CORNERS:,} "
            "for triangulating one polygon (shadowgeo.limits.MAX_POLYGON_CORNERS)"
        )
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
    origin = points.mean(axis=0)
    flat = np.column_stack([(points - origin) @ u, (points - origin) @ v])
    if not len(holes):
        spiked = _spiked_triangles(flat) if many_reflex(flat) else None
        if spiked is not None:
            return spiked
        return np.asarray(triangulate([flat]), dtype=np.int64).reshape(-1, 3)
    loops, order, start = [flat], [np.arange(len(points))], len(points)
    for hole in holes:
        ring = np.column_stack([(hole - origin) @ u, (hole - origin) @ v])
        index = np.arange(start, start + len(hole))
        if signed_areas([ring])[0] > 0:  # a hole runs clockwise against its outer loop
            ring, index = ring[::-1], index[::-1]
        loops.append(ring)
        order.append(index)
        start += len(hole)
    triangles = np.asarray(triangulate(loops), dtype=np.int64).reshape(-1, 3)
    mapped: np.ndarray = np.concatenate(order)[triangles]
    return mapped


def fan(block: np.ndarray) -> np.ndarray:
    """(m, k) vertex indices of convex polygons -> (m * (k - 2), 3) triangles
    fanned from each polygon's first vertex, polygon by polygon."""
    size = block.shape[1]
    spokes = np.arange(1, size - 1)
    first = np.repeat(block[:, :1], size - 2, axis=1)
    return np.stack([first, block[:, spokes], block[:, spokes + 1]], -1).reshape(-1, 3)


def polygons_triangles(
    points: np.ndarray, block: np.ndarray, *, convex: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate polygons that all have k corners.

    Parameters
    ----------
    points : (n, 3) float64
    block : (m, k) int
        Each row a polygon's indices into ``points``, k >= 3.
    convex : bool
        True when the polygons are known to be convex: all are fanned.
        Otherwise those that are not convex are triangulated in their plane
        (:func:`polygon_triangles`), the rest fanned.

    Returns
    -------
    triangles : (t, 3) int64
        Indices into ``points``: first the non-convex polygons' triangles,
        polygon by polygon, then the fans.
    rows : (t,) int64
        The row of ``block`` each triangle comes from.
    """
    rows = np.arange(len(block))
    triangles, owners = [], []
    if block.shape[1] > 3 and not convex:
        fits = is_convex(points[block])
        for row, corners in zip(rows[~fits], block[~fits], strict=True):
            pieces = corners[polygon_triangles(points[corners])]
            triangles.append(pieces)
            owners.append(np.full(len(pieces), row))
        rows, block = rows[fits], block[fits]
    triangles.append(fan(block))
    owners.append(np.repeat(rows, block.shape[1] - 2))
    return np.concatenate(triangles).astype(np.int64), np.concatenate(owners).astype(np.int64)
