"""2-D regions: union by winding, intersection, decomposition, triangulation.

One thin wrapper over manifold3d's ``CrossSection`` (Clipper2 in C++). Clipper2
rounds coordinates to 1e-8, so callers work in a *local frame* whose units make
the region as large as Clipper2 handles safely (``MAX_COORDINATE``); rounding
then costs about 1e-16 of the region's size.
"""

from __future__ import annotations

import collections
import hashlib
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from manifold3d import CrossSection, FillRule, triangulate

from .arrangement import convex_union_arrays, convex_union_flat
from .errors import BudgetError
from .limits import CONVEX_TURN as _CONVEX_TURN
from .limits import MAX_UNION_CROSSINGS, MAX_UNION_SWEEP
from .orientation import MAX_COORDINATE, turn_sign, turns
from .plane import Plane
from .simplify import without_collinear
from .sweep import simple_triangles
from .topology import loop_rings

__all__ = [
    "ARRANGED_LOOPS",
    "FlatParts",
    "STRAIGHT_SLACK",
    "arranged_parts",
    "clipper_parts",
    "components",
    "crossings_estimate",
    "sweep_work",
    "fan",
    "fill",
    "holds_box",
    "intersect",
    "is_convex",
    "local_scale",
    "nest",
    "nest_flat",
    "parts_area",
    "points_in_parts",
    "polygon_triangles",
    "polygons_triangles",
    "region_loops",
    "signed_areas",
    "star_shaped_flat",
    "star_triangles",
    "subtract",
    "triangles_region",
    "triangulate_parts",
    "union_parts",
    "union_region",
    "unite",
    "whole_loop",
    "without_copies",
]

# A corner this close (local units) to the straight run between its
# neighbours is dropped before triangulating: a few hundred units in the last
# place of MAX_COORDINATE, far below any length a shadow resolves.
STRAIGHT_SLACK = 64 * MAX_COORDINATE * float(np.finfo(np.float64).eps)


def star_shaped_flat(points: np.ndarray, starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(l,) bool: whether each loop (``lengths[i]`` rows of ``points`` from
    ``starts[i]``, one loop after another, within +-MAX_COORDINATE) is
    certainly simple and counter-clockwise.

    Certified when the loop is star-shaped around the mean of its corners
    c: every edge turns left around c beyond rounding (``c -> p_i ->
    p_i+1``) and the edges go round c once in all, so they lie in wedges
    from c that do not overlap: no two edges meet but neighbours at their
    corner. Such a loop's inside is its region of positive winding as it is,
    with no 2-D union to find it (a convex loop is one; so is a star of
    50,000 spikes, whose union takes Clipper2 a quadratic sweep).
    """
    if not len(lengths):
        return np.zeros(0, dtype=bool)
    position = np.arange(len(points))
    ends = np.repeat(starts + lengths, lengths)
    after = np.where(position + 1 == ends, np.repeat(starts, lengths), position + 1)
    middle = np.repeat(_loop_means(points, starts, lengths), lengths, axis=0)
    sign, cross = turns(middle, points, points[after])
    spoke, next_spoke = points - middle, points[after] - middle
    dot = spoke[:, 0] * next_spoke[:, 0] + spoke[:, 1] * next_spoke[:, 1]
    sweep = np.add.reduceat(np.arctan2(cross, dot), starts)
    star: np.ndarray = (np.minimum.reduceat(sign, starts) == 1) & (np.abs(sweep - 2 * np.pi) < 1.0)
    return star & (lengths >= 3)


def _loop_means(points: np.ndarray, starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(l, 2) the mean of each loop's corners: the centre the star-shaped
    certificate is given for (:func:`star_shaped_flat`, :func:`star_triangles`)."""
    means: np.ndarray = np.add.reduceat(points, starts) / lengths[:, None]
    return means


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
    cx, cy = (float(value) for value in _loop_means(local, starts, lengths)[0])
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


def whole_loop(loops: list[np.ndarray], keep_triangles: bool = False) -> bool:
    """Whether ``loops`` are one loop whose inside is certainly their region
    of positive winding, so that no union is needed: a counter-clockwise loop
    star-shaped round the mean of its corners (:func:`star_shaped_flat`), or
    one of :data:`_SPIKED_CORNERS` corners or more, many reflex, that the
    sweep of :func:`shadowgeo.sweep.simple_triangles` certifies simple
    (Clipper2's own sweep is quadratic in such loops; smaller ones are left
    to it).

    ``keep_triangles``: the caller triangulates the loop next
    (:func:`triangulate_parts`); the sweep then cuts it into triangles as it
    certifies it and keeps them for that call, one sweep for both."""
    if len(loops) != 1 or len(loops[0]) < 3:
        return False
    loop = np.asarray(loops[0], dtype=np.float64)
    if star_shaped_flat(loop, np.zeros(1, dtype=np.int64), np.array([len(loop)]))[0]:
        return True
    if not _many_reflex(loop):
        return False
    simple, triangles = simple_triangles(loop, triangles=keep_triangles)
    if simple and triangles is not None:
        _SWEPT[_loop_key(loop)] = triangles
        while len(_SWEPT) > _SWEPT_KEPT:
            _SWEPT.popitem(last=False)  # the oldest
    return simple


# Triangles of the loops whole_loop certified last by the sweep (keep_triangles),
# by their content (:func:`_loop_key`), for _spiked_triangles to take.
_SWEPT: collections.OrderedDict[bytes, np.ndarray] = collections.OrderedDict()
_SWEPT_KEPT = 2


def _loop_key(loop: np.ndarray) -> bytes:
    """A digest of a (k, 2) float64 loop's corners, bit for bit."""
    data = np.ascontiguousarray(loop, dtype=np.float64)
    return (
        len(data).to_bytes(8, "little") + hashlib.blake2b(data.tobytes(), digest_size=16).digest()
    )


def holds_box(region: CrossSection, low: np.ndarray, high: np.ndarray) -> bool:
    """Whether ``region`` certainly holds the box ``low``-``high`` (2-D,
    within +-MAX_COORDINATE): it is one convex counter-clockwise loop and
    every corner of the box lies left of each of its edges beyond rounding.
    Then the region's intersection with anything in the box is that thing,
    and the intersection (a sweep over both) can be skipped."""
    loops = region_loops(region)
    if not whole_loop(loops):
        return False
    loop = loops[0]
    after = np.roll(loop, -1, axis=0)
    if not np.all(turns(loop, after, np.roll(after, -1, axis=0))[0] == 1):
        return False  # not convex beyond rounding
    corners = np.array([low, [high[0], low[1]], high, [low[0], high[1]]], dtype=np.float64)
    origin = np.repeat(loop, 4, axis=0)
    sign, _ = turns(origin, np.repeat(after, 4, axis=0), np.tile(corners, (len(loop), 1)))
    return bool(np.all(sign == 1))


def local_scale(extent: float) -> float:
    """Units per length that put the largest coordinate that will occur,
    ``extent``, at ``MAX_COORDINATE``: Clipper2's fixed 1e-8 grid is then
    about 1e-16 of the region's size."""
    return MAX_COORDINATE / extent


def signed_areas(loops: list[np.ndarray]) -> np.ndarray:
    """Shoelace signed area of each (k, 2) loop, positive counter-clockwise."""
    if not loops:
        return np.zeros(0)
    if len(loops) == 1:  # one loop (most shadows): no bookkeeping of where loops start
        x, y = loops[0][:, 0], loops[0][:, 1]
        if len(x) == 0:
            return np.zeros(1)
        x_next, y_next = np.concatenate((x[1:], x[:1])), np.concatenate((y[1:], y[:1]))
        cross = x * y_next - x_next * y
        return np.array([0.5 * np.add.reduce(cross)])
    points = np.concatenate(loops).reshape(-1, 2)
    lengths = np.array([len(loop) for loop in loops])
    starts, following = loop_rings(lengths)  # each loop closes on its own first point
    cross = points[:, 0] * points[following, 1] - points[following, 0] * points[:, 1]
    out = np.zeros(len(loops))
    nonempty = lengths > 0
    out[nonempty] = 0.5 * np.add.reduceat(cross, starts[nonempty]) if len(cross) else 0.0
    return out


# Edge pairs sampled to estimate the crossings of a union, and the fewest
# sampled crossings that may refuse one (fewer say too little to act on).
_CROSSING_SAMPLES = 1 << 16
_FEWEST_SAMPLED_CROSSINGS = 8
# For unions too large for pair sampling to resolve the budget (crossings
# among few of very many pairs, e.g. one union per receiving face side by
# side): whole crossing counts of a few sampled edges, about this many edge
# tests in all, refusing only when this many of those edges cross something.
_EDGE_TESTS = 20_000_000
_FEWEST_CROSSING_EDGES = 4
# Unions of at least this many loops drop exact copies first (without_copies).
_COPIES_CHECKED = 64


def _turn(origin: np.ndarray, one: np.ndarray, two: np.ndarray) -> np.ndarray:
    """The turn origin -> one -> two, > 0 to the left, points as complex
    numbers (one against many, or row by row)."""
    ahead, aside = one - origin, two - origin
    cross: np.ndarray = ahead.real * aside.imag - ahead.imag * aside.real
    return cross


def _apart(one: np.ndarray, two: np.ndarray) -> np.ndarray:
    """Whether turns ``one`` and ``two`` have opposite signs, neither zero
    (nor NaN): ``np.sign(one) * np.sign(two) < 0`` by comparisons only (a
    sign taken of numbers whose signs change at random costs a mispredicted
    branch each)."""
    apart: np.ndarray = ((one < 0) & (two > 0)) | ((one > 0) & (two < 0))
    return apart


def _proper_crossings(p: np.ndarray, q: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Whether segments p-q and c-d (complex ends) cross at a point inside
    both."""
    with np.errstate(over="ignore", invalid="ignore"):
        crossing: np.ndarray = _apart(_turn(p, q, c), _turn(p, q, d))
        crossing &= _apart(_turn(c, d, p), _turn(c, d, q))
    return crossing


# Up to this many loops, the crossing budget is first bounded exactly from
# the loops' boxes (_box_pairs_bound, a k x k test): a cell of a hundred
# shadows side by side is seldom near the budget, and sampling it cost 1.6 ms.
_BOX_BOUND_LOOPS = 512
# Sampled pairs tested at a time: a few hundred kB of temporaries, reused
# (a whole sample at once is fresh memory each union, dearer than the tests).
_SAMPLE_BLOCK = 1 << 13


def crossings_estimate(
    loops: list[np.ndarray], cells: np.ndarray | None = None
) -> tuple[float, int]:
    """(estimated edge crossings, sampled crossings) among the edges of the
    (k, 2) ``loops``. Exact (0, 0) when there are too few pairs to pass
    :data:`~shadowgeo.limits.MAX_UNION_CROSSINGS`.

    Two fixed pseudo-random samples: pairs of edges (the share that cross
    properly, times the number of pairs), and, when that sample is too thin
    to see the budget, a few edges tested against every edge (their mean
    crossings, times half the edges; the count returned is then the number
    of sampled edges that cross something).

    ``cells``, when given, (len(loops),) non-decreasing labels of loops
    laid out apart (no edge of one cell's loops meets another cell's, as
    many faces' pieces in cells of one plane): only pairs within a cell are
    counted, sampled and tested.

    Examples
    --------
    >>> square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    >>> crossings_estimate([square, square + 0.5])
    (0.0, 0)
    """
    lengths = np.array([len(loop) for loop in loops])
    n_edges = int(lengths.sum())
    if cells is None:
        pairs = n_edges * (n_edges - 1) / 2
    else:  # each cell's edges, and where they begin
        cell_of_loop = np.unique(np.asarray(cells), return_inverse=True)[1].reshape(-1)
        cell_edges = np.bincount(cell_of_loop, weights=lengths).astype(np.int64)
        cell_first = np.cumsum(cell_edges) - cell_edges
        cell_pairs = cell_edges * (cell_edges - 1) / 2
        pairs = float(cell_pairs.sum())
    if pairs <= MAX_UNION_CROSSINGS:
        return 0.0, 0
    start = np.concatenate(loops).astype(np.float64).reshape(-1, 2)
    if (
        cells is None
        and len(loops) <= _BOX_BOUND_LOOPS
        and _box_pairs_bound(start, lengths) <= MAX_UNION_CROSSINGS
    ):
        return 0.0, 0
    firsts, following = loop_rings(lengths)  # each loop closes
    end = start[following]
    rng = np.random.default_rng(0)  # fixed: the same loops always get the same answer
    if cells is None:
        first = rng.integers(n_edges, size=_CROSSING_SAMPLES)
        second = rng.integers(n_edges, size=_CROSSING_SAMPLES)
    else:  # a cell by its share of the pairs, then two distinct edges of it
        paired = np.flatnonzero(cell_pairs > 0)  # cells of two edges or more
        share = np.cumsum(cell_pairs[paired])
        chosen = np.searchsorted(share, rng.random(_CROSSING_SAMPLES) * share[-1], side="right")
        cell = paired[np.minimum(chosen, len(paired) - 1)]
        size = cell_edges[cell]
        one = rng.integers(size)
        other = (one + 1 + rng.integers(size - 1)) % size
        first, second = cell_first[cell] + one, cell_first[cell] + other
    # points as complex numbers: numpy gathers one far faster than a row
    start_z, end_z = start.view(np.complex128).ravel(), end.view(np.complex128).ravel()
    sampled = 0
    for block in range(0, _CROSSING_SAMPLES, _SAMPLE_BLOCK):
        one, other = first[block : block + _SAMPLE_BLOCK], second[block : block + _SAMPLE_BLOCK]
        crossing = _proper_crossings(start_z[one], end_z[one], start_z[other], end_z[other])
        sampled += int(np.count_nonzero(crossing))
    estimate = sampled / _CROSSING_SAMPLES * pairs
    resolvable = _FEWEST_SAMPLED_CROSSINGS / _CROSSING_SAMPLES * pairs
    if sampled >= _FEWEST_SAMPLED_CROSSINGS or resolvable <= MAX_UNION_CROSSINGS:
        return estimate, sampled
    low, high = np.minimum(start, end), np.maximum(start, end)
    edge_cell = None if cells is None else np.repeat(cell_of_loop, lengths)
    counts = []
    for edge in rng.integers(n_edges, size=max(16, _EDGE_TESTS // n_edges)).tolist():
        begin, stop = 0, n_edges
        if edge_cell is not None:  # (the edges of its own cell only)
            begin = int(cell_first[edge_cell[edge]])
            stop = begin + int(cell_edges[edge_cell[edge]])
        lo, hi = low[begin:stop], high[begin:stop]
        near = begin + np.flatnonzero(
            (lo[:, 0] <= high[edge, 0])
            & (hi[:, 0] >= low[edge, 0])
            & (lo[:, 1] <= high[edge, 1])
            & (hi[:, 1] >= low[edge, 1])
        )  # only edges whose boxes meet this one's can cross it
        hits = _proper_crossings(start_z[edge], end_z[edge], start_z[near], end_z[near])
        counts.append(int(np.count_nonzero(hits)))
    crossing_edges = int(np.count_nonzero(counts))
    return float(np.mean(counts)) * n_edges / 2, crossing_edges


def sweep_work(loops: list[np.ndarray]) -> int:
    """The steps Clipper2's sweep takes to place the edges of the (k, 2)
    ``loops`` in its list of active edges: for each distinct y of a corner
    (a scanline), the edges that begin there times the edges that span it
    (ends included), summed. Exact 0 when there are too few edges to pass
    :data:`~shadowgeo.limits.MAX_UNION_SWEEP`.

    Each edge that begins at a scanline is placed by a walk along the edges
    active there, so when many corners share a y (a soup of copies of one
    template, seen square-on) the work grows with their product, not with
    the crossings: 146,000 edges on 200 scanlines took 5.5 s with no
    crossing at all; the same loops turned by 0.3 rad, 0.15 s. (A fan of
    32,768 thin triangles round one point, no crossing either: 33 s.)

    Examples
    --------
    >>> square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    >>> sweep_work([square, square + 0.5])
    0
    """
    lengths = np.fromiter(map(len, loops), dtype=np.int64, count=len(loops))
    n_edges = int(lengths.sum())
    if n_edges * n_edges <= MAX_UNION_SWEEP:  # (the product never exceeds it)
        return 0
    y = np.concatenate(loops)[:, 1].astype(np.float64)
    y_next = y[loop_rings(lengths)[1]]  # each loop closes
    low = np.sort(np.minimum(y, y_next))
    high = np.sort(np.maximum(y, y_next))
    scanlines = np.unique(y)
    begun = np.searchsorted(low, scanlines, side="right")
    beginning = begun - np.searchsorted(low, scanlines, side="left")
    spanning = begun - np.searchsorted(high, scanlines, side="left")
    return int(np.dot(beginning, spanning))


def _box_pairs_bound(points: np.ndarray, lengths: np.ndarray) -> float:
    """How many edge pairs of the loops (``points`` one loop after another,
    ``lengths[i]`` each; empty loops ignored) could
    cross: pairs within a loop, and pairs of loops whose bounding boxes
    meet (an edge lies in its loop's box, so loops with boxes apart share
    no crossing). An exact upper bound on the crossings, found from the
    loops' boxes alone."""
    kept = lengths > 0
    sizes = lengths[kept].astype(np.float64)
    starts = (np.cumsum(lengths) - lengths)[kept]
    low = np.minimum.reduceat(points, starts, axis=0)
    high = np.maximum.reduceat(points, starts, axis=0)
    meet = np.ones((len(sizes), len(sizes)), dtype=bool)
    for axis in (0, 1):  # closed boxes: touching boxes meet
        meet &= low[:, None, axis] <= high[None, :, axis]
        meet &= high[:, None, axis] >= low[None, :, axis]
    across = float(sizes @ (meet @ sizes)) - float(sizes @ sizes)  # ordered pairs, i != j
    return across / 2 + float(np.sum(sizes * (sizes - 1) / 2))


def without_copies(loops: list[np.ndarray]) -> list[np.ndarray]:
    """``loops`` less each loop that repeats an earlier one point for point
    (from any starting point), when no loop winds clockwise: a copy then only
    raises a winding that is already positive, so the positive and the
    nonzero region stay as they are, and Clipper2's sweep slows down on every
    coincident edge (twenty thousand clipped copies of four triangles took it
    seconds). With a clockwise loop (a hole) copies count, and all are kept.

    Examples
    --------
    >>> square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    >>> len(without_copies([square, np.roll(square, 1, axis=0), square + 2]))
    2
    >>> len(without_copies([square, np.roll(square, 1, axis=0), square[::-1]]))
    3
    """
    kept = _without_copies_kept(loops)
    return loops if kept is None else [loops[i] for i in kept]


def _without_copies_kept(loops: list[np.ndarray]) -> list[int] | None:
    """:func:`without_copies` as the indices of the loops it keeps (empty
    loops dropped too), or None when it keeps every loop."""
    lengths = np.array([len(loop) for loop in loops], dtype=np.int64)
    index = np.flatnonzero(lengths)  # the loops with points
    some_empty = len(index) < len(loops)
    if some_empty:
        loops = [loops[i] for i in index.tolist()]
        lengths = lengths[index]
    every = index.tolist() if some_empty else None  # (when no copy goes)
    points = np.concatenate(loops).astype(np.float64).reshape(-1, 2)
    starts, following = loop_rings(lengths)  # each loop closes
    with np.errstate(over="ignore", invalid="ignore"):
        cross = points[:, 0] * points[following, 1] - points[:, 1] * points[following, 0]
        doubled = np.add.reduceat(cross, starts)
    if not np.all(doubled >= 0):  # a clockwise loop (or an overflow): copies count
        return every
    # extremes do not depend on where a loop starts: equal for copies
    keys = np.column_stack(
        [
            lengths.astype(np.float64),
            np.minimum.reduceat(points[:, 0], starts),
            np.maximum.reduceat(points[:, 0], starts),
            np.minimum.reduceat(points[:, 1], starts),
            np.maximum.reduceat(points[:, 1], starts),
        ]
    )
    order = np.lexsort(keys.T[::-1])
    same = np.all(keys[order][1:] == keys[order][:-1], axis=1)
    if not same.any():
        return every
    suspects = np.zeros(len(loops), dtype=bool)
    suspects[order[1:][same]] = True
    suspects[order[:-1][same]] = True
    # Each suspect from its least point (by x, then y; the first of equal
    # ones), bit for bit: a copy is a later suspect of the same length with
    # the same points from there. Suspects of one length at a time.
    dropped = np.zeros(len(loops), dtype=bool)
    chosen = np.flatnonzero(suspects)
    for length in np.unique(lengths[chosen]).tolist():
        members = chosen[lengths[chosen] == length]
        rows = points[starts[members][:, None] + np.arange(length)]  # (m, length, 2)
        x, y = rows[:, :, 0], rows[:, :, 1]
        least = np.where(x == x.min(axis=1, keepdims=True), y, np.inf)
        first = np.argmin(least, axis=1)  # (the first of the least)
        turned = np.take_along_axis(
            rows, ((np.arange(length) + first[:, None]) % length)[:, :, None], axis=1
        )
        flat = np.ascontiguousarray(turned).reshape(len(members), 2 * length)
        keys = flat.view(np.dtype((np.void, 16 * length))).ravel()
        _, earliest = np.unique(keys, return_index=True)
        copy = np.ones(len(members), dtype=bool)
        copy[earliest] = False
        dropped[members[copy]] = True
    if not dropped.any():
        return every
    kept: list[int] = index[~dropped].tolist()
    return kept


def triangles_region(triangles: np.ndarray) -> CrossSection:
    """The region a (m, 3, 2) stack of triangles covers (a receiving patch
    seen in its plane): each turned counter-clockwise, those of no area
    dropped, filled as one region."""
    areas = signed_areas(list(triangles))
    keep = areas != 0
    oriented = [t if a > 0 else t[::-1] for t, a in zip(triangles[keep], areas[keep], strict=True)]
    return fill(oriented)


def fill(
    loops: list[np.ndarray], rule: str = "positive", cells: np.ndarray | None = None
) -> CrossSection:
    """The region of points whose winding number over ``loops`` passes ``rule``
    (``"positive"``: > 0, ``"nonzero"``, ``"evenodd"``). ``cells``: labels of
    loops laid out apart, as :func:`crossings_estimate` takes them.

    Raises
    ------
    GeometryError
        When the loops' edges cross each other more than
        :data:`~shadowgeo.limits.MAX_UNION_CROSSINGS` times (estimated by
        :func:`crossings_estimate`): Clipper2's work grows with the crossings,
        more than linearly, so such a union would take minutes. Or when
        placing the edges in Clipper2's sweep takes more than
        :data:`~shadowgeo.limits.MAX_UNION_SWEEP` steps (counted by
        :func:`sweep_work`: many edges beginning on scanlines many edges span).
    """
    if not loops:
        return CrossSection()
    if rule != "evenodd" and len(loops) >= _COPIES_CHECKED:
        kept = _without_copies_kept(loops)
        if kept is not None:
            loops = [loops[i] for i in kept]
            cells = None if cells is None else np.asarray(cells)[kept]
    estimate, sampled = crossings_estimate(loops, cells)
    if estimate > MAX_UNION_CROSSINGS and sampled >= _FEWEST_CROSSING_EDGES:
        n_edges = sum(len(loop) for loop in loops)
        raise BudgetError(
            f"the shadow's outline ({len(loops)} loops, {n_edges} edges) has about "
            f"{estimate:.2g} edge crossings, past the budget of {MAX_UNION_CROSSINGS:,} "
            "(shadowgeo.limits.MAX_UNION_CROSSINGS)"
        )
    _check_sweep(loops)  # (after the crossings: a tangle is named by those)
    fill_rule = {
        "positive": FillRule.Positive,
        "nonzero": FillRule.NonZero,
        "evenodd": FillRule.EvenOdd,
    }[rule]
    return CrossSection([np.ascontiguousarray(loop, dtype=np.float64) for loop in loops], fill_rule)


def _check_sweep(loops: list[np.ndarray]) -> None:
    """Raise BudgetError when uniting ``loops`` would take Clipper2's sweep
    more than MAX_UNION_SWEEP steps."""
    work = sweep_work(loops)
    if work > MAX_UNION_SWEEP:
        n_edges = sum(len(loop) for loop in loops)
        raise BudgetError(
            f"the shadow's outline ({len(loops)} loops, {n_edges} edges) needs {work:.2g} "
            f"steps of the union's sweep (many corners on few lines), past the budget of "
            f"{MAX_UNION_SWEEP:,} (shadowgeo.limits.MAX_UNION_SWEEP)"
        )


def union_parts(
    loops: list[np.ndarray], groups: Callable[[], np.ndarray]
) -> list[list[np.ndarray]]:
    """The parts (``[outer, hole, ...]``, as :func:`components` gives them)
    of the region of positive winding over ``loops``, for loops in
    ``groups`` whose own winding is never negative.

    Parameters
    ----------
    loops : list of (k, 2) float64
    groups : callable returning (n,) int
        A label per loop, asked for only when there are many loops. The
        loops of one label together wind >= 0 at every point (all the
        outline loops of one connected part of a mesh, or one
        counter-clockwise triangle). Then the positive region of the whole
        is the union of the groups' positive regions.

    Notes
    -----
    Many strictly convex counter-clockwise loops (a city of box buildings)
    are first tried by their arrangement (:func:`arranged_parts`), which
    needs no Clipper2 call; where it cannot certify a sign (touching
    outlines) :func:`clipper_parts` does the work.
    """
    if len(loops) >= ARRANGED_LOOPS:
        sizes = np.fromiter(map(len, loops), dtype=np.int64, count=len(loops))
        flat = arranged_parts(np.concatenate(loops), sizes)
        if flat is not None:
            return flat.parts()
    return clipper_parts(loops, groups)


def arranged_parts(points: np.ndarray, sizes: np.ndarray) -> FlatParts | None:
    """:func:`union_parts` by the loops' arrangement alone, for loops given
    flat (``points`` one loop after another, ``sizes[i]`` points each), with
    the result flat too; None where it does not apply (too few loops for the
    arrangement to pay, a loop not strictly convex, a sign it cannot
    certify): then :func:`clipper_parts` unites the loops."""
    if len(sizes) < ARRANGED_LOOPS:
        return None
    boundary = convex_union_arrays(points, sizes)
    return None if boundary is None else FlatParts.nested(*boundary)


def clipper_parts(
    loops: list[np.ndarray], groups: Callable[[], np.ndarray]
) -> list[list[np.ndarray]]:
    """:func:`union_parts` by Clipper2.

    Clipper2's sweep keeps a list of the edges its scanline crosses, so one
    union of thousands of overlapping outlines scattered over a plane costs
    about n^1.5. Many loops are therefore first united cell by cell of a
    grid of about ``_CELL_LOOPS`` loops each (every group in the cell of its
    first loop's box centre). A cell's part whose box meets no other cell's
    parts is final as it is; the rest, near the cells' borders, are united
    once more.
    """
    if len(loops) <= _GROUPED_LOOPS:
        return components(fill(loops))
    return _cell_parts(loops, groups)


def _cell_parts(
    loops: list[np.ndarray], groups: Callable[[], np.ndarray]
) -> list[list[np.ndarray]]:
    """:func:`union_parts` cell by cell (see its Notes)."""
    low, high = _boxes(loops)
    labels = np.asarray(groups(), dtype=np.int64)
    labels = labels - labels.min()
    first = np.full(int(labels.max()) + 1, len(loops), dtype=np.int64)
    np.minimum.at(first, labels, np.arange(len(loops)))
    centres = 0.5 * (low + high)
    anchor = centres[first[labels]]  # each loop placed by its group's first loop
    count = math.ceil(math.sqrt(len(loops) / _CELL_LOOPS))
    bottom, top = anchor.min(axis=0), anchor.max(axis=0)
    span = np.where(top > bottom, top - bottom, 1.0)
    cell_xy = np.minimum(((anchor - bottom) / span * count).astype(np.int64), count - 1)
    cell = cell_xy[:, 0] * count + cell_xy[:, 1]
    order = np.argsort(cell, kind="stable")
    bounds = np.searchsorted(cell[order], np.arange(count * count + 1))
    parts: list[list[np.ndarray]] = []
    owner: list[int] = []
    for index in range(count * count):
        members = order[bounds[index] : bounds[index + 1]].tolist()
        if members:
            united = components(fill([loops[i] for i in members]))
            parts.extend(united)
            owner.extend([index] * len(united))
    final = _final_parts(parts, np.array(owner, dtype=np.int64))
    rest = [loop for part, done in zip(parts, final, strict=True) if not done for loop in part]
    return [part for part, done in zip(parts, final, strict=True) if done] + components(fill(rest))


def union_region(loops: list[np.ndarray], groups: Callable[[], np.ndarray]) -> CrossSection:
    """:func:`union_parts` as a region, to intersect with others: the
    arrangement's loops filled, or one union for few loops, or the cells'
    parts filled once more for many."""
    if len(loops) >= ARRANGED_LOOPS:
        boundary = convex_union_flat(loops)
        if boundary is not None:
            points, starts = boundary
            bounds = [*starts.tolist(), len(points)]
            return fill([points[a:b] for a, b in itertools.pairwise(bounds)])
    if len(loops) <= _GROUPED_LOOPS:
        return fill(loops)
    return fill([loop for part in _cell_parts(loops, groups) for loop in part])


def _final_parts(parts: list[list[np.ndarray]], owner: np.ndarray) -> list[bool]:
    """Whether each cell's part is final: its outer loop's box meets no
    other cell's box of parts, so no other cell's part can touch it."""
    low, high = _boxes([part[0] for part in parts])
    n_cells = int(owner.max()) + 1
    cell_low = np.full((n_cells, 2), np.inf)
    cell_high = np.full((n_cells, 2), -np.inf)
    np.minimum.at(cell_low, owner, low)
    np.maximum.at(cell_high, owner, high)
    meets = (low[:, None, 0] <= cell_high[None, :, 0]) & (low[:, None, 1] <= cell_high[None, :, 1])
    meets &= (high[:, None, 0] >= cell_low[None, :, 0]) & (high[:, None, 1] >= cell_low[None, :, 1])
    meets[np.arange(len(parts)), owner] = False
    touched = np.asarray(np.any(meets, axis=1), dtype=bool)
    return [not flag for flag in touched.tolist()]


def _boxes(loops: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2) lower and upper corners of each loop's bounding box."""
    points = np.concatenate(loops)
    lengths = np.fromiter(map(len, loops), dtype=np.int64, count=len(loops))
    starts = np.cumsum(lengths) - lengths  # integers even for one loop
    return np.minimum.reduceat(points, starts, axis=0), np.maximum.reduceat(points, starts, axis=0)


def region_loops(region: CrossSection) -> list[np.ndarray]:
    """The loops of ``region`` (outer loops counter-clockwise, holes
    clockwise) as (k, 2) float64 arrays, dropping any of fewer than three
    points."""
    loops = [np.asarray(loop, dtype=np.float64) for loop in region.to_polygons()]
    return [loop for loop in loops if len(loop) >= 3]


# A polygon of one loop of this many corners or more, this many of them
# reflex, is triangulated by star_triangles or the sweep of shadowgeo.sweep,
# not by manifold3d's ear clipping (_spiked_triangles), and whole_loop sweeps
# it. Below, manifold3d and Clipper2 are as fast or faster
# (benchmarks/bench_polygons.py: equal near 4,000 corners of a comb).
_SPIKED_CORNERS = 4096
_SPIKED_REFLEX = 64
# Candidate edges one batch of nest's point-in-loop tests visits at most.
_NEST_EDGES = 4_000_000
# union_parts: loops above this are united cell by cell first, about
# _CELL_LOOPS to a cell (below it one union is faster).
_GROUPED_LOOPS = 2000
_CELL_LOOPS = 100
# union_parts and arranged_parts try convex loops by their arrangement from this many on
# (below it the numpy steps' fixed costs outweigh Clipper2's).
ARRANGED_LOOPS = 64


def intersect(region: CrossSection, other: CrossSection) -> CrossSection:
    return region ^ other


def subtract(region: CrossSection, other: CrossSection) -> CrossSection:
    """The points of ``region`` not in ``other``."""
    return region - other


def unite(region: CrossSection, other: CrossSection) -> CrossSection:
    """The points of ``region`` or ``other``."""
    return region + other


def components(region: CrossSection) -> list[list[np.ndarray]]:
    """Connected parts of ``region``, each ``[outer, hole, ...]``: outer loop
    counter-clockwise, holes clockwise, as (k, 2) float64 arrays.

    Every part has a positive area. Clipper2 rounds to its fixed grid, and a
    sliver thinner than the grid can come back inside out (a negative area):
    such a part has no area worth the name and is dropped.

    The loops come from one flat ``to_polygons`` and each hole goes to the
    smallest outer loop around it (:func:`nest`): Clipper2's own
    ``decompose`` is quadratic in the holes of a part, and a city's shadow
    is one part with thousands of courtyards.
    """
    return nest(region_loops(region))


def nest(loops: list[np.ndarray]) -> list[list[np.ndarray]]:
    """Group the loops of a region without crossings (outer loops
    counter-clockwise, holes clockwise) into ``[outer, hole, ...]`` parts.

    Each hole belongs to the smallest outer loop that contains it. Candidates
    are outer loops whose bounding box holds the hole's; only a hole with more
    than one candidate is tested, at the midpoint of its first edge (in a
    region without crossings or overlapping edges that point lies on no other
    loop), against all candidates but the largest. Parts are ordered by
    their outer loop, holes from the smallest.
    """
    if not loops:
        return []
    if len(loops) == 1:  # the common case of one outline: no holes to place
        return [loops] if signed_areas(loops)[0] > 0 else []
    lengths = np.array([len(loop) for loop in loops], dtype=np.int64)
    return nest_flat(np.concatenate(loops).reshape(-1, 2), np.cumsum(lengths) - lengths, loops)


def nest_flat(
    points: np.ndarray, starts: np.ndarray, loops: list[np.ndarray] | None = None
) -> list[list[np.ndarray]]:
    """:func:`nest` of loops given as one (n, 2) array of their points, loop
    ``i`` from ``starts[i]`` to the next start; ``loops``: the same loops as
    arrays, when they are at hand already (else cut from ``points``)."""
    return FlatParts.nested(points, starts).parts(loops)


@dataclass(frozen=True)
class FlatParts:
    """Loops of one (n, 2) array grouped into parts, as :func:`nest` groups
    them, without an array per loop until one is asked for.

    ``points``: the loops one after another, loop ``i`` from ``starts[i]``
    (``lengths[i]`` points); ``areas``: each loop's signed area;
    ``groups``: per part, the loop indices ``[outer, hole, ...]``.
    """

    points: np.ndarray
    starts: np.ndarray
    lengths: np.ndarray
    areas: np.ndarray
    groups: list[list[int]]

    @classmethod
    def nested(cls, points: np.ndarray, starts: np.ndarray) -> FlatParts:
        """The loops at ``starts`` of ``points``, holes placed in the
        smallest outer loop around them (see :func:`nest`)."""
        lengths = np.diff(np.append(starts, len(points)))
        if len(starts) == 0:
            return cls(points, starts, lengths, np.zeros(0), [])
        _, following = loop_rings(lengths)
        cross = points[:, 0] * points[following, 1] - points[following, 0] * points[:, 1]
        areas = 0.5 * np.add.reduceat(cross, starts)
        outers = np.flatnonzero(areas > 0)
        holes = np.flatnonzero(areas < 0)
        if len(holes) == 0 or len(outers) == 0:  # holes in nothing bound no region
            return cls(points, starts, lengths, areas, [[i] for i in outers.tolist()])
        parent = _hole_parents(points, starts, lengths, following, areas, outers, holes)
        # holes grouped by parent, largest first within each group
        regroup = np.lexsort((-areas[holes], parent))
        grouped, group_parent = holes[regroup], parent[regroup]
        first = np.searchsorted(group_parent, outers, side="left")
        last = np.searchsorted(group_parent, outers, side="right")
        groups = [[i] for i in outers.tolist()]
        emptied = []
        for index in np.flatnonzero(last > first).tolist():
            own = grouped[first[index] : last[index]]
            if areas[outers[index]] + areas[own].sum() <= 0:
                emptied.append(index)
            groups[index].extend(own.tolist())
        if emptied:
            gone = set(emptied)
            groups = [group for index, group in enumerate(groups) if index not in gone]
        return cls(points, starts, lengths, areas, groups)

    def parts(self, loops: list[np.ndarray] | None = None) -> list[list[np.ndarray]]:
        """The parts as lists of (k, 2) arrays: views of ``points``, or the
        same loops of ``loops`` (say, the points moved into another frame)."""
        if loops is None:
            loops = self.cut(self.points)
        return [[loops[i] for i in group] for group in self.groups]

    def cut(self, points: np.ndarray) -> list[np.ndarray]:
        """``points`` (an array like :attr:`points`, row for row) cut into
        the loops."""
        bounds = self.starts.tolist()
        return [points[a : a + k] for a, k in zip(bounds, self.lengths.tolist(), strict=True)]

    @property
    def area(self) -> float:
        """The parts' area: outer loops minus holes."""
        kept = [i for group in self.groups for i in group]
        return float(self.areas[kept].sum()) if kept else 0.0

    def reach(self) -> float:
        """The largest absolute coordinate of the parts' outer loops."""
        if not self.groups:
            return 0.0
        largest = np.maximum.reduceat(np.abs(self.points).max(axis=1), self.starts)
        return float(largest[[group[0] for group in self.groups]].max())


def _hole_parents(
    points: np.ndarray,
    starts: np.ndarray,
    lengths: np.ndarray,
    following: np.ndarray,
    areas: np.ndarray,
    outers: np.ndarray,
    holes: np.ndarray,
) -> np.ndarray:
    """(h,) the loop index of the outer loop each of ``holes`` belongs to:
    the smallest whose box holds the hole's and, where several do, that
    holds the hole's first edge's midpoint."""
    low = np.minimum.reduceat(points, starts, axis=0)
    high = np.maximum.reduceat(points, starts, axis=0)
    parent = np.full(len(holes), -1, dtype=np.int64)
    by_size = outers[np.argsort(areas[outers], kind="stable")]  # smallest first
    chunk = max(1, 4_000_000 // max(len(outers), 1))
    for start in range(0, len(holes), chunk):
        rows = holes[start : start + chunk]
        outer_low, outer_high = low[by_size], high[by_size]
        around = (outer_low[None, :, 0] <= low[rows, None, 0]) & (
            outer_low[None, :, 1] <= low[rows, None, 1]
        )
        around &= (outer_high[None, :, 0] >= high[rows, None, 0]) & (
            outer_high[None, :, 1] >= high[rows, None, 1]
        )
        count = around.sum(axis=1)
        single = count == 1
        if single.any():
            parent[start : start + chunk][single] = by_size[np.argmax(around[single], axis=1)]
        many = np.flatnonzero(count > 1)
        if len(many):
            parent[start + many] = _smallest_around(
                points, starts, lengths, following, rows[many], by_size, around[many]
            )
    return parent


def _smallest_around(
    points: np.ndarray,
    starts: np.ndarray,
    lengths: np.ndarray,
    following: np.ndarray,
    holes: np.ndarray,
    by_size: np.ndarray,
    around: np.ndarray,
) -> np.ndarray:
    """For each of ``holes`` (loop indices), the smallest of its candidate
    outer loops (``by_size[around[row]]``, smallest first) that holds the
    midpoint of its first edge; the largest candidate without a test when
    none of the others does (every hole lies in some outer loop, and the
    largest is often a whole city's outline, the costliest to test).

    All (hole, candidate) crossing-number tests at once, over the edges
    of the candidates that straddle the point's height."""
    row, column = np.nonzero(around)  # by row, then smallest candidate first
    last = np.append(row[1:] != row[:-1], True)
    parent: np.ndarray = by_size[column[last]]
    row, candidate = row[~last], by_size[column[~last]]
    if not len(row):
        return parent
    corner = starts[holes]
    point = 0.5 * (points[corner] + points[corner + 1])[row]
    counts = lengths[candidate]
    ends = np.cumsum(counts)
    inside = np.zeros(len(row), dtype=bool)
    # pairs in batches of about _NEST_EDGES candidate edges
    cuts = np.searchsorted(ends, np.arange(_NEST_EDGES, int(ends[-1]), _NEST_EDGES))
    for begin, stop in itertools.pairwise([0, *np.unique(cuts).tolist(), len(row)]):
        if stop > begin:
            inside[begin:stop] = _holds(
                points,
                following,
                starts[candidate[begin:stop]],
                counts[begin:stop],
                point[begin:stop],
            )
    found = np.flatnonzero(inside)
    rows_found, first = np.unique(row[found], return_index=True)
    parent[rows_found] = candidate[found[first]]
    return parent


def _holds(
    points: np.ndarray,
    following: np.ndarray,
    starts: np.ndarray,
    counts: np.ndarray,
    point: np.ndarray,
) -> np.ndarray:
    """(p,) bool: whether loop p (``counts[p]`` points from ``starts[p]``)
    holds ``point[p]`` strictly inside, by crossing numbers."""
    edge = np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(int(counts.sum()))
    pair = np.repeat(np.arange(len(counts)), counts)
    start, end = points[edge], points[following[edge]]
    height = point[pair, 1]
    straddle = np.flatnonzero((start[:, 1] > height) != (end[:, 1] > height))
    start, end, pair = start[straddle], end[straddle], pair[straddle]
    crossing = start[:, 0] + (point[pair, 1] - start[:, 1]) * (end[:, 0] - start[:, 0]) / (
        end[:, 1] - start[:, 1]
    )
    hits = np.bincount(pair[crossing > point[pair, 0]], minlength=len(counts))
    holds: np.ndarray = hits % 2 == 1
    return holds


def parts_area(parts: list[list[np.ndarray]]) -> float:
    """Area of :func:`components`' parts (outer loops minus holes), >= 0."""
    return float(signed_areas([loop for loops in parts for loop in loops]).sum())


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
    spiked = [len(part) == 1 and _many_reflex(np.asarray(part[0], np.float64)) for part in parts]
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


def _many_reflex(loop: np.ndarray) -> bool:
    """Whether the (k, 2) loop has :data:`_SPIKED_CORNERS` corners or more
    and :data:`_SPIKED_REFLEX` certain reflex ones (turned clockwise, for a
    loop run counter-clockwise)."""
    if len(loop) < _SPIKED_CORNERS:
        return False
    scale = float(np.abs(loop - loop.mean(axis=0)).max())
    if not (np.isfinite(scale) and scale > 0):
        return False
    local = (loop - loop.mean(axis=0)) * (MAX_COORDINATE / scale)  # only to count them
    after = np.roll(local, -1, axis=0)
    sign, _ = turns(local, after, np.roll(after, -1, axis=0))
    return int(np.count_nonzero(sign == -1)) >= _SPIKED_REFLEX


def _spiked_triangles(loop: np.ndarray) -> np.ndarray | None:
    """Triangles of a polygon that is one loop of :data:`_SPIKED_CORNERS`
    corners or more, many reflex (:func:`_many_reflex`, which the caller has
    found), by :func:`star_triangles` or else the sweep of
    :func:`shadowgeo.sweep.simple_triangles`; None for one neither
    certifies. manifold3d's ear clipping is quadratic in such corners (a
    star of 50,000 spikes: 7 s; a comb of 12,000 teeth: 17 s; a circle of
    50,000 corners: 0.04 s)."""
    loop = np.asarray(loop, dtype=np.float64)
    triangles = star_triangles(loop)
    if triangles is not None:
        return triangles
    kept = _SWEPT.pop(_loop_key(loop), None) if _SWEPT else None
    if kept is not None:  # cut by the sweep that certified it (whole_loop)
        return kept
    return simple_triangles(loop)[1]


def _tiles(part: list[np.ndarray]) -> list[list[np.ndarray]]:
    """``part`` cut by a square grid into pieces of about 16 loops each."""
    region = fill(part)
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
            pieces.extend(components(intersect(region, CrossSection([box]))))
    return pieces


def polygon_triangles(points: np.ndarray, holes: Sequence[np.ndarray] = ()) -> np.ndarray:
    """Triangulate one simple polygon (k, 3), convex or not, in its own plane.

    ``holes``: (h, 3) loops inside it, in its plane, either way round (a
    city model's walls with windows, a footprint's courtyard).

    Returns (m, 3) indices into ``points`` followed by each hole's corners,
    wound as the polygon is (its Newell normal). A polygon with no area
    gives no triangles.

    Examples
    --------
    >>> square = np.array([[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]], float)
    >>> hole = np.array([[1, 1, 0], [3, 1, 0], [3, 3, 0], [1, 3, 0]], float)
    >>> corners = np.concatenate([square, hole])[polygon_triangles(square, [hole])]
    >>> float(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
    ...                               corners[:, 2] - corners[:, 0]), axis=1).sum() / 2)
    12.0
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
    origin = points.mean(axis=0)
    flat = np.column_stack([(points - origin) @ u, (points - origin) @ v])
    if not len(holes):
        spiked = _spiked_triangles(flat) if _many_reflex(flat) else None
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


def is_convex(corners: np.ndarray) -> np.ndarray:
    """(m, k, 3) polygons -> (m,) bool: True where convex, every turn to the
    same side of the polygon's Newell normal and the turns adding up to one
    full turn (so a star that winds twice is not convex)."""
    following = np.roll(corners, -1, axis=1)
    normal = np.cross(corners, following).sum(axis=1)  # Newell's normal, times 2
    edges = following - corners
    turns = np.cross(edges, np.roll(edges, -1, axis=1))
    sine = np.einsum("mkd,md->mk", turns, normal)
    cosine = np.einsum("mkd,mkd->mk", edges, np.roll(edges, -1, axis=1))
    scale = np.linalg.norm(normal, axis=1)[:, None]
    angles = np.arctan2(sine, cosine * scale)
    convex: np.ndarray = np.all(angles >= -_CONVEX_TURN, axis=1) & np.isclose(
        angles.sum(axis=1), 2 * np.pi
    )
    return convex


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


def points_in_parts(points: np.ndarray, parts: list[list[np.ndarray]]) -> np.ndarray:
    """(p,) bool: which of ``points`` (p, 2) lie in the polygons ``parts``
    (``[outer, hole, ...]`` lists), by the even-odd rule over every loop,
    all points at once per edge."""
    inside = np.zeros(len(points), dtype=bool)
    for part in parts:
        for loop in part:
            start, end = loop, np.roll(loop, -1, axis=0)
            for (x0, y0), (x1, y1) in zip(start, end, strict=True):
                crosses = (y0 > points[:, 1]) != (y1 > points[:, 1])
                with np.errstate(divide="ignore", invalid="ignore"):
                    x_at = x0 + (points[:, 1] - y0) * (x1 - x0) / (y1 - y0)
                inside ^= crosses & (points[:, 0] < x_at)
    return inside
