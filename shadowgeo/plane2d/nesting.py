"""Nesting: the loops of a region without crossings grouped into parts
``[outer, hole, ...]``, each hole in the smallest outer loop around it
(:func:`nest`, :class:`FlatParts`), and a Clipper2 region's parts
(:func:`components`) and area (:func:`parts_area`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from manifold3d import CrossSection

from ..topology import loop_rings
from .predicates import signed_areas

__all__ = ["FlatParts", "components", "nest", "nest_flat", "parts_area", "region_loops"]


# Candidate edges one batch of nest's point-in-loop tests visits at most.
_NEST_EDGES = 4_000_000


def region_loops(region: CrossSection) -> list[np.ndarray]:
    """The loops of ``region`` (outer loops counter-clockwise, holes
    clockwise) as (k, 2) float64 arrays, dropping any of fewer than three
    points."""
    loops = [np.asarray(loop, dtype=np.float64) for loop in region.to_polygons()]
    return [loop for loop in loops if len(loop) >= 3]


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
