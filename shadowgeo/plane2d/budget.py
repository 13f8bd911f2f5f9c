"""What a 2-D union would cost Clipper2, measured before it runs: the
crossings among the loops' edges (:func:`crossings_estimate`) and the steps
of its sweep (:func:`sweep_work`). :func:`shadowgeo.plane2d.union.unite`
refuses a union past :data:`~shadowgeo.limits.MAX_UNION_CROSSINGS` or
:data:`~shadowgeo.limits.MAX_UNION_SWEEP` by these counts.
"""

from __future__ import annotations

import numpy as np

from ..limits import MAX_UNION_CROSSINGS, MAX_UNION_SWEEP
from ..topology import loop_rings

__all__ = ["FEWEST_CROSSING_EDGES", "crossings_estimate", "sweep_bound", "sweep_work"]


# Edge pairs sampled to estimate the crossings of a union, and the fewest
# sampled crossings that may refuse one (fewer say too little to act on).
_CROSSING_SAMPLES = 1 << 16
_FEWEST_SAMPLED_CROSSINGS = 8
# For unions too large for pair sampling to resolve the budget (crossings
# among few of very many pairs, e.g. one union per receiving face side by
# side): whole crossing counts of a few sampled edges, about this many edge
# tests in all, refusing only when this many of those edges cross something.
_EDGE_TESTS = 20_000_000
FEWEST_CROSSING_EDGES = 4


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
    n_edges = sum(map(len, loops))
    if n_edges * (n_edges - 1) // 2 <= MAX_UNION_CROSSINGS:  # (cells only lower the pairs)
        return 0.0, 0
    lengths = np.array([len(loop) for loop in loops])
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
    :data:`~shadowgeo.limits.MAX_UNION_SWEEP`, or when :func:`sweep_bound`
    shows the work cannot pass it.

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
    n_edges = sum(map(len, loops))
    if n_edges * n_edges <= MAX_UNION_SWEEP:  # (the product never exceeds it)
        return 0
    lengths = np.fromiter(map(len, loops), dtype=np.int64, count=len(loops))
    y = np.concatenate(loops)[:, 1].astype(np.float64)
    if sweep_bound(y, lengths) <= MAX_UNION_SWEEP:
        return 0
    # each corner's scanline by rank (one sort), and each edge's lower and
    # upper scanline (each loop closes)
    scanlines, rank = np.unique(y, return_inverse=True)
    rank = rank.reshape(-1)
    rank_next = rank[loop_rings(lengths)[1]]
    beginning = np.bincount(np.minimum(rank, rank_next), minlength=len(scanlines))
    ending = np.bincount(np.maximum(rank, rank_next), minlength=len(scanlines))
    # spanning scanline s: begun at or below it, less those ended below it
    spanning = np.cumsum(beginning) - (np.cumsum(ending) - ending)
    return int(np.dot(beginning, spanning))


def sweep_bound(y: np.ndarray, lengths: np.ndarray) -> int:
    """An upper bound on :func:`sweep_work` from the loops' y-ranges alone
    (``y`` the corners' y, loop after loop, ``lengths[i]`` each, none empty):
    an edge that begins on a scanline of loop i is placed past edges of the
    loops whose y-range holds that line, all of which meet loop i's range, so
    the work is at most the sum over loops of its edges times the edges of
    every loop whose range meets its own. Sorting the loops, not the edges:
    many faces' pieces in cells of one plane (thousands of small loops in
    bands apart) cost about a seventh of the exact count.

    Examples
    --------
    >>> y = np.array([0.0, 0.0, 1.0, 1.0, 0.5, 0.5, 1.5, 1.5])
    >>> sweep_bound(y, np.array([4, 4]))  # two squares overlapping in y (exactly 32)
    64
    """
    starts = np.cumsum(lengths) - lengths
    low, high = np.minimum.reduceat(y, starts), np.maximum.reduceat(y, starts)
    by_low, by_high = np.argsort(low), np.argsort(high)
    below_low = np.concatenate([[0], np.cumsum(lengths[by_low])])
    below_high = np.concatenate([[0], np.cumsum(lengths[by_high])])
    # edges of loops beginning at or below each loop's top, less those of loops
    # ending below its bottom
    meeting = below_low[np.searchsorted(low[by_low], high, side="right")]
    meeting -= below_high[np.searchsorted(high[by_high], low, side="left")]
    return int(np.dot(lengths, meeting))


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
