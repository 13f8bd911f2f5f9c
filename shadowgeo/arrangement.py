"""Exact union of many convex loops, by their arrangement, in numpy.

A city's shadow is the union of thousands of small convex outlines (one per
building). Clipper2 pays a few microseconds per loop and its sweep grows as
n^1.5 over a plane; here the union is built from the loops' crossings
directly, all loops at once:

1. loops whose boxes overlap (in the frame of the edges' main direction,
   along which shadows are long) are paired through a uniform grid;
2. for each pair, the edges of each loop that meet the other's box are
   paired when their own boxes meet, and four orientations tell whether
   they cross; each loop's first vertex is tested against the loops whose
   boxes hold it;
3. walking round each loop, the number of other loops covering it starts at
   its first vertex's count and steps by +-1 at each crossing: the stretches
   covered by none are the union's boundary;
4. those stretches are chained, crossing to crossing, into loops.

Every sign is certified: an orientation is used only when it is larger than
the bound on float64's rounding error of its evaluation (Shewchuk's), and so
is the order of two crossings on one edge. When a sign or an order cannot be
certified (loops touching, sharing an edge, three edges through one point) or
a loop is not strictly convex and counter-clockwise, :func:`convex_union`
gives None and the caller unites the loops another way (Clipper2's integer
sweep). The result is then the exact union's combinatorics, with crossing
points rounded once (about 1e-16 of the pair's size).
"""

from __future__ import annotations

import math

import numpy as np

from .limits import CROSSING_RESOLUTION as _T_RESOLUTION
from .limits import FRAME_ROUNDING as _FRAME_ROUNDING
from .limits import ORIENTATION_ERROR as _ORIENTATION_ERROR
from .limits import TINY
from .topology import cycle_walk, loop_rings, loops_taken

__all__ = ["convex_union", "convex_union_arrays", "convex_union_flat", "strictly_convex_loops"]

# Candidate box pairs per loop above which the grid is not worth it (one loop
# spanning many others' cells): the caller unites the loops another way.
_PAIRS_PER_LOOP = 64
# ... unless there are no more candidates than this in all (a few tens of MB).
_CANDIDATE_PAIRS = 1_000_000
# The grid's cells are listed in a table while there are at most this many
# per loop (else found by bisection).
_DENSE_CELLS = 8
# Edge pairs of the paired loops (every edge of one against every edge of
# the other) above which the candidate arrays would fill too much memory:
# many-sided loops over one another.
_TABLE_ENTRIES = 20_000_000


def convex_union(loops: list[np.ndarray]) -> list[np.ndarray] | None:
    """The boundary loops of the union of convex counter-clockwise ``loops``.

    Parameters
    ----------
    loops : list of (k, 2) float64, k >= 3
        Each strictly convex and counter-clockwise.

    Returns
    -------
    list of (k, 2) float64 or None
        The union's outer loops (counter-clockwise) and holes (clockwise), in
        no particular order; None when a loop is not strictly convex and
        counter-clockwise, or a sign or order the union depends on is within
        rounding of zero (touching loops, shared edges, collinear overlaps),
        or the loops' boxes pile up so that too many pairs would be tested.

    Examples
    --------
    >>> square = np.array([[0.0, 0], [2, 0], [2, 2], [0, 2]])
    >>> [len(loop) for loop in convex_union([square, square + 1])]
    [8]
    """
    flat = convex_union_flat(loops)
    if flat is None:
        return None
    points, starts = flat
    bounds = [*starts.tolist(), len(points)]
    return [points[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def convex_union_flat(loops: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`convex_union` as one (n, 2) array of the loops' points and
    the (c,) start of each loop in it (no array per loop)."""
    if not loops:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    sizes = np.fromiter(map(len, loops), dtype=np.int64, count=len(loops))
    return convex_union_arrays(np.concatenate(loops), sizes)


def convex_union_arrays(
    points: np.ndarray, sizes: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`convex_union_flat` of loops given as one (n, 2) array of their
    points, one loop after another, ``sizes[i]`` points each."""
    if len(sizes) == 0:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    if sizes.min() < 3:
        return None
    points, starts, following, step = _loop_edges(points, sizes)
    if not _strictly_convex(step, following, starts):
        return None
    low = np.minimum.reduceat(points, starts, axis=0)
    high = np.maximum.reduceat(points, starts, axis=0)
    axes, grow = _main_frame(points, step)
    turned_low, turned_high = _grown_boxes(_turned(points, axes), starts, grow)
    pairs = _box_pairs(turned_low, turned_high)
    if pairs is None:
        return None
    order, first, second = pairs
    low_xy, high_xy = low.view(np.complex128).ravel(), high.view(np.complex128).ravel()
    one, other = order[first], order[second]
    meets = _boxes_meet(low_xy[one], high_xy[one], low_xy[other], high_xy[other])
    first, second = first[meets], second[meets]
    if len(first) == 0:  # no two boxes meet: each loop is its own outline
        return points, starts
    # Loops renumbered in the grid's order: neighbours sit close in memory,
    # and the gathers below run several times faster.
    source, sizes = loops_taken(sizes, order)
    low, high = low[order], high[order]
    points = points.view(np.complex128).ravel()[source].view(np.float64).reshape(-1, 2)
    starts, following = loop_rings(sizes)
    if int(np.sum(sizes[first] * sizes[second])) > _TABLE_ENTRIES:
        return None
    frame = (_turned(points, axes), grow, turned_low[order], turned_high[order])
    found = _crossings(points, following, starts, sizes, low, high, first, second, frame)
    if found is None:
        return None
    return _boundary(points, following, starts, sizes, *found)


def _strictly_convex(step: np.ndarray, following: np.ndarray, starts: np.ndarray) -> bool:
    """Every loop turns left at each corner, by more than rounding, and its
    edges' directions go round once (so it is simple); ``step``: the edges
    as complex numbers."""
    return bool(np.all(_convex_each(step, following, starts)))


def strictly_convex_loops(points: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """(l,) bool: whether each loop of ``points`` (n, 2), ``sizes[i]`` points
    each in turn, is strictly convex and counter-clockwise beyond rounding:
    the test :func:`convex_union` makes of its loops, loop by loop."""
    sizes = np.asarray(sizes, dtype=np.int64)
    if len(sizes) == 0:
        return np.zeros(0, dtype=bool)
    if sizes.min() < 3:
        result = np.zeros(len(sizes), dtype=bool)
        enough = sizes >= 3
        point_enough = np.repeat(enough, sizes)
        result[enough] = strictly_convex_loops(points[point_enough], sizes[enough])
        return result
    _, starts, following, step = _loop_edges(points, sizes)
    return _convex_each(step, following, starts)


def _loop_edges(
    points: np.ndarray, sizes: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Loops laid one after another (``sizes[i]`` points each): the points
    as contiguous float64, each loop's start, each point's next on its loop,
    and each edge (to that next point) as a complex number."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    starts, following = loop_rings(sizes)
    step = points.view(np.complex128).ravel()
    return points, starts, following, step[following] - step


def _convex_each(step: np.ndarray, following: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """:func:`_strictly_convex` loop by loop."""
    after = step[following]
    turn = step.real * after.imag - step.imag * after.real
    scale = np.abs(step.real * after.imag) + np.abs(step.imag * after.real)
    left: np.ndarray = np.logical_and.reduceat(turn > 2 * _ORIENTATION_ERROR * scale, starts)
    # With every turn to the left (by less than a half turn), the direction
    # passes the +x axis once for each time the loop winds round.
    passes = (step.imag < 0) & (after.imag >= 0)
    once = np.add.reduceat(passes.astype(np.int64), starts) == 1
    convex: np.ndarray = left & once
    return convex


def _main_frame(points: np.ndarray, step: np.ndarray) -> tuple[np.ndarray, float]:
    """(2, 2) axes of the frame of the edges' (``step``, complex) main
    direction, and by how much a box in that frame is grown to hold every
    point for sure.

    Shadows cast by one light are long along the light's direction; boxes
    along it pair far fewer loops (and edges) that do not meet than boxes
    along x and y.
    """
    # Sums of products written out and the tensor's main axis in closed
    # form: a BLAS or LAPACK call (np.dot, @, eigh) may wake OpenBLAS's
    # threads, which then spin on the other core.
    x, y = step.real, step.imag
    across = float(np.add.reduce(x * y))
    spread = float(np.add.reduce(x * x)) - float(np.add.reduce(y * y))
    angle = 0.5 * math.atan2(2 * across, spread)
    cosine, sine = math.cos(angle), math.sin(angle)
    axes = np.array([[-sine, cosine], [cosine, sine]])  # columns: across, then along
    grow = _FRAME_ROUNDING * float(np.abs(points).max(initial=0.0)) + np.finfo(float).tiny
    return axes, grow


def _turned(points: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(n, 2) ``points @ axes``, written out (no BLAS call)."""
    x, y = points[:, 0], points[:, 1]
    return np.column_stack([x * axes[0, 0] + y * axes[1, 0], x * axes[0, 1] + y * axes[1, 1]])


def _grown_boxes(
    turned: np.ndarray, starts: np.ndarray, grow: float
) -> tuple[np.ndarray, np.ndarray]:
    """Each loop's box of ``turned`` points, grown by ``grow``."""
    low = np.minimum.reduceat(turned, starts, axis=0)
    high = np.maximum.reduceat(turned, starts, axis=0)
    return low - grow, high + grow


def _box_pairs(
    low: np.ndarray, high: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The loops in grid order, and (i, j), i != j, positions in that order,
    each unordered pair once, of the loops whose closed boxes meet.

    A grid with cells as large as the largest box: each box is filed under
    the cell of its lower corner and paired with the boxes of its own cell
    and of the next cells. None when that would test more than
    ``_PAIRS_PER_LOOP`` candidates per loop and ``_CANDIDATE_PAIRS`` in all."""
    count = len(low)
    cell = np.maximum((high - low).max(axis=0), TINY)
    origin = low.min(axis=0)
    column_row = np.floor((low - origin) / cell).astype(np.int64)
    rows = int(column_row[:, 1].max()) + 3
    # rows shifted by one so that the row below the first is still >= 0
    cell_id = column_row[:, 0] * rows + column_row[:, 1] + 1
    order = np.argsort(cell_id, kind="stable")
    sorted_id = cell_id[order]
    position = np.arange(count)
    # same cell (later boxes only), then the cells right-below, right,
    # right-above and above
    steps = np.array([0, rows - 1, rows, rows + 1, 1])
    targets = (sorted_id[None, :] + steps[:, None]).ravel()
    n_cells = int(sorted_id[-1]) + rows + 2
    if n_cells <= _DENSE_CELLS * count:  # each cell's range from a table, no search
        bounds = np.zeros(n_cells + 1, dtype=np.int64)
        np.cumsum(np.bincount(sorted_id, minlength=n_cells), out=bounds[1:])
        begins, ends = bounds[targets], bounds[targets + 1]
    else:
        begins = np.searchsorted(sorted_id, targets, side="left")
        ends = np.searchsorted(sorted_id, targets, side="right")
    begins[:count] = position + 1
    counts = np.maximum(ends - begins, 0)
    total = int(counts.sum())
    if total > max(_PAIRS_PER_LOOP * count, _CANDIDATE_PAIRS):
        return None
    first = np.repeat(np.tile(position, 5), counts)
    offsets = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
    second = np.repeat(begins, counts) + offsets
    low = np.ascontiguousarray(low[order]).view(np.complex128).ravel()
    high = np.ascontiguousarray(high[order]).view(np.complex128).ravel()
    meets = _boxes_meet(low[first], high[first], low[second], high[second])
    return order, first[meets], second[meets]


def _boxes_meet(
    low_a: np.ndarray, high_a: np.ndarray, low_b: np.ndarray, high_b: np.ndarray
) -> np.ndarray:
    """Whether closed boxes a and b meet, corners as complex numbers."""
    meets: np.ndarray = (low_a.real <= high_b.real) & (low_b.real <= high_a.real)
    meets &= (low_a.imag <= high_b.imag) & (low_b.imag <= high_a.imag)
    return meets


def _orientation(origin: np.ndarray, towards: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Twice the signed area of each triangle origin -> towards -> point
    (> 0: point left of the line), points as complex numbers."""
    ahead, aside = towards - origin, point - origin
    side: np.ndarray = ahead.real * aside.imag - ahead.imag * aside.real
    return side


def _crossings(
    points: np.ndarray,
    following: np.ndarray,
    starts: np.ndarray,
    sizes: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    frame: tuple[np.ndarray, float, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, ...] | None:
    """Every proper crossing between the edges of paired loops, and each
    loop's cover count at its first vertex; None where a sign is uncertain.

    Only edge pairs whose boxes meet are tested (others cannot meet), boxes
    taken in ``frame`` (the points turned into the main frame, the growth
    that holds their rounding, the loops' grown boxes there); each such
    pair's four orientations must be certain.

    Returns (depth, edge_a, t_a, delta_a, edge_b, t_b, delta_b, where,
    slack): per loop the number of other loops holding its first vertex; per
    crossing the global index of the edge on each side, the parameter along
    it, +1 where that edge enters the other loop (-1 leaving), the crossing
    point, and (n, 2) each parameter's rounding bound."""
    # Points, edge ends and edge boxes as complex numbers: numpy gathers one
    # complex far faster than a row of an (n, 2) array.
    start = points.view(np.complex128).ravel()
    end = start[following]
    step = end - start
    turned, grow, turned_low, turned_high = frame
    turned_start = np.ascontiguousarray(turned).view(np.complex128).ravel()
    turned_end = turned_start[following]
    edge_low = np.minimum(turned_start.real, turned_end.real) - grow
    edge_low = edge_low + 1j * (np.minimum(turned_start.imag, turned_end.imag) - grow)
    edge_high = np.maximum(turned_start.real, turned_end.real) + grow
    edge_high = edge_high + 1j * (np.maximum(turned_start.imag, turned_end.imag) + grow)
    loop_low = np.ascontiguousarray(turned_low).view(np.complex128).ravel()
    loop_high = np.ascontiguousarray(turned_high).view(np.complex128).ravel()
    box_low, box_high = low.view(np.complex128).ravel(), high.view(np.complex128).ravel()
    pair_low = np.minimum(box_low[first].real, box_low[second].real) + 1j * np.minimum(
        box_low[first].imag, box_low[second].imag
    )
    pair_size = np.maximum(box_high[first], box_high[second]) - pair_low
    bound = _ORIENTATION_ERROR * np.maximum(pair_size.real, pair_size.imag) ** 2  # per pair
    depth = _first_vertex_depth(start, end, starts, sizes, box_low, box_high, first, second, bound)
    if depth is None:
        return None
    # The edge pairs of a block of loop pairs at a time: the temporaries
    # (several numbers per edge pair) stay a few MB, memory reused from
    # block to block rather than fresh pages each time.
    weight = np.cumsum(sizes[first] * sizes[second])
    cuts = np.searchsorted(weight, np.arange(_BLOCK_EDGE_PAIRS, int(weight[-1]), _BLOCK_EDGE_PAIRS))
    edges = (start, step, edge_low, edge_high, loop_low, loop_high)
    found = []
    for begin, stop in zip([0, *cuts.tolist()], [*cuts.tolist(), len(first)], strict=True):
        if stop > begin:
            block = _block_crossings(
                edges, starts, sizes, first[begin:stop], second[begin:stop], bound[begin:stop]
            )
            if block is None:
                return None
            found.append(block)
    edge_a, t_a, delta_a, edge_b, t_b, delta_b, where, slack = (
        np.concatenate(column) for column in zip(*found, strict=True)
    )
    return depth, edge_a, t_a, delta_a, edge_b, t_b, delta_b, where, slack


# Edge pairs (every edge of one loop against every edge of the other,
# summed over the loop pairs) that _crossings tests in one block.
_BLOCK_EDGE_PAIRS = 1 << 16


def _block_crossings(
    edges: tuple[np.ndarray, ...],
    starts: np.ndarray,
    sizes: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    bound: np.ndarray,
) -> tuple[np.ndarray, ...] | None:
    """:func:`_crossings`' crossings between the loop pairs ``first[i]``,
    ``second[i]`` (``bound``: each pair's orientation error bound;
    ``edges``: every edge's start and step, its box and its loop's box in
    the main frame), without the first vertices' depth."""
    start, step, edge_low, edge_high, loop_low, loop_high = edges
    edges_a, edges_b, owners = [], [], []
    radix = int(sizes.max()) + 1
    pair_sizes = sizes[first] * radix + sizes[second]
    classes = np.unique(pair_sizes).tolist()
    for key in classes:
        # (one class, the common case of equal loops: no subset to take)
        chosen = np.flatnonzero(pair_sizes == key) if len(classes) > 1 else None
        loops_a = first if chosen is None else first[chosen]
        loops_b = second if chosen is None else second[chosen]
        size_a, size_b = divmod(key, radix)
        # pairs of edges whose boxes meet, among the edges of each loop
        # that meet the other loop's box
        index_a = starts[loops_a][:, None] + np.arange(size_a)
        index_b = starts[loops_b][:, None] + np.arange(size_b)
        low_a, high_a = edge_low[index_a], edge_high[index_a]
        low_b, high_b = edge_low[index_b], edge_high[index_b]
        near_a = _meets_box(low_a, high_a, loop_low[loops_b], loop_high[loops_b])
        near_b = _meets_box(low_b, high_b, loop_low[loops_a], loop_high[loops_a])
        meet = near_a[:, :, None] & near_b[:, None, :]
        flat = np.flatnonzero(meet)
        pair, rest = np.divmod(flat, size_a * size_b)
        edges_a.append(starts[loops_a[pair]] + rest // size_b)
        edges_b.append(starts[loops_b[pair]] + rest % size_b)
        owners.append(pair if chosen is None else chosen[pair])
    edge_a, edge_b, owner = np.concatenate(edges_a), np.concatenate(edges_b), np.concatenate(owners)
    low_a, high_a, low_b, high_b = (
        edge_low[edge_a],
        edge_high[edge_a],
        edge_low[edge_b],
        edge_high[edge_b],
    )
    meet = (low_a.real <= high_b.real) & (low_b.real <= high_a.real)
    meet &= (low_a.imag <= high_b.imag) & (low_b.imag <= high_a.imag)
    edge_a, edge_b, owner = edge_a[meet], edge_b[meet], owner[meet]
    # The four orientations from three products: with r = b0 - a0 and the
    # edges' steps da, db, b0 and a0 against the other's edge are the usual
    # determinants (b0 - a0) x ..., and b1, a1 add the steps' product c.
    a0, step_a, b0, step_b = start[edge_a], step[edge_a], start[edge_b], step[edge_b]
    r = b0 - a0
    u = step_a.real * r.imag - step_a.imag * r.real  # b0 against a's edge
    s = r.real * step_b.imag - r.imag * step_b.real  # a0 against b's edge
    c = step_a.real * step_b.imag - step_a.imag * step_b.real
    v, w = u + c, s - c  # b1 against a's edge, a1 against b's edge
    margin = bound[owner]
    smallest = np.minimum(np.minimum(np.abs(u), np.abs(v)), np.minimum(np.abs(s), np.abs(w)))
    if np.any(smallest <= margin):
        return None
    cross = np.flatnonzero((u * v < 0) & (s * w < 0))
    edge_a, edge_b, margin = edge_a[cross], edge_b[cross], margin[cross]
    u, s, c = u[cross], s[cross], c[cross]
    t_a, t_b = s / c, -u / c  # s / (s - w), u / (u - v)
    where = a0[cross] + t_a * step_a[cross]
    where_xy = np.column_stack([where.real, where.imag])
    slack = 2 * margin / np.abs(c)
    slack = np.column_stack([slack, slack])
    delta_a, delta_b = np.where(s < 0, 1, -1), np.where(u < 0, 1, -1)
    return edge_a, t_a, delta_a, edge_b, t_b, delta_b, where_xy, slack


def _first_vertex_depth(
    start: np.ndarray,
    end: np.ndarray,
    starts: np.ndarray,
    sizes: np.ndarray,
    box_low: np.ndarray,
    box_high: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    bound: np.ndarray,
) -> np.ndarray | None:
    """(n,) how many other loops hold each loop's first vertex; None if a
    first vertex is within rounding of another loop's edge line while on
    the inner side of all the others."""
    depth = np.zeros(len(sizes), dtype=np.int64)
    for inner, outer in ((first, second), (second, first)):
        corner = start[starts[inner]]
        low, high = box_low[outer], box_high[outer]
        inside_box = (low.real <= corner.real) & (corner.real <= high.real)
        inside_box &= (low.imag <= corner.imag) & (corner.imag <= high.imag)
        rows = np.flatnonzero(inside_box)
        for size in np.unique(sizes[outer[rows]]).tolist():
            chosen = rows[sizes[outer[rows]] == size]
            index = starts[outer[chosen]][:, None] + np.arange(size)
            side = _orientation(start[index], end[index], corner[chosen][:, None])
            margin = bound[chosen][:, None]
            outside = np.any(side < -margin, axis=1)
            if np.any(~outside & np.any(side <= margin, axis=1)):
                return None
            depth += np.bincount(inner[chosen[~outside]], minlength=len(depth))
    return depth


def _meets_box(
    low: np.ndarray, high: np.ndarray, box_low: np.ndarray, box_high: np.ndarray
) -> np.ndarray:
    """(p, k) bool: whether box [low, high][p, k] meets box p (corners as
    complex numbers)."""
    meets: np.ndarray = (low.real <= box_high.real[:, None]) & (high.real >= box_low.real[:, None])
    meets &= (low.imag <= box_high.imag[:, None]) & (high.imag >= box_low.imag[:, None])
    return meets


def _boundary(
    points: np.ndarray,
    following: np.ndarray,
    starts: np.ndarray,
    sizes: np.ndarray,
    depth: np.ndarray,
    edge_a: np.ndarray,
    t_a: np.ndarray,
    delta_a: np.ndarray,
    edge_b: np.ndarray,
    t_b: np.ndarray,
    delta_b: np.ndarray,
    where: np.ndarray,
    slack: np.ndarray,
) -> tuple[np.ndarray, np.ndarray] | None:
    """The stretches of the loops covered by no other loop, chained into
    loops, as (n, 2) points and the start of each loop among them; None if
    two crossings on one edge are too close to order."""
    n_points, n_crossings = len(points), len(t_a)
    # Events round every loop: each vertex, then the crossings on the edge
    # it starts, by parameter. Only the crossings are sorted (by edge + t,
    # exact in order where the ts differ by more than _T_RESOLUTION), then
    # merged after their edge's vertex.
    edge = np.concatenate([edge_a, edge_b])
    t = np.concatenate([t_a, t_b])
    order = np.argsort(edge + t, kind="stable")
    edge, t = edge[order], t[order]
    error = np.concatenate([slack[:, 0], slack[:, 1]])[order]
    same_edge = edge[1:] == edge[:-1]
    resolution = max(_T_RESOLUTION, 64 * float(np.spacing(float(n_points))))
    close = t[1:] - t[:-1] <= np.maximum(error[1:] + error[:-1], resolution)
    margin = np.maximum(error, resolution)
    if np.any(same_edge & close) or np.any((t <= margin) | (1 - t <= margin)):
        return None
    on_edge = np.bincount(edge, minlength=n_points)  # crossings before each vertex
    vertex_at = np.arange(n_points) + np.cumsum(on_edge) - on_edge
    crossing_at = edge + 1 + np.arange(len(edge))
    n_events = n_points + len(edge)
    node = np.empty(n_events, dtype=np.int64)
    node[vertex_at] = np.arange(n_points)
    node[crossing_at] = n_points + np.concatenate([np.arange(n_crossings)] * 2)[order]
    delta = np.zeros(n_events, dtype=np.int64)
    delta[crossing_at] = np.concatenate([delta_a, delta_b])[order]
    loop_of_point = np.repeat(np.arange(len(sizes)), sizes)
    loop = np.empty(n_events, dtype=np.int64)
    loop[vertex_at] = loop_of_point
    loop[crossing_at] = loop_of_point[edge]
    # The cover count after each event: the first vertex's count, stepped at
    # each crossing (a loop's first event is its first vertex, delta 0).
    first_event = vertex_at[starts]
    last_event = np.append(first_event[1:], n_events) - 1
    running = np.cumsum(delta)
    cover = depth[loop] + running - running[first_event][loop]
    if np.any(cover < 0) or np.any(running[last_event] != running[first_event]):
        return None
    after = np.arange(1, n_events + 1)
    after[last_event] = first_event
    kept = np.flatnonzero(cover == 0)
    if not len(kept):
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    start_node, end_node = node[kept], node[after[kept]]
    piece_at = np.full(n_points + n_crossings, -1, dtype=np.int64)
    piece_at[start_node] = np.arange(len(kept))
    successor = piece_at[end_node]
    # each node starts one stretch (else two were written to one slot)
    if np.any(successor < 0) or np.any(piece_at[start_node] != np.arange(len(kept))):
        return None
    walk, cuts = _walk_runs(successor)
    location = np.concatenate([points, where])[start_node[walk]]
    return location, np.concatenate([[0], cuts]).astype(np.int64)


def _walk_runs(successor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~shadowgeo.topology.cycle_walk` of a permutation made mostly
    of runs ``k -> k + 1`` (the stretches of one loop between crossings):
    the runs are walked, then laid out."""
    count = len(successor)
    breaks = np.flatnonzero(successor[:-1] != np.arange(1, count))
    run_first = np.concatenate([[0], breaks + 1])
    run_last = np.append(breaks, count - 1)
    run_of = np.repeat(np.arange(len(run_first)), run_last - run_first + 1)
    runs, run_cuts = cycle_walk(run_of[successor[run_last]])
    lengths = (run_last - run_first + 1)[runs]
    ends = np.cumsum(lengths)
    walk = np.arange(count) - np.repeat(ends - lengths - run_first[runs], lengths)
    cuts = (ends - lengths)[run_cuts]
    return walk, cuts
