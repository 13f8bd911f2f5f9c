"""Compiled loops for the many-lights path (numba), where numpy would take
dozens of passes over a chunk's arrays for a few hundred corners a light.

Imported on first use only (numba's import and the cached machine code take
about 0.8 s and 100 MB), when :mod:`shadowgeo.compiled`'s rule says a job
repays it: :func:`shadowgeo.batchlights.whole_outlines` for a light of two to
64 outline loops, 128 corners or more, one loop's box holding the others' (a
dented caster's folds; not a few shapes side by side, nor a small scene's
sphere and box); :func:`shadowgeo.topology.cycle_walk` and
``shadowgeo.silhouette._successors`` for walks of a million items or more (the
same results as their numpy ways, bit for bit); :func:`union_areas` and
:func:`ring_pieces` for the shadowed share of each face in a long sun study
(:func:`shadowgeo.surface.shadowed_fractions`, the same to about 1e-12 of a
face's area as the 2-D union it replaces: each convex body's shadow on a
face as one convex piece, and the area of the union of a face's pieces).
``SHADOWGEO_COMPILED=never`` keeps numba out, ``always`` takes these loops
for every job. Each function is compiled once and cached beside this file
(or in numba's user cache when this folder is read-only).

The signs of :func:`whole_loops` are certificates: each is taken only when it holds beyond the
rounding of the numbers that give it, and a loop or light that is not
certified goes the general way (a 2-D union by Clipper2), never a guess.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["cycle_walk", "ring_pieces", "successors", "union_areas", "whole_loops"]

# A sign is certain when the cross product is beyond its light's margin
# (see whole_loops), an order along an axis when the difference is beyond
# the axis slack.

# Directions (over half a turn, from x) in which a loop is tried for being
# monotone when it is not along its principal axis.
_DIRECTIONS = 16


@nb.njit(cache=True, inline="always")
def _pseudo_angle(dx: float, dy: float) -> float:
    """A number in [0, 4) that grows with the angle of (dx, dy) from the x
    axis, counter-clockwise; p(angle + pi) = p(angle) + 2 (mod 4)."""
    size = abs(dx) + abs(dy)
    ratio = dy / size if size > 0 else 0.0
    if dx >= 0:
        return ratio + 4.0 if dy < 0 else ratio
    return 2.0 - ratio


@nb.njit(cache=True)
def _mean(x: np.ndarray, y: np.ndarray, first: int, n: int) -> tuple[float, float]:
    """The mean of the corners ``first .. first + n``, summed in order."""
    sx = 0.0
    sy = 0.0
    for i in range(first, first + n):
        sx += x[i]
        sy += y[i]
    return sx / n, sy / n


@nb.njit(cache=True)
def _star(
    x: np.ndarray, y: np.ndarray, first: int, n: int, margin: float, rel: np.ndarray
) -> tuple[bool, float, float]:
    """Whether the loop of corners ``first .. first + n`` is certainly
    star-shaped around the mean of its corners and counter-clockwise: each
    edge turns left round the mean beyond ``margin``, and the spokes' angles
    fall back once only round the loop (each certain turn is a step far
    beyond the angles' rounding). Fills ``rel[:n]`` with each spoke's
    pseudo-angle from the first spoke's, in [0, 4) and rising; returns the
    mean too."""
    cx, cy = _mean(x, y, first, n)
    falls = 0
    base = _pseudo_angle(x[first] - cx, y[first] - cy)
    previous = base
    for k in range(n):
        i = first + k
        j = first + (k + 1) % n
        ax = x[i] - cx
        ay = y[i] - cy
        # (p_i - c) x (p_i+1 - c) as (p_i - c) x (p_i+1 - p_i)
        if not ax * (y[j] - y[i]) - ay * (x[j] - x[i]) > margin:
            return False, cx, cy
        angle = _pseudo_angle(ax, ay)
        if k > 0 and angle < previous:
            falls += 1
        previous = angle
        rel[k] = angle - base + (4.0 if angle < base else 0.0)
    if base < previous:  # the step from the last spoke back to the first
        falls += 1
    return falls == 1, cx, cy


@nb.njit(cache=True)
def _monotone(
    x: np.ndarray,
    y: np.ndarray,
    first: int,
    n: int,
    c: float,
    s: float,
    slack: float,
    margin: float,
    along: np.ndarray,
    side: np.ndarray,
) -> bool:
    """Whether the loop of corners ``first .. first + n`` is certainly simple
    and counter-clockwise by being monotone along the axis (c, s): from one
    lowest corner its corners rise strictly to one highest (the lower side)
    and fall strictly back (the upper side), and each corner between the
    ends of one side lies strictly left of the other side's edge across
    from it (:func:`_beside`). It is then the region between the graphs of
    two functions, one above the other. Orders are certain beyond
    ``slack``, sides beyond ``margin`` (a turn of axes keeps the signs of
    the loop's own cross products). ``along`` and ``side`` are scratch of at
    least ``n + 1`` items."""
    if n < 3:
        return False
    for k in range(n):
        along[k] = x[first + k] * c + y[first + k] * s
    lowest = -1
    highest = -1
    changes = 0
    for k in range(n):
        rise = along[(k + 1) % n] - along[k]
        if not abs(rise) > slack:
            return False
        fall_in = along[k] - along[(k - 1) % n] < 0
        if rise > 0 and fall_in:
            lowest = k
            changes += 1
        elif rise < 0 and not fall_in:
            highest = k
            changes += 1
        if changes > 2:
            return False
    if changes != 2:
        return False
    up = (highest - lowest) % n  # edges of the lower side
    down = n - up  # of the upper side
    # The upper side in rising order (from the lowest corner backwards)
    # against the lower side's corners between its ends, then the lower
    # side (forwards) against the upper side's.
    for t in range(down + 1):
        side[t] = (lowest - t) % n
    if not _beside(x, y, first, n, along, side, down + 1, lowest, 1, up, True, slack, margin):
        return False
    for t in range(up + 1):
        side[t] = (lowest + t) % n
    return _beside(x, y, first, n, along, side, up + 1, lowest, -1, down, False, slack, margin)


@nb.njit(cache=True)
def _beside(
    x: np.ndarray,
    y: np.ndarray,
    first: int,
    n: int,
    along: np.ndarray,
    side: np.ndarray,
    m: int,
    start: int,
    step: int,
    count: int,
    upper: bool,
    slack: float,
    margin: float,
) -> bool:
    """Whether the corners ``start + step t`` (t from 1 to ``count`` - 1,
    round the loop ``first .. first + n``), in rising order along the axis,
    lie strictly left of the edge of ``side`` (``m`` corners of the other
    side in rising order) across from each: below the upper side's edges,
    which run falling, above the lower side's, which run rising."""
    u = 0
    for t in range(1, count):
        k = (start + step * t) % n
        while u + 1 < m - 1 and along[side[u + 1]] <= along[k]:
            u += 1
        lo, hi = side[u], side[u + 1]
        if not (along[k] - along[lo] > slack and along[hi] - along[k] > slack):
            return False
        tail = first + (hi if upper else lo)
        head = first + (lo if upper else hi)
        i = first + k
        cross = (x[head] - x[tail]) * (y[i] - y[tail]) - (y[head] - y[tail]) * (x[i] - x[tail])
        if not cross > margin:
            return False
    return True


@nb.njit(cache=True)
def _simple(
    x: np.ndarray,
    y: np.ndarray,
    first: int,
    n: int,
    slack: float,
    margin: float,
    along: np.ndarray,
    side: np.ndarray,
) -> bool:
    """:func:`_monotone` along the loop's principal axis (a crescent's
    length), else along one of ``_DIRECTIONS`` directions half a turn apart
    from x."""
    mx, my = _mean(x, y, first, n)
    sxx = 0.0
    sxy = 0.0
    syy = 0.0
    for i in range(first, first + n):
        dx = x[i] - mx
        dy = y[i] - my
        sxx += dx * dx
        sxy += dx * dy
        syy += dy * dy
    angle = 0.5 * np.arctan2(2 * sxy, sxx - syy)
    if _monotone(x, y, first, n, np.cos(angle), np.sin(angle), slack, margin, along, side):
        return True
    for k in range(_DIRECTIONS):  # a fold's loop that bends is often monotone another way
        angle = np.pi * k / _DIRECTIONS
        if _monotone(x, y, first, n, np.cos(angle), np.sin(angle), slack, margin, along, side):
            return True
    return False


@nb.njit(cache=True, inline="always")
def _wedge(px: float, py: float, rel: np.ndarray, n: int, base: float) -> tuple[int, float]:
    """The wedge of the star-shaped loop (spokes' angles ``rel`` from the
    first spoke's, ``base``) whose angles hold the direction (px, py) from
    its centre: the last spoke at or before it; and that direction's angle
    from the first spoke."""
    angle = _pseudo_angle(px, py)
    turn = angle - base + (4.0 if angle < base else 0.0)
    lo = 0
    hi = n
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if rel[mid] <= turn:
            lo = mid
        else:
            hi = mid
    return lo, turn


@nb.njit(cache=True)
def _held(
    x: np.ndarray,
    y: np.ndarray,
    first: int,
    n: int,
    h_first: int,
    h_n: int,
    rel: np.ndarray,
    cx: float,
    cy: float,
    margin: float,
) -> bool:
    """Whether the loop ``first .. first + n`` is certainly inside the
    star-shaped loop ``h_first .. h_first + h_n`` (centre (cx, cy), spokes'
    angles ``rel``): each corner strictly inside the wedge (the triangle
    from the centre to an edge) its angle finds, and each edge crossing
    every spoke between its ends' wedges short of the holder's corner, the
    wedges spanning less than half a turn. The pieces of an edge between
    two spokes then lie in the wedge between them."""
    base = _pseudo_angle(x[h_first] - cx, y[h_first] - cy)
    w_j, t_j = _wedge(x[first] - cx, y[first] - cy, rel, h_n, base)
    for k in range(n):
        i = first + k
        j = first + (k + 1) % n
        w_i, t_i = w_j, t_j  # each corner's wedge, found once
        w_j, t_j = _wedge(x[j] - cx, y[j] - cy, rel, h_n, base)
        a = h_first + w_i
        b = h_first + (w_i + 1) % h_n
        if not _in_wedge(x, y, i, a, b, cx, cy, margin):
            return False
        ccw = (t_j - t_i) % 4.0 < 2.0
        lo = w_i if ccw else w_j
        hi = w_j if ccw else w_i
        if lo != hi and not _spans_spokes(x, y, i, j, lo, hi, h_first, h_n, rel, cx, cy, margin):
            return False
    return True


@nb.njit(cache=True)
def _in_wedge(
    x: np.ndarray,
    y: np.ndarray,
    i: int,
    a: int,
    b: int,
    cx: float,
    cy: float,
    margin: float,
) -> bool:
    """Whether corner ``i`` lies strictly inside the triangle from the centre
    (cx, cy) to the holder's edge ``a -> b`` (beyond ``margin``)."""
    ox = x[i] - cx
    oy = y[i] - cy
    ax = x[a] - cx
    ay = y[a] - cy
    bx = x[b] - cx
    by = y[b] - cy
    inside: bool = (
        ax * oy - ay * ox > margin
        and ox * by - oy * bx > margin
        and (bx - ax) * (oy - ay) - (by - ay) * (ox - ax) > margin
    )
    return inside


@nb.njit(cache=True)
def _spans_spokes(
    x: np.ndarray,
    y: np.ndarray,
    i: int,
    j: int,
    lo: int,
    hi: int,
    h_first: int,
    h_n: int,
    rel: np.ndarray,
    cx: float,
    cy: float,
    margin: float,
) -> bool:
    """Whether the edge ``i -> j``, its ends in the holder's wedges ``lo``
    and ``hi`` (counter-clockwise, less than half a turn apart), crosses
    every spoke between them short of the holder's corner: the centre and
    each corner strictly on opposite sides of its line."""
    top = (hi + 1) % h_n
    if top == lo or not (rel[top] - rel[lo]) % 4.0 < 1.9:
        return False
    dx = x[j] - x[i]
    dy = y[j] - y[i]
    to_centre = dx * (cy - y[i]) - dy * (cx - x[i])
    if not abs(to_centre) > margin:
        return False
    spoke = (lo + 1) % h_n
    while True:
        v = h_first + spoke
        to_corner = dx * (y[v] - y[i]) - dy * (x[v] - x[i])
        if not (
            (to_centre > margin and to_corner < -margin)
            or (to_centre < -margin and to_corner > margin)
        ):
            return False
        if spoke == hi:
            break
        spoke = (spoke + 1) % h_n
    return True


@nb.njit(cache=True)
def whole_loops(
    x: np.ndarray,
    y: np.ndarray,
    loop_lengths: np.ndarray,
    loop_light: np.ndarray,
    count: int,
    point_slack: float,
    product_slack: float,
    epsilon: float,
) -> np.ndarray:
    """(count,) for each light, the index of the one loop whose inside is
    certainly the light's whole region of positive winding, else -1 (see
    :func:`shadowgeo.batchlights.whole_outlines` for the certificates).

    ``x``, ``y`` are the loops' corners one loop after another,
    ``loop_lengths`` their counts and ``loop_light`` (ascending) their
    lights. A light's margins come from the box of its corners (size s: its
    width plus its height; any difference of two of its points is at most s
    in |dx| + |dy|): a cross product of two differences is off by at most
    ``4 point_slack s + product_slack s^2``, a coordinate along an axis by
    ``4 epsilon (|x| + |y|)`` at most.
    """
    result = np.full(count, -1, dtype=np.int64)
    n_loops = len(loop_lengths)
    firsts = np.empty(n_loops + 1, dtype=np.int64)
    firsts[0] = 0
    longest = 1
    for loop in range(n_loops):
        firsts[loop + 1] = firsts[loop] + loop_lengths[loop]
        longest = max(longest, loop_lengths[loop])
    rel = np.empty(longest)  # scratch, the longest loop's size
    along = np.empty(longest + 1)
    side = np.empty(longest + 1, dtype=np.int64)
    start = 0
    while start < n_loops:
        light = loop_light[start]
        stop = start
        while stop < n_loops and loop_light[stop] == light:
            stop += 1
        low_x = np.inf
        high_x = -np.inf
        low_y = np.inf
        high_y = -np.inf
        for i in range(firsts[start], firsts[stop]):
            low_x = min(low_x, x[i])
            high_x = max(high_x, x[i])
            low_y = min(low_y, y[i])
            high_y = max(high_y, y[i])
        size = (high_x - low_x) + (high_y - low_y)
        margin = 4 * point_slack * size + product_slack * size * size
        slack = 8 * epsilon * (max(-low_x, high_x) + max(-low_y, high_y))
        # the loop of largest area holds the others, if any does
        holder = start
        best = -np.inf
        for loop in range(start, stop):
            twice = 0.0
            a, n = firsts[loop], loop_lengths[loop]
            for k in range(n):
                i = a + k
                j = a + (k + 1) % n
                twice += x[i] * y[j] - x[j] * y[i]
            if twice >= best:
                best = twice
                holder = loop
        h_first, h_n = firsts[holder], loop_lengths[holder]
        star, cx, cy = _star(x, y, h_first, h_n, margin, rel)
        certified = star
        for loop in range(start, stop):
            if not certified:
                break
            if loop == holder:
                continue
            a, n = firsts[loop], loop_lengths[loop]
            certified = _simple(x, y, a, n, slack, margin, along, side) and _held(
                x, y, a, n, h_first, h_n, rel, cx, cy, margin
            )
        if certified:
            result[light] = holder
        start = stop
    return result


@nb.njit(cache=True)
def cycle_walk(successor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`shadowgeo.topology.cycle_walk` walked one item after another
    (the same result: each cycle from its lowest item, cycles by that
    item). Items are taken in rising order; the first not yet walked is the
    lowest of its cycle, all lower items being on cycles walked before."""
    count = len(successor)
    for item in range(count):  # numba does not check indices
        if successor[item] < 0 or successor[item] >= count:
            raise IndexError("cycle_walk: a successor out of range")
    walk = np.empty(count, dtype=np.int64)
    cuts = np.empty(count, dtype=np.int64)
    seen = np.zeros(count, dtype=np.bool_)
    filled = 0
    n_cuts = 0
    for first in range(count):
        if seen[first]:
            continue
        if filled > 0:
            cuts[n_cuts] = filled
            n_cuts += 1
        item = first
        while not seen[item]:
            seen[item] = True
            walk[filled] = item
            filled += 1
            item = successor[item]
    return walk, cuts[:n_cuts].copy()


@nb.njit(cache=True)
def successors(starts: np.ndarray, ends: np.ndarray, span: int) -> tuple[np.ndarray, bool]:
    """``shadowgeo.silhouette._successors`` (the k-th edge ending at a key,
    by edge index, goes on to the k-th edge starting there) for keys in
    blocks of ``span`` (a light's vertices: ``light * span + vertex``),
    each edge's two keys in one block, blocks rising with the edge index:
    one pass a block with a list of edges out of each vertex. False when the
    keys are not so (or the edges do not close): the caller then sorts."""
    count = len(starts)
    successor = np.empty(count, dtype=np.int64)
    head = np.full(span, -1, dtype=np.int64)
    tail = np.empty(span, dtype=np.int64)
    following = np.full(count, -1, dtype=np.int64)
    first = 0
    block = -1
    while first < count:
        if starts[first] < 0 or starts[first] // span <= block:
            return successor, False
        block = starts[first] // span
        base = block * span
        last = first
        while last < count and starts[last] // span == block:
            last += 1
        for edge in range(first, last):  # the edges out of each vertex, in order
            vertex = starts[edge] - base
            if head[vertex] < 0:
                head[vertex] = edge
            else:
                following[tail[vertex]] = edge
            tail[vertex] = edge
        closed = True
        for edge in range(first, last):  # the k-th in goes on to the k-th out
            end = ends[edge] - base
            if end < 0 or end >= span or head[end] < 0:
                closed = False
                break
            successor[edge] = head[end]
            head[end] = following[head[end]]
        for edge in range(first, last):
            vertex = starts[edge] - base
            if head[vertex] >= 0:
                closed = False
            head[vertex] = -1
        if not closed:
            return successor, False
        first = last
    return successor, True


# -- the area of a union of convex pieces, face by face ---------------------------------------
# The union's boundary is the parts of the pieces' edges no other piece covers;
# each part t0..t1 of an edge a->b adds (t1 - t0) cross(a, b) / 2. A repeated
# edge counts for its lowest piece only, an edge two pieces share from either
# side for neither. Shared edges of pieces clipped from different caster
# triangles differ in their last bits: collinearity, a repeated corner and the
# box test each take the slack ``eps`` (a length).


@nb.njit(cache=True)
def _covered(
    ax: float,
    ay: float,
    bx: float,
    by: float,
    i: int,
    flat: np.ndarray,
    counts: np.ndarray,
    j: int,
    eps: float,
) -> tuple[float, float]:
    """The parameter range (t0, t1) of the segment a->b of polygon i that
    lies inside polygon j (empty: t0 >= t1)."""
    t0, t1 = 0.0, 1.0
    n = counts[j]
    for k in range(n):
        cx, cy = flat[j, k, 0], flat[j, k, 1]
        dx, dy = flat[j, (k + 1) % n, 0], flat[j, (k + 1) % n, 1]
        ex, ey = dx - cx, dy - cy
        length = np.sqrt(ex * ex + ey * ey)
        if length <= eps:  # a corner repeated, to rounding: its direction is noise
            continue
        s0 = ex * (ay - cy) - ey * (ax - cx)
        s1 = ex * (by - cy) - ey * (bx - cx)
        near = eps * length
        if abs(s0) <= near and abs(s1) <= near:  # on this edge's line
            same = ex * (bx - ax) + ey * (by - ay) > 0.0
            if same and j < i:
                continue  # inside for this constraint
            if not same:
                continue
            return 1.0, 0.0
        if s0 <= 0.0 and s1 <= 0.0:
            return 1.0, 0.0
        if s0 <= 0.0:  # enters at s = 0
            t0 = max(t0, s0 / (s0 - s1))
        elif s1 <= 0.0:
            t1 = min(t1, s0 / (s0 - s1))
        if t0 >= t1:
            return 1.0, 0.0
    return t0, t1


@nb.njit(cache=True)
def _uncovered(starts: np.ndarray, stops: np.ndarray, m: int) -> float:
    """The length of [0, 1] outside the ``m`` ranges ``starts[i]..stops[i]``."""
    if m == 0:
        return 1.0
    order = np.argsort(starts[:m])
    reach = 0.0
    free = 0.0
    for o in order:
        if starts[o] > reach:
            free += starts[o] - reach
        reach = max(reach, stops[o])
    if reach < 1.0:
        free += 1.0 - reach
    return free


@nb.njit(cache=True)
def _face_area(
    flat: np.ndarray,
    counts: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    first: int,
    last: int,
    eps: float,
    thin: np.ndarray,
) -> float:
    """The area of the union of the pieces ``first`` to ``last`` of ``flat``
    (those ``thin`` left out)."""
    total = 0.0
    starts = np.empty(last - first)
    stops = np.empty(last - first)
    for i in range(first, last):
        if thin[i]:
            continue
        n = counts[i]
        for k in range(n):
            ax, ay = flat[i, k, 0], flat[i, k, 1]
            bx, by = flat[i, (k + 1) % n, 0], flat[i, (k + 1) % n, 1]
            if ax == bx and ay == by:
                continue
            m = 0
            sx0, sx1 = min(ax, bx), max(ax, bx)
            sy0, sy1 = min(ay, by), max(ay, by)
            for j in range(first, last):
                if j == i or thin[j]:
                    continue
                if (
                    sx1 + eps < low[j, 0]
                    or sx0 - eps > high[j, 0]
                    or sy1 + eps < low[j, 1]
                    or sy0 - eps > high[j, 1]
                ):
                    continue
                t0, t1 = _covered(ax, ay, bx, by, i, flat, counts, j, eps)
                if t0 < t1:
                    starts[m] = t0
                    stops[m] = t1
                    m += 1
            total += _uncovered(starts, stops, m) * (ax * by - bx * ay)
    return 0.5 * total


@nb.njit(cache=True)
def union_areas(
    flat: np.ndarray, counts: np.ndarray, start: np.ndarray, count: np.ndarray, eps: float
) -> np.ndarray:
    """(f,) the area of the union of the convex counter-clockwise polygons
    ``flat[start[f]:start[f] + count[f]]`` ((n, k, 2), ``counts`` corners
    each) of each face ``f``. A polygon no wider than about ``eps`` (its area
    at most ``eps`` times its perimeter: a sliver, or corners repeated) is
    left out: its edges, one way and back along a line or of no length, would
    cover the others' edges it meets, not an area."""
    low = np.empty((flat.shape[0], 2))
    high = np.empty((flat.shape[0], 2))
    thin = np.zeros(flat.shape[0], dtype=np.bool_)
    for i in range(flat.shape[0]):
        n = counts[i]
        low[i, 0] = flat[i, :n, 0].min()
        low[i, 1] = flat[i, :n, 1].min()
        high[i, 0] = flat[i, :n, 0].max()
        high[i, 1] = flat[i, :n, 1].max()
        twice, perimeter = 0.0, 0.0
        for k in range(n):
            ax, ay = flat[i, k, 0], flat[i, k, 1]
            bx, by = flat[i, (k + 1) % n, 0], flat[i, (k + 1) % n, 1]
            twice += ax * by - bx * ay
            perimeter += np.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
        thin[i] = 0.5 * twice <= eps * perimeter
    out = np.zeros(len(start))
    for f in range(len(start)):
        out[f] = _face_area(flat, counts, low, high, start[f], start[f] + count[f], eps, thin)
    return out


@nb.njit(cache=True)
def _before(x: np.ndarray, y: np.ndarray, a: int, b: int) -> bool:
    """Whether point ``a`` comes before ``b`` in (x, y) order."""
    return bool(x[a] < x[b] or (x[a] == x[b] and y[a] < y[b]))


@nb.njit(cache=True)
def _turn(x: np.ndarray, y: np.ndarray, o: int, a: int, b: int) -> float:
    """Twice the signed area of the triangle o, a, b (positive: a left turn)."""
    return float((x[a] - x[o]) * (y[b] - y[o]) - (y[a] - y[o]) * (x[b] - x[o]))


@nb.njit(cache=True)
def _hull(x: np.ndarray, y: np.ndarray, n: int, order: np.ndarray, chain: np.ndarray) -> int:
    """The convex hull of the first ``n`` points (x, y), counter-clockwise
    and without collinear corners, into ``chain`` (Andrew's monotone chain):
    its corner count (below 3 for collinear points); ``order`` is room for
    the sort."""
    for i in range(n):
        order[i] = i
    for i in range(1, n):  # insertion sort: a body has a few dozen corners
        item, j = order[i], i - 1
        while j >= 0 and _before(x, y, item, order[j]):
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = item
    k = 0
    for i in range(n):  # lower chain
        while k >= 2 and _turn(x, y, chain[k - 2], chain[k - 1], order[i]) <= 0.0:
            k -= 1
        chain[k] = order[i]
        k += 1
    lower = k + 1
    for i in range(n - 2, -1, -1):  # upper chain
        while k >= lower and _turn(x, y, chain[k - 2], chain[k - 1], order[i]) <= 0.0:
            k -= 1
        chain[k] = order[i]
        k += 1
    return k - 1 if k - 1 >= 3 else 0  # the last repeats the first


@nb.njit(cache=True)
def _height(p: np.ndarray, origin: np.ndarray, normal: np.ndarray) -> float:
    """The height of point ``p`` above the plane through ``origin`` with unit ``normal``."""
    return float(
        (p[0] - origin[0]) * normal[0]
        + (p[1] - origin[1]) * normal[1]
        + (p[2] - origin[2]) * normal[2]
    )


@nb.njit(cache=True)
def _cut_body(
    points: np.ndarray,
    vertices: np.ndarray,
    edges: np.ndarray,
    normal: np.ndarray,
    origin: np.ndarray,
    eps: float,
    found: np.ndarray,
    heights: np.ndarray,
) -> int:
    """The corners of a convex body (its ``vertices`` and ``edges``, indices
    into ``points``) ahead of the plane through ``origin`` with unit
    ``normal``, into ``found``: all of them when none lies more than ``eps``
    behind it, else those on or ahead of it and where its edges cross it;
    none when no corner lies more than ``eps`` ahead. Returns their count;
    ``heights`` is room for the vertices' heights."""
    low, high = np.inf, -np.inf
    for k in range(len(vertices)):
        h = _height(points[vertices[k]], origin, normal)
        heights[k] = h
        low, high = min(low, h), max(high, h)
    if high <= eps:
        return 0
    c = 0
    for k in range(len(vertices)):
        if low >= -eps or heights[k] >= 0.0:
            for d in range(3):
                found[c, d] = points[vertices[k], d]
            c += 1
    if low >= -eps:
        return c
    for k in range(len(edges)):
        a, b = points[edges[k, 0]], points[edges[k, 1]]
        ha, hb = _height(a, origin, normal), _height(b, origin, normal)
        if (ha > 0.0 and hb < 0.0) or (ha < 0.0 and hb > 0.0):
            t = ha / (ha - hb)
            for d in range(3):
                found[c, d] = a[d] + (b[d] - a[d]) * t
            c += 1
    return c


@nb.njit(cache=True)
def _holds(x: np.ndarray, y: np.ndarray, chain: np.ndarray, k: int, px: float, py: float) -> bool:
    """Whether the point (px, py) lies in the counter-clockwise ring
    ``chain[:k]`` of the points (x, y), on its edge included (to rounding:
    a point this test misses is measured the exact way)."""
    for j in range(k):
        a, b = chain[j], chain[(j + 1) % k]
        if (x[b] - x[a]) * (py - y[a]) - (y[b] - y[a]) * (px - x[a]) < 0.0:
            return False
    return True


@nb.njit(cache=True)
def _clip_to_triangle(polygon: np.ndarray, n: int, triangle: np.ndarray, spare: np.ndarray) -> int:
    """The convex ``polygon[:n]`` (2-D, counter-clockwise) cut to the
    counter-clockwise ``triangle`` (3, 2) (Sutherland-Hodgman, a pass an
    edge, back and forth between ``polygon`` and ``spare``, each with room
    for ``n + 3`` corners): the result's corner count, its corners in
    ``spare`` (after the third pass; 0 when less than three are left)."""
    source, target = polygon, spare
    for e in range(3):
        ax, ay = triangle[e, 0], triangle[e, 1]
        ex, ey = triangle[(e + 1) % 3, 0] - ax, triangle[(e + 1) % 3, 1] - ay
        m = 0
        for j in range(n):
            px, py = source[j, 0], source[j, 1]
            qx, qy = source[(j + 1) % n, 0], source[(j + 1) % n, 1]
            sp = ex * (py - ay) - ey * (px - ax)
            sq = ex * (qy - ay) - ey * (qx - ax)
            if sp >= 0.0:
                target[m, 0], target[m, 1] = px, py
                m += 1
            if (sp >= 0.0) != (sq >= 0.0):
                t = sp / (sp - sq)
                target[m, 0], target[m, 1] = px + t * (qx - px), py + t * (qy - py)
                m += 1
        source, target = target, source
        n = m
        if n < 3:
            return 0
    return n


@nb.njit(cache=True)
def _face_triangle(frame: np.ndarray, triangle: np.ndarray) -> None:
    """A face's corners (``frame``: corners, normal, u, v, origin; see
    :func:`ring_pieces`) in its 2-D frame, counter-clockwise, into ``triangle``."""
    u, v, origin = frame[4], frame[5], frame[6]
    for c in range(3):
        qx, qy, qz = frame[c, 0] - origin[0], frame[c, 1] - origin[1], frame[c, 2] - origin[2]
        triangle[c, 0] = qx * u[0] + qy * u[1] + qz * u[2]
        triangle[c, 1] = qx * v[0] + qy * v[1] + qz * v[2]
    turn = (triangle[1, 0] - triangle[0, 0]) * (triangle[2, 1] - triangle[0, 1]) - (
        triangle[1, 1] - triangle[0, 1]
    ) * (triangle[2, 0] - triangle[0, 0])
    if turn < 0.0:  # wound against its normal
        for d in range(2):
            triangle[1, d], triangle[2, d] = triangle[2, d], triangle[1, d]


@nb.njit(cache=True)
def ring_pieces(
    points: np.ndarray,
    vertices: np.ndarray,
    vertex_starts: np.ndarray,
    edges: np.ndarray,
    edge_starts: np.ndarray,
    body: np.ndarray,
    face: np.ndarray,
    frames: np.ndarray,
    direction: np.ndarray,
    eps: float,
    offsets: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each convex body's shadow on each face it may shade, under a
    directional light travelling along ``direction``: for each pair ``i``
    (sorted by face), body ``body[i]`` (its vertices
    ``vertices[vertex_starts[b]:vertex_starts[b + 1]]`` and its edges
    likewise, indices into ``points``) cut to the part ahead of face
    ``face[i]``'s plane (see :func:`_cut_body`), projected along the light
    onto that plane, and the convex hull of the images cut to the face: a
    convex counter-clockwise polygon in the face's frame, its corners from
    ``offsets[i]`` on in the (offsets[-1], 2) result.

    ``frames`` (f, 7, 3) holds each face's three corners (either way round
    its normal), unit normal, in-plane axes u and v (``u x v`` = normal) and
    the origin of its 2-D frame (a point of its plane), all in ``points``'
    frame. ``offsets``: room for each pair's corners, its body's
    vertices and edges and three more.

    Also (m,) the corner counts (0: nothing with area, or not needed) and
    (m,) whether the hull holds the whole face (it is then wholly shadowed,
    and its face's later pairs are not measured)."""
    flat = np.zeros((offsets[-1], 2))
    counts = np.zeros(len(body), dtype=np.int64)
    covers = np.zeros(len(body), dtype=np.bool_)
    room = 3
    for i in range(len(body)):
        room = max(room, offsets[i + 1] - offsets[i])
    found = np.empty((room, 3))  # scratch, reused by every pair
    x, y, heights = np.empty(room), np.empty(room), np.empty(room)
    chain = np.empty(2 * room + 1, dtype=np.int64)
    order = np.empty(room, dtype=np.int64)
    polygon, spare = np.empty((room + 3, 2)), np.empty((room + 3, 2))
    triangle = np.empty((3, 2))
    done = -1  # a face already wholly shadowed
    current = -1  # the face whose triangle and cosine are set
    cosine = 1.0
    for i in range(len(body)):
        f = face[i]
        if f == done:
            continue
        b = body[i]
        corner, normal, u, v, origin = (
            frames[f, 0],
            frames[f, 3],
            frames[f, 4],
            frames[f, 5],
            frames[f, 6],
        )
        if f != current:  # the face's triangle in its frame, counter-clockwise, once a face
            cosine = -(
                normal[0] * direction[0] + normal[1] * direction[1] + normal[2] * direction[2]
            )
            _face_triangle(frames[f], triangle)
            current = f
        mine = vertices[vertex_starts[b] : vertex_starts[b + 1]]
        lines = edges[edge_starts[b] : edge_starts[b + 1]]
        n = _cut_body(points, mine, lines, normal, corner, eps, found, heights)
        if n < 3:
            continue
        for j in range(n):  # along the light onto the face's plane, in its frame (scalars:
            # a small array a corner was most of the time)
            qx, qy, qz = found[j, 0] - origin[0], found[j, 1] - origin[1], found[j, 2] - origin[2]
            along = (qx * normal[0] + qy * normal[1] + qz * normal[2]) / cosine
            qx, qy, qz = (
                qx + along * direction[0],
                qy + along * direction[1],
                qz + along * direction[2],
            )
            x[j] = qx * u[0] + qy * u[1] + qz * u[2]
            y[j] = qx * v[0] + qy * v[1] + qz * v[2]
        k = _hull(x, y, n, order, chain)
        if k == 0:
            continue
        whole = True
        for c in range(3):
            whole = whole and _holds(x, y, chain, k, triangle[c, 0], triangle[c, 1])
        if whole:
            covers[i] = True
            done = f
            continue
        for j in range(k):
            polygon[j, 0], polygon[j, 1] = x[chain[j]], y[chain[j]]
        m = _clip_to_triangle(polygon, k, triangle, spare)
        if m < 3:
            continue
        flat[offsets[i] : offsets[i] + m] = spare[:m]
        counts[i] = m
    return flat, counts, covers
