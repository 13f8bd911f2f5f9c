"""Many 2-D loops at once, and the same loops with fewer points.

:data:`Loops` lays out the loops of many regions as three arrays;
:func:`without_collinear` drops the points a straight run between two kept
points passes within ``eps`` of (and, first, repeated points and the tips of
zero-width spikes), every loop in one pass. The regions of
:mod:`shadowgeo.surface` go through it before :mod:`shadowgeo.seams` stitches
them, and so do the parts :mod:`shadowgeo.plane2d.triangulation` triangulates.
"""

from __future__ import annotations

import numpy as np

from .topology import loops_taken

__all__ = ["Loops", "loops_of", "without_collinear"]

# Loops of many regions at once: (P, 2) points, loop after loop; (L,) the
# number of points of each loop; (L,) the region of each loop.
Loops = tuple[np.ndarray, np.ndarray, np.ndarray]


def loops_of(regions: list[list[np.ndarray]]) -> Loops:
    """:data:`Loops` from a list of regions, each a list of (k, 2) loops."""
    sizes = np.array([len(loop) for region in regions for loop in region], dtype=np.int64)
    region = np.repeat(np.arange(len(regions)), [len(loops) for loops in regions])
    if len(sizes) == 0:
        return np.zeros((0, 2)), sizes, region.astype(np.int64)
    points = np.concatenate([loop for loops in regions for loop in loops])
    return points, sizes, region.astype(np.int64)


def without_collinear(regions: Loops, eps: float) -> Loops:
    """``regions`` without the loop points that a straight run between two
    kept points passes within ``eps`` of (a shadow edge split where the
    pieces that made it met, a point where a loop runs on along a face
    edge, a zero-width spike): each region is the same up to ``eps`` times
    its edges' lengths, and :func:`shadowgeo.seams.stitch` still splits every shared edge
    alike (it inserts the points either side keeps).

    The points off the line through their neighbours by more than ``eps``
    are kept; between two kept points, the point farthest from the line
    joining them is kept too while it is farther than ``eps`` (Douglas and
    Peucker's rule, every stretch of every loop at once), so every point
    dropped lies within ``eps`` of the loop that is left. A loop with no
    such point starts from its first point and the one farthest from it; a
    loop left with fewer than three points (no area) goes. Repeated points
    and the tips of zero-width spikes go first (:func:`_without_spikes`)."""
    points, sizes, region = _without_spikes(regions, eps)
    if not len(sizes):
        return points, sizes, region
    count = len(points)
    starts, loop, _, before, after = _ring(sizes)
    ends = starts + sizes
    index = np.arange(count)
    kept = _off_line(points, points[before], points[after]) > eps
    # a loop every point of which is on its neighbours' line: its first
    # point and the one farthest from it
    bare = ~np.logical_or.reduceat(kept, starts)
    if bare.any():
        reach = np.hypot(*(points - points[starts[loop]]).T)
        farthest = reach == np.maximum.reduceat(reach, starts)[loop]
        seed = bare[loop] & ((index == starts[loop]) | farthest)
        kept |= seed
    for _ in range(_DOUGLAS_PEUCKER_ROUNDS):
        at = np.where(kept, index, -1)
        back = np.maximum.accumulate(at)
        last = np.maximum.reduceat(at, starts)
        back = np.where(back >= starts[loop], back, last[loop])
        ahead = np.where(kept, index, count)
        ahead = np.minimum.accumulate(ahead[::-1])[::-1]
        first = np.minimum.reduceat(np.where(kept, index, count), starts)
        ahead = np.where(ahead < ends[loop], ahead, first[loop])
        gap = np.where(kept, 0.0, _off_line(points, points[back], points[ahead]))
        worst = np.full(count, -1.0)
        np.maximum.at(worst, back, gap)
        far = ~kept & (gap > eps) & (gap == worst[back])
        if not far.any():
            break
        # the first farthest point of each stretch
        _, chosen = np.unique(back[far], return_index=True)
        kept[np.flatnonzero(far)[chosen]] = True
    else:  # rounds spent: the stretches still too far from their chords stay whole
        kept |= np.isin(back, np.unique(back[~kept & (gap > eps)]))
    counts = np.add.reduceat(kept.astype(np.int64), starts)
    alive = counts >= 3
    keep = kept & alive[loop]
    # Dropping the points near a chord can leave a spike's tip between two
    # points that meet (a tip of two points 2e-6 apart, one of them on the
    # line of its neighbours: fuzz campaign, seed 40, geometry case 19499):
    # such tips go too.
    return _without_spikes((points[keep], counts[alive], region[alive]), eps)


def _without_spikes(regions: Loops, eps: float) -> Loops:
    """``regions`` without repeated points (within ``eps`` of the one before)
    and the tips of zero-width spikes (points whose neighbours are one
    point): neither changes a region's area; never two neighbours in one
    pass, a loop left with fewer than three points going.

    A loop with nothing to drop in a pass is final (the loops do not touch
    one another): later passes work on the loops still changing only, and
    the loops are put back in their order at the end."""
    points, sizes, region = regions
    # (final loops: their points, sizes, regions and places in the input)
    finished: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    place = np.arange(len(sizes))
    for turn in range(_SPIKE_PASSES):
        if not len(sizes):
            break
        _, owner, local, before, after = _ring(sizes)
        length = sizes[owner]
        # (the coordinates as contiguous columns: np.hypot of strided views
        # of the points was most of a pass)
        x, y = np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1])
        x_before, y_before = x[before], y[before]
        repeat = np.hypot(x - x_before, y - y_before) <= eps
        tip = _folded(x, y, before, after, eps)
        drop = repeat | tip
        changing = np.bincount(owner[drop], minlength=len(sizes)) > 0
        if not changing.all():  # set the final loops aside
            done = ~changing
            at = np.repeat(done, sizes)
            finished.append((points[at], sizes[done], region[done], place[done]))
            points, sizes, region, place = (
                points[~at],
                sizes[changing],
                region[changing],
                place[changing],
            )
            owner, local, length, drop = (
                np.repeat(np.arange(len(sizes)), sizes),
                local[~at],
                length[~at],
                drop[~at],
            )
        if not len(sizes):
            break
        # one colour of the loop's places a pass: even, odd, and the last
        # place of an odd loop (the first's neighbour) on its own
        colour = np.where((local == length - 1) & (length % 2 == 1), 2, local % 2)
        drop &= colour == turn % 3
        counts = sizes - np.bincount(owner[drop], minlength=len(sizes))
        alive = counts >= 3
        keep = ~drop & np.repeat(alive, sizes)
        points, sizes, region, place = points[keep], counts[alive], region[alive], place[alive]
    finished.append((points, sizes, region, place))
    if len(finished) == 1:
        return points, sizes, region
    # every loop back in its place in the input
    all_points = np.concatenate([part[0] for part in finished])
    all_sizes = np.concatenate([part[1] for part in finished])
    all_region = np.concatenate([part[2] for part in finished])
    all_place = np.concatenate([part[3] for part in finished])
    order = np.argsort(all_place, kind="stable")
    index, sizes = loops_taken(all_sizes, order)
    return all_points[index], sizes, all_region[order]


def _folded(
    x: np.ndarray, y: np.ndarray, before: np.ndarray, after: np.ndarray, eps: float
) -> np.ndarray:
    """(n,) True at the tip ``b`` of a zero-width spike ``a -> b -> c``: the
    loop turns back at ``b`` (``a`` and ``c`` lie on the same side of it) and
    each of ``a`` and ``c`` lies within ``eps`` of the line through ``b`` and
    the other, so the two edges run along one line (to ``eps``) and the
    triangle ``a b c`` has no width. Neighbours within ``eps`` of each other
    are such a tip too; a neighbour within ``eps`` of ``b`` is not (it is a
    repeated point). Testing only that the neighbours meet missed a slit
    whose sides run along one line but end a few times ``eps`` apart at its
    mouth: a shadow united from pieces that meet along a line far from the
    light (fuzz campaign, seed 39, geometry case 11905), whose long, nearly
    collinear edges the ear clipping then crossed with a triangle turned
    over."""
    ax, ay = x[before] - x, y[before] - y
    cx, cy = x[after] - x, y[after] - y
    meet = np.hypot(x[after] - x[before], y[after] - y[before]) <= eps
    a_length, c_length = np.hypot(ax, ay), np.hypot(cx, cy)
    near = np.minimum(a_length, c_length)
    cross = np.abs(ax * cy - ay * cx)
    # (a neighbour within eps of b is a repeated point, dropped as such)
    back = (ax * cx + ay * cy > 0) & (near > eps)
    thin = back & (cross <= eps * near)
    folded: np.ndarray = meet | thin
    return folded


def _ring(sizes: np.ndarray) -> tuple[np.ndarray, ...]:
    """For loops of ``sizes`` points laid one after another: each loop's
    start, and per point its loop, its place in it, and the index of the
    point before and after it round the loop."""
    starts = np.cumsum(sizes) - sizes
    loop = np.repeat(np.arange(len(sizes)), sizes)
    index = np.arange(int(sizes.sum()))
    local = index - starts[loop]
    before, after = index - 1, index + 1
    before[starts], after[starts + sizes - 1] = starts + sizes - 1, starts
    return starts, loop, local, before, after


# Passes of _without_spikes at most (each drops the such points of one colour).
_SPIKE_PASSES = 24
# Rounds of Douglas and Peucker's rule in without_collinear (each keeps one
# more point of every stretch still too far from its chord).
_DOUGLAS_PEUCKER_ROUNDS = 48


def _off_line(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(n,) distance of each point from the line through ``start`` and
    ``end`` (from ``start`` where the two are one point)."""
    chord = end - start
    offset = points - start
    length = np.hypot(chord[:, 0], chord[:, 1])
    cross = np.abs(offset[:, 0] * chord[:, 1] - offset[:, 1] * chord[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        distance = np.where(length > 0, cross / length, np.hypot(offset[:, 0], offset[:, 1]))
    result: np.ndarray = distance
    return result
