"""2-D tests on loops and points: signed areas, convexity, star-shaped and
simple loops (which need no union), points in polygons.

Loops are (k, 2) float64 arrays, counter-clockwise for an outer loop and
clockwise for a hole; the certificates work within +-``MAX_COORDINATE``
(:mod:`shadowgeo.orientation`), where their rounding margins hold.
"""

from __future__ import annotations

import collections
import hashlib

import numpy as np

from ..limits import CONVEX_TURN as _CONVEX_TURN
from ..orientation import MAX_COORDINATE, turns
from ..sweep import simple_triangles
from ..topology import loop_rings

__all__ = [
    "is_convex",
    "loop_means",
    "many_reflex",
    "points_in_parts",
    "signed_areas",
    "star_shaped_flat",
    "swept_triangles",
    "whole_loop",
]


# A polygon of one loop of this many corners or more, this many of them
# reflex (many_reflex), is triangulated by star_triangles or the sweep of
# shadowgeo.sweep, not by manifold3d's ear clipping (.triangulation), and
# whole_loop sweeps it. Below, manifold3d and Clipper2 are as fast or faster
# (benchmarks/bench_polygons.py: equal near 4,000 corners of a comb).
_SPIKED_CORNERS = 4096
_SPIKED_REFLEX = 64


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
    middle = np.repeat(loop_means(points, starts, lengths), lengths, axis=0)
    sign, cross = turns(middle, points, points[after])
    spoke, next_spoke = points - middle, points[after] - middle
    dot = spoke[:, 0] * next_spoke[:, 0] + spoke[:, 1] * next_spoke[:, 1]
    sweep = np.add.reduceat(np.arctan2(cross, dot), starts)
    star: np.ndarray = (np.minimum.reduceat(sign, starts) == 1) & (np.abs(sweep - 2 * np.pi) < 1.0)
    return star & (lengths >= 3)


def loop_means(points: np.ndarray, starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(l, 2) the mean of each loop's corners: the centre the star-shaped
    certificate is given for (:func:`star_shaped_flat`,
    :func:`~shadowgeo.plane2d.triangulation.star_triangles`)."""
    means: np.ndarray = np.add.reduceat(points, starts) / lengths[:, None]
    return means


def whole_loop(loops: list[np.ndarray], keep_triangles: bool = False) -> bool:
    """Whether ``loops`` are one loop whose inside is certainly their region
    of positive winding, so that no union is needed: a counter-clockwise loop
    star-shaped round the mean of its corners (:func:`star_shaped_flat`), or
    one of :data:`_SPIKED_CORNERS` corners or more, many reflex, that the
    sweep of :func:`shadowgeo.sweep.simple_triangles` certifies simple
    (Clipper2's own sweep is quadratic in such loops; smaller ones are left
    to it).

    ``keep_triangles``: the caller triangulates the loop next
    (:func:`~shadowgeo.plane2d.triangulation.triangulate_parts`); the sweep
    then cuts it into triangles as it certifies it and keeps them for that
    call (:func:`swept_triangles`), one sweep for both."""
    if len(loops) != 1 or len(loops[0]) < 3:
        return False
    loop = np.asarray(loops[0], dtype=np.float64)
    if star_shaped_flat(loop, np.zeros(1, dtype=np.int64), np.array([len(loop)]))[0]:
        return True
    if not many_reflex(loop):
        return False
    simple, triangles = simple_triangles(loop, triangles=keep_triangles)
    if simple and triangles is not None:
        _SWEPT[_loop_key(loop)] = triangles
        while len(_SWEPT) > _SWEPT_KEPT:
            _SWEPT.popitem(last=False)  # the oldest
    return simple


# Triangles of the loops whole_loop certified last by the sweep (keep_triangles),
# by their content (:func:`_loop_key`), for swept_triangles to hand over.
_SWEPT: collections.OrderedDict[bytes, np.ndarray] = collections.OrderedDict()
_SWEPT_KEPT = 2


def _loop_key(loop: np.ndarray) -> bytes:
    """A digest of a (k, 2) float64 loop's corners, bit for bit."""
    data = np.ascontiguousarray(loop, dtype=np.float64)
    return (
        len(data).to_bytes(8, "little") + hashlib.blake2b(data.tobytes(), digest_size=16).digest()
    )


def swept_triangles(loop: np.ndarray) -> np.ndarray | None:
    """The (k - 2, 3) triangles :func:`whole_loop`'s sweep cut the (k, 2)
    ``loop`` into when it certified it (``keep_triangles``), taken out of
    its keeping (at most once); None when it kept none for this loop."""
    if not _SWEPT:
        return None
    return _SWEPT.pop(_loop_key(np.asarray(loop, dtype=np.float64)), None)


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


def many_reflex(loop: np.ndarray) -> bool:
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
