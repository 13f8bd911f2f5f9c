"""One simple polygon, certified and triangulated by a sweep in O(n log n).

manifold3d's ear clipping and Clipper2's sweep both take time that grows
with the square of a polygon's corners when many of its edges lie across
every sweep line (a comb of 12,000 teeth: 48,000 corners, 85 s to convert).
:func:`simple_triangles` sweeps the polygon once, from its top corner down:

1. the edges the sweep line crosses are kept in order along it (a list,
   searched by bisection), and every two that become neighbours are tested
   for a crossing, as Shamos and Hoey showed suffices to find one if any
   exists: no crossing found, and the polygon is simple;
2. in the same pass, diagonals from each split and merge corner cut the
   polygon into pieces monotone along the sweep (de Berg et al.,
   *Computational Geometry*, chapter 3);
3. each piece is cut into triangles by the stack walk for monotone
   polygons.

Every orientation is certified against float64's rounding
(:func:`shadowgeo.orientation.turns`' margins, for coordinates within
``MAX_COORDINATE``; the loop is first scaled there by a power of two): one
that rounding could decide (touching edges, three corners on a line that a
triangle would need) gives None, and the caller takes the general way. The
result is checked once more at the end: ``k - 2`` triangles, each certainly
counter-clockwise, whose areas add up to the loop's.
"""

from __future__ import annotations

import math

import numpy as np

from .limits import RELATIVE_ROUNDING
from .orientation import MAX_COORDINATE, turn_sign, turns

__all__ = ["simple_triangles"]

# Corner kinds along the sweep (top to bottom).
_START, _SPLIT, _END, _MERGE, _LEFT, _RIGHT = range(6)


class _Uncertain(Exception):
    """A sign or an order the sweep needs is within rounding: not certified."""


def simple_triangles(loop: np.ndarray, triangles: bool = True) -> tuple[bool, np.ndarray | None]:
    """Whether the counter-clockwise (k, 2) ``loop`` is certainly simple, and
    if so (and ``triangles``) its ``(k - 2, 3)`` counter-clockwise triangles
    of its own corners (None when a triangle could not be certified).

    Returns ``(False, None)`` when the loop is not certainly simple: it
    crosses or touches itself, runs clockwise, or a sign the test needs is
    within rounding of zero.
    """
    loop = np.asarray(loop, dtype=np.float64)
    n = len(loop)
    if n < 3 or not np.all(np.isfinite(loop)):
        return False, None
    middle = 0.5 * (loop.min(axis=0) + loop.max(axis=0))
    extent = float(np.abs(loop - middle).max())
    if not extent > 0:
        return False, None
    # a power of two: the scaled loop is the loop (no rounding), its middle
    # moved to the origin first (a difference: rounded once, 1e-16 of the size)
    local = np.ldexp(loop - middle, int(math.floor(math.log2(MAX_COORDINATE / extent))))
    if not _doubled_area(local) > 0:
        return False, None  # clockwise (or no area): the sweep takes counter-clockwise loops
    try:
        sweep = _Sweep(local)
        sweep.run()
    except _Uncertain:
        return False, None
    if sweep.crossed:
        return False, None
    if not triangles:
        return True, None
    try:
        found = sweep.triangles()
    except _Uncertain:
        return True, None
    if len(found) != n - 2 or not _tiles(local, found):
        return True, None
    return True, found


class _Sweep:
    """The sweep over one loop (coordinates within +-MAX_COORDINATE)."""

    def __init__(self, points: np.ndarray) -> None:
        self.n = len(points)
        self.xs: list[float] = points[:, 0].tolist()
        self.ys: list[float] = points[:, 1].tolist()
        # sweep order: down in y, then right in x (ties broken as if turned)
        order = np.lexsort((points[:, 0], -points[:, 1]))
        ordered = points[order]
        if np.any(np.all(ordered[1:] == ordered[:-1], axis=1)):
            raise _Uncertain  # a corner repeated: the loop touches itself
        self.order: list[int] = order.tolist()
        rank = np.empty(self.n, dtype=np.int64)
        rank[order] = np.arange(self.n)
        self.rank: list[int] = rank.tolist()
        following = np.roll(np.arange(self.n), -1)
        upper = np.where(rank < rank[following], np.arange(self.n), following)
        lower = np.where(rank < rank[following], following, np.arange(self.n))
        self.upper: list[int] = upper.tolist()  # each edge's corners, top and bottom
        self.lower: list[int] = lower.tolist()
        self.west: list[float] = np.minimum(points[upper, 0], points[lower, 0]).tolist()
        self.east: list[float] = np.maximum(points[upper, 0], points[lower, 0]).tolist()
        self.status: list[int] = []  # edges across the sweep line, left to right
        self.helper: dict[int, int] = {}
        self.kind: list[int] = [0] * self.n
        self.diagonals: list[tuple[int, int]] = []
        self.crossed = False

    # -- certified signs ------------------------------------------------------

    def orient(self, i: int, j: int, x: float, y: float) -> int:
        """+1 when ``i -> j -> (x, y)`` certainly turns left, -1 right;
        raises :class:`_Uncertain` when rounding could decide it."""
        xs, ys = self.xs, self.ys
        sign = turn_sign(xs[j] - xs[i], ys[j] - ys[i], x - xs[i], y - ys[i])
        if sign == 0:
            raise _Uncertain
        return sign

    def turn(self, i: int, j: int, k: int) -> int:
        return self.orient(i, j, self.xs[k], self.ys[k])

    # -- the edges along the sweep line --------------------------------------

    def ends(self, edge: int) -> tuple[int, int]:
        """(upper, lower) corner of edge ``edge`` (corner ``edge`` to the next)."""
        return self.upper[edge], self.lower[edge]

    def left_of_point(self, edge: int, x: float, y: float) -> bool:
        """Whether ``edge`` passes left of the point (x, y) at its height: by
        x alone when the point is past either end's x, else by a certified
        turn (the point right of a downward edge: a left turn from its top
        to its bottom)."""
        if x > self.east[edge]:
            return True
        if x < self.west[edge]:
            return False
        return self.orient(self.upper[edge], self.lower[edge], x, y) > 0

    def position(self, corner: int) -> int:
        """How many edges of the status lie left of ``corner`` (none of them
        ends at it)."""
        status, lo, hi = self.status, 0, len(self.status)
        x, y = self.xs[corner], self.ys[corner]
        while lo < hi:
            mid = (lo + hi) // 2
            if self.left_of_point(status[mid], x, y):
                lo = mid + 1
            else:
                hi = mid
        return lo

    def check(self, at: int) -> None:
        """Test the status's neighbours ``at - 1`` and ``at`` for a crossing."""
        if 0 < at < len(self.status) and self.cross(self.status[at - 1], self.status[at]):
            self.crossed = True

    def cross(self, e: int, f: int) -> bool:
        n = self.n
        if (e + 1) % n == f or (f + 1) % n == e:
            return False  # neighbours round the loop: they meet at their corner, turning
        a, b = e, (e + 1) % n
        c, d = f, (f + 1) % n
        xs, ys = self.xs, self.ys
        # apart along x or y (exact comparisons): no crossing, whatever the
        # orientations (edges in line, as a comb's teeth's feet are)
        if max(xs[a], xs[b]) < min(xs[c], xs[d]) or max(xs[c], xs[d]) < min(xs[a], xs[b]):
            return False
        if max(ys[a], ys[b]) < min(ys[c], ys[d]) or max(ys[c], ys[d]) < min(ys[a], ys[b]):
            return False
        one = self.turn(a, b, c) != self.turn(a, b, d)
        return one and self.turn(c, d, a) != self.turn(c, d, b)

    def insert(self, edges: list[int], corner: int) -> None:
        """Insert the edges that start at ``corner`` (one or two, left to right)."""
        at = self.position(corner)
        self.status[at:at] = edges
        self.check(at)
        self.check(at + len(edges))

    # -- the pass -------------------------------------------------------------

    def run(self) -> None:
        n, rank = self.n, self.rank
        handlers = (self.start, self.split, self.end, self.merge, self.left, self.right)
        for corner in self.order:
            before, after = (corner - 1) % n, (corner + 1) % n
            below_before, below_after = rank[before] > rank[corner], rank[after] > rank[corner]
            if below_before == below_after:  # a top or a bottom: convex or not
                convex = self.turn(before, corner, after) > 0
                if below_before:
                    kind = _START if convex else _SPLIT
                else:
                    kind = _END if convex else _MERGE
            else:  # on a chain: its turn does not matter (three corners may be in line)
                kind = _LEFT if not below_before else _RIGHT
            self.kind[corner] = kind
            handlers[kind](corner)
            if self.crossed:
                return

    def start(self, v: int) -> None:
        previous = (v - 1) % self.n
        # e_v goes down the left, the edge before it down the right
        self.insert([v, previous], v)
        self.helper[v] = v

    def split(self, v: int) -> None:
        previous = (v - 1) % self.n
        at = self.position(v)
        if at == 0:
            raise _Uncertain  # no edge left of a split corner: not a simple ccw loop
        left = self.status[at - 1]
        if left not in self.helper:
            raise _Uncertain
        self.diagonals.append((v, self.helper[left]))
        self.helper[left] = v
        self.status[at:at] = [previous, v]
        self.check(at)
        self.check(at + 2)
        self.helper[v] = v

    def end(self, v: int) -> None:
        previous = (v - 1) % self.n
        self.close(previous, v)
        self.drop(previous)
        self.drop(v)

    def merge(self, v: int) -> None:
        previous = (v - 1) % self.n
        self.close(previous, v)
        self.drop(previous)
        self.drop(v)
        self.left_of(v)

    def left(self, v: int) -> None:  # going down the left: the inside to the right
        previous = (v - 1) % self.n
        self.close(previous, v)
        self.drop(previous)
        self.insert([v], v)
        self.helper[v] = v

    def right(self, v: int) -> None:  # going up the right: the inside to the left
        self.drop(v)
        self.left_of(v)
        self.insert([(v - 1) % self.n], v)

    def close(self, edge: int, v: int) -> None:
        """The left edge ``edge`` ends at ``v``: a diagonal to its helper when
        that is a merge corner."""
        if edge not in self.helper:
            raise _Uncertain
        helper = self.helper.pop(edge)
        if self.kind[helper] == _MERGE:
            self.diagonals.append((v, helper))

    def left_of(self, v: int) -> None:
        """The edge just left of ``v`` takes ``v`` as its helper (a diagonal
        first when its helper was a merge corner)."""
        at = self.position(v)
        if at == 0:
            raise _Uncertain
        left = self.status[at - 1]
        if left not in self.helper:
            raise _Uncertain
        if self.kind[self.helper[left]] == _MERGE:
            self.diagonals.append((v, self.helper[left]))
        self.helper[left] = v

    def drop(self, edge: int) -> None:
        """Take ``edge`` out of the status and test its two neighbours."""
        index = self.find(edge)
        del self.status[index]
        self.check(index)

    def find(self, edge: int) -> int:
        """Where ``edge``, which ends at the corner being swept, lies in the
        status: bisection by that corner, whose edges lie together."""
        _, corner = self.ends(edge)
        status, lo, hi = self.status, 0, len(self.status)
        x, y = self.xs[corner], self.ys[corner]
        n = self.n
        while lo < hi:
            mid = (lo + hi) // 2
            other = status[mid]
            if other == edge:
                return mid
            if other == corner or (other + 1) % n == corner:  # the corner's other edge
                for near in (mid - 1, mid + 1):
                    if 0 <= near < len(status) and status[near] == edge:
                        return near
                raise _Uncertain
            if self.left_of_point(other, x, y):
                lo = mid + 1
            else:
                hi = mid
        raise _Uncertain  # not where the order says: the order is not certain

    # -- the pieces and their triangles --------------------------------------

    def triangles(self) -> np.ndarray:
        n, xs, ys = self.n, self.xs, self.ys
        around: list[list[int]] = [[(v - 1) % n, (v + 1) % n] for v in range(n)]
        for a, b in self.diagonals:
            around[a].append(b)
            around[b].append(a)
        for v, ring in enumerate(around):
            if len(ring) > 2:  # counter-clockwise round v
                x, y = xs[v], ys[v]
                ring.sort(key=lambda w: math.atan2(ys[w] - y, xs[w] - x))
        used: set[tuple[int, int]] = set()
        result: list[tuple[int, int, int]] = []
        starts = [(v, (v + 1) % n) for v in range(n)]
        starts += self.diagonals + [(b, a) for a, b in self.diagonals]
        for first in starts:
            if first in used:
                continue
            face = []
            u, w = first
            while (u, w) not in used:
                used.add((u, w))
                face.append(u)
                ring = around[w]
                if len(ring) == 2:
                    after = ring[0] if ring[1] == u else ring[1]
                else:  # the neighbour just clockwise of u round w
                    after = ring[ring.index(u) - 1]
                u, w = w, after
            result.extend(self.monotone(face))
        return np.array(result, dtype=np.int64).reshape(-1, 3)

    def monotone(self, face: list[int]) -> list[tuple[int, int, int]]:
        """Triangles of one counter-clockwise piece, monotone along the sweep."""
        if len(face) < 3:
            raise _Uncertain
        rank = self.rank
        top = min(range(len(face)), key=lambda k: rank[face[k]])
        face = face[top:] + face[:top]
        bottom = max(range(len(face)), key=lambda k: rank[face[k]])
        # counter-clockwise from the top runs down the left chain
        chain = {v: 0 for v in face[1:bottom]} | {v: 1 for v in face[bottom + 1 :]}
        chain[face[0]] = chain[face[bottom]] = 2
        ordered = sorted(face, key=rank.__getitem__)
        triangles: list[tuple[int, int, int]] = []
        stack = [ordered[0], ordered[1]]
        for j in range(2, len(ordered) - 1):
            v = ordered[j]
            if chain[v] != chain[stack[-1]]:
                while len(stack) > 1:
                    s = stack.pop()
                    triangles.append(self.oriented(v, s, stack[-1]))
                stack = [ordered[j - 1], v]
            else:
                last = stack.pop()
                while stack and self.inside(v, last, stack[-1], chain[v]):
                    s = stack.pop()
                    triangles.append(self.oriented(v, last, s))
                    last = s
                stack.extend((last, v))
        v = ordered[-1]
        while len(stack) > 1:
            s = stack.pop()
            triangles.append(self.oriented(v, s, stack[-1]))
        return triangles

    def inside(self, v: int, last: int, s: int, side: int) -> bool:
        """Whether the diagonal from ``v`` to ``s`` (above ``last`` on ``v``'s
        chain) certainly lies inside: ``last`` bulges outwards past it. Not
        when rounding could decide it: ``last`` then stays, as a reflex
        corner would."""
        try:
            turn = self.turn(s, last, v)
        except _Uncertain:
            return False
        return turn > 0 if side == 0 else turn < 0

    def oriented(self, a: int, b: int, c: int) -> tuple[int, int, int]:
        return (a, b, c) if self.turn(a, b, c) > 0 else (a, c, b)


def _tiles(points: np.ndarray, triangles: np.ndarray) -> bool:
    """Every triangle certainly counter-clockwise and their areas adding up
    to the loop's (to rounding)."""
    a, b, c = points[triangles[:, 0]], points[triangles[:, 1]], points[triangles[:, 2]]
    sign, cross = turns(a, b, c)
    if not np.all(sign == 1):
        return False
    doubled = _doubled_area(points)
    return abs(float(cross.sum()) - doubled) <= RELATIVE_ROUNDING * abs(doubled)


def _doubled_area(points: np.ndarray) -> float:
    """Twice the loop's signed area (shoelace), positive counter-clockwise."""
    x, y = points[:, 0], points[:, 1]
    return float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
