"""Exact level sets of a cover: where each point is covered by exactly ``m`` regions.

Given ``count`` regions (each a set of loops without crossings: outer loops
counter-clockwise, holes clockwise, so the winding number of a point is 1
inside and 0 outside) and a window, :func:`cover_levels` cuts the window into
polygons on which the number of covering regions is constant.

How: the winding number of a point over *all* the regions' loops is the number
of regions covering it. Adding ``m - 1`` clockwise copies of a rectangle that
holds everything lowers every winding number by ``m - 1``, so one Clipper2
union with the positive fill rule gives the points covered at least ``m``
times, exactly; level ``m`` is the difference of two such unions.

Why it is tiled: each level costs one union of every loop, and Clipper2's
sweep grows faster than linearly with the number of edges it holds at once.
The window is split in halves (a k-d tree) until each tile holds a few
thousand vertices; the loops are cut at each split by Sutherland-Hodgman in
one numpy pass. That cut keeps every winding number strictly inside the half
(the part of a loop beyond the line is replaced by a walk along the line, and
the closed curves this changes lie on the far side), so each tile's levels are
exact. A tile holding no loop of some regions needs no level above the number
it does hold. The level polygons come back cut along the tile edges: pieces of
one level do not overlap, and together they are its exact region.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from manifold3d import CrossSection
from numpy.typing import NDArray

from .plane2d import nest, signed_areas, unite
from .topology import loop_rings

__all__ = [
    "MAX_DEPTH",
    "Parts",
    "TILE_VERTICES",
    "cover_bands",
    "cover_level_areas",
    "cover_levels",
]

Parts = list[list[NDArray[np.float64]]]

# A tile holding more loop vertices than this is split in two.
TILE_VERTICES = 2000
# Splits stop at this depth whatever the tile holds (a single complex loop
# gains nothing from more cuts).
MAX_DEPTH = 16


@dataclass(frozen=True)
class _Loops:
    """Loops packed flat: ``points`` (n, 2), loop ``lengths`` (k,) and the
    region each loop belongs to, ``owner`` (k,)."""

    points: NDArray[np.float64]
    lengths: NDArray[np.int64]
    owner: NDArray[np.int64]

    @classmethod
    def pack(cls, regions: list[list[NDArray[np.float64]]]) -> _Loops:
        loops = [loop for region in regions for loop in region if len(loop) >= 3]
        owner = [index for index, region in enumerate(regions) for loop in region if len(loop) >= 3]
        if not loops:
            return cls(np.zeros((0, 2)), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
        return cls(
            np.concatenate(loops).astype(np.float64),
            np.array([len(loop) for loop in loops], dtype=np.int64),
            np.array(owner, dtype=np.int64),
        )

    def unpack(self) -> list[NDArray[np.float64]]:
        return np.split(self.points, np.cumsum(self.lengths)[:-1]) if len(self.lengths) else []

    def clip(self, axis: int, value: float, below: bool) -> _Loops:
        """Sutherland-Hodgman against the half-plane ``x[axis] <= value``
        (``below``) or ``>= value``, every loop at once."""
        if not len(self.lengths):
            return self
        points = self.points
        starts, following = loop_rings(self.lengths)
        coordinate = points[:, axis]
        inside = coordinate <= value if below else coordinate >= value
        crossing = inside != inside[following]
        # where the edge i -> following[i] meets the line, the same point in both halves
        start, end = points[crossing], points[following[crossing]]
        t = (value - start[:, axis]) / (end[:, axis] - start[:, axis])
        cut = start + t[:, None] * (end - start)
        cut[:, axis] = value
        emitted = inside.astype(np.int64) + crossing
        out = np.empty((int(emitted.sum()), 2))
        first = np.cumsum(emitted) - emitted  # where vertex i's output begins
        out[first[inside]] = points[inside]
        out[first[crossing] + inside[crossing]] = cut
        lengths = np.add.reduceat(emitted, starts)
        kept = lengths >= 3  # a loop meeting the half keeps a vertex and two cuts
        if kept.all():
            return _Loops(out, lengths, self.owner)
        keep_points = np.repeat(kept, lengths)
        return _Loops(out[keep_points], lengths[kept], self.owner[kept])


def _rectangle(low: NDArray[np.float64], high: NDArray[np.float64]) -> NDArray[np.float64]:
    """Counter-clockwise corners of the box [low, high]."""
    return np.array([[low[0], low[1]], [high[0], low[1]], [high[0], high[1]], [low[0], high[1]]])


def _tiles(
    loops: _Loops, low: NDArray[np.float64], high: NDArray[np.float64], tile_vertices: int
) -> list[tuple[NDArray[np.float64], NDArray[np.float64], _Loops]]:
    """The window [low, high] split in halves until each tile holds at most
    ``tile_vertices`` vertices, with each tile's loops cut to it; in a fixed
    order (depth first, low half first)."""
    tiles = []
    stack = [(low, high, loops, 0)]
    while stack:
        low, high, here, depth = stack.pop()
        if len(here.points) <= tile_vertices or depth >= MAX_DEPTH:
            tiles.append((low, high, here))
            continue
        axis = int(np.argmax(high - low))
        middle = 0.5 * (low[axis] + high[axis])
        upper_low, lower_high = low.copy(), high.copy()
        upper_low[axis] = lower_high[axis] = middle
        stack.append((upper_low, high, here.clip(axis, middle, below=False), depth + 1))
        stack.append((low, lower_high, here.clip(axis, middle, below=True), depth + 1))
    return tiles


def cover_levels(
    regions: list[list[NDArray[np.float64]]],
    window: CrossSection,
    *,
    tile_vertices: int = TILE_VERTICES,
) -> dict[int, Parts]:
    """The parts of ``window`` covered by exactly ``m`` of ``regions``.

    Parameters
    ----------
    regions : list of list of (k, 2) float64
        Each region as its loops without crossings (outer loops
        counter-clockwise, holes clockwise), in Clipper2's working range.
    window : CrossSection
        The area to cut into levels.
    tile_vertices : int
        Tiles are split until they hold at most this many loop vertices.

    Returns
    -------
    dict[int, list of [outer, hole, ...]]
        For each ``m`` with area, the parts covered by exactly ``m`` regions
        (outer loops counter-clockwise, holes clockwise), cut along the tile
        edges. The levels tile the window: they do not overlap and their
        areas add up to the window's.

    Examples
    --------
    Two unit squares overlapping by half, in a 3 x 1 window:

    >>> import numpy as np
    >>> square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    >>> window = CrossSection([np.array([[0, 0], [3, 0], [3, 1], [0, 1]], dtype=float)])
    >>> levels = cover_levels([[square], [square + [0.5, 0]]], window)
    >>> {m: sum(CrossSection(p).area() for p in parts) for m, parts in sorted(levels.items())}
    {0: 1.5, 1: 1.0, 2: 0.5}
    """
    levels: dict[int, Parts] = {}
    for tile, whole, winding in _window_tiles(regions, window, tile_vertices):
        for m, parts in _tile_levels(tile, whole, winding).items():
            levels.setdefault(m, []).extend(parts)
    return dict(sorted(levels.items()))


def cover_bands(
    regions: list[list[NDArray[np.float64]]],
    window: CrossSection,
    thresholds: list[int],
    *,
    tile_vertices: int = TILE_VERTICES,
) -> list[Parts]:
    """The parts of ``window`` covered by at least ``thresholds[i]`` of
    ``regions`` and fewer than ``thresholds[i + 1]`` (the last: no upper
    limit), for increasing ``thresholds`` of at least 1: :func:`cover_levels`
    with one union per threshold instead of one per level, for many regions
    grouped into a few bands (a soft shadow's samples).

    >>> import numpy as np
    >>> square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    >>> window = CrossSection([np.array([[0, 0], [3, 0], [3, 1], [0, 1]], dtype=float)])
    >>> bands = cover_bands([[square], [square + [0.5, 0]], [square + [1, 0]]], window, [1, 2])
    >>> [round(sum(CrossSection(p).area() for p in parts), 9) for parts in bands]
    [1.0, 1.0]
    """
    if any(b <= a for a, b in zip(thresholds, thresholds[1:], strict=False)) or (
        thresholds and thresholds[0] < 1
    ):
        raise ValueError(f"thresholds must increase from 1 up, got {thresholds}")
    bands: list[Parts] = [[] for _ in thresholds]
    for tile, whole, winding in _window_tiles(regions, window, tile_vertices):
        regions_at = [winding.at_least(m, tile, whole) for m in thresholds]
        for index, region in enumerate(regions_at):
            if index + 1 < len(regions_at):
                region = region - regions_at[index + 1]
            if not region.is_empty():
                bands[index].extend(_parts(region))
    return bands


def cover_level_areas(
    regions: list[list[NDArray[np.float64]]],
    window: CrossSection,
    *,
    tile_vertices: int = TILE_VERTICES,
) -> dict[int, float]:
    """The area of ``window`` covered by exactly ``m`` of ``regions``, for
    each ``m`` with area: :func:`cover_levels`' areas without its polygons.

    The same unions, tile by tile, but each level's area is the difference
    of the areas covered at least ``m`` and ``m + 1`` times: no difference
    of regions is formed, no polygon is taken out of Clipper2 or nested.
    The areas agree with those of :func:`cover_levels`' polygons to
    rounding (a few units in the last place of the window's area).
    """
    areas: dict[int, float] = {}
    for tile, whole, winding in _window_tiles(regions, window, tile_vertices):
        previous, m = float(tile.area()), 0
        while previous > 0:
            upper = float(winding.at_least(m + 1, tile, whole).area())
            exactly = previous - upper
            if exactly > 0:
                areas[m] = areas.get(m, 0.0) + exactly
            previous, m = upper, m + 1
    return dict(sorted(areas.items()))


@dataclass(frozen=True)
class _Winding:
    """One tile's loops, cut to its rectangle, for the winding trick."""

    loops: list[NDArray[np.float64]]
    deepest: int  # no point is covered by more regions than hold loops here
    clockwise: NDArray[np.float64]  # a rectangle round the tile, clockwise

    @classmethod
    def of(cls, loops: _Loops, low: NDArray[np.float64], high: NDArray[np.float64]) -> _Winding:
        margin = 1.0 + float(np.max(high - low))
        clockwise = _rectangle(low - margin, high + margin)[::-1].copy()
        return cls(loops.unpack(), len(np.unique(loops.owner)), clockwise)

    def at_least(self, m: int, tile: CrossSection, whole: bool) -> CrossSection:
        """The part of ``tile`` covered by at least ``m`` regions (``whole``:
        the tile is the rectangle the loops are cut to)."""
        if m > self.deepest:
            return CrossSection()
        union = unite(self.loops + [self.clockwise] * (m - 1))
        return union if whole else union ^ tile


def _window_tiles(
    regions: list[list[NDArray[np.float64]]], window: CrossSection, tile_vertices: int
) -> Iterator[tuple[CrossSection, bool, _Winding]]:
    """Each non-empty tile of ``window`` (:func:`_tiles`), whether it is its
    whole rectangle, and its loops ready for the winding trick."""
    if window.is_empty():
        return
    bounds = window.bounds()  # (xmin, ymin, xmax, ymax)
    low, high = np.array(bounds[:2], dtype=np.float64), np.array(bounds[2:], dtype=np.float64)
    loops = _Loops.pack(regions)
    for axis in (0, 1):  # within the window's box, as every tile's loops are within the tile
        loops = loops.clip(axis, low[axis], below=False).clip(axis, high[axis], below=True)
    for tile_low, tile_high, tile_loops in _tiles(loops, low, high, tile_vertices):
        rectangle = unite([_rectangle(tile_low, tile_high)])
        tile = window ^ rectangle
        if tile.is_empty():
            continue
        # the loops are cut to the rectangle: a window covering it limits nothing
        whole = (rectangle - window).is_empty()
        yield tile, whole, _Winding.of(tile_loops, tile_low, tile_high)


def _tile_levels(tile: CrossSection, whole: bool, winding: _Winding) -> dict[int, Parts]:
    """The winding trick on one tile: ``tile`` covered exactly ``m`` times."""
    levels: dict[int, Parts] = {}
    previous, m = tile, 0
    while not previous.is_empty():
        upper = winding.at_least(m + 1, tile, whole)
        exactly = previous - upper
        if not exactly.is_empty():
            parts = _parts(exactly)
            if parts:
                levels[m] = parts
        previous, m = upper, m + 1
    return levels


def _parts(region: CrossSection) -> Parts:
    """``region`` as [outer, hole, ...] parts, as :func:`shadowgeo.plane2d.components`
    gives them; without holes each outer loop is a part of its own, no
    nesting needed."""
    loops = [loop for loop in region.to_polygons() if len(loop) >= 3]
    areas = signed_areas(loops)
    if np.any(areas == 0):  # a loop folded onto itself: no area, no part
        loops = [loop for loop, area in zip(loops, areas, strict=True) if area != 0]
        areas = areas[areas != 0]
    if np.all(areas > 0):
        return [[loop] for loop in loops]
    return nest(loops)
