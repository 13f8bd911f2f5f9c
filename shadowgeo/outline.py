"""A closed caster's outline seen from the light, and its shadow on faces.

The caster's shadow on any plane wholly behind it (seen from the light) is its
silhouette, projected once into a 2-D frame across the light's rays
(:mod:`shadowgeo.lightframe`) and united, mapped onto the plane. On a receiver
face it is that region cut to the face's image in the frame
(:meth:`Outline.cut`): faces wholly inside are shadowed whole, and a face the
outline's edge crosses is cut from the few edge segments near it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np
import shapely

from .arrangement import strictly_convex_loops
from .cells import grid_cells
from .lightframe import corner_max, corner_min, misses_boxes, overlapping_boxes, twice_areas
from .limits import PRODUCT_ROUNDING, TINY
from .orientation import MAX_COORDINATE
from .plane2d import components, unite
from .topology import loop_rings

if TYPE_CHECKING:
    from manifold3d import CrossSection

__all__ = ["Outline", "OutlineSet", "make_outlines", "padded_loops"]


def padded_loops(points: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """(n, k, 2) loops of ``sizes`` points each, taken in turn from ``points``,
    each padded to the longest by repeating its last point (repeated points
    add no edges)."""
    sizes = np.asarray(sizes, dtype=np.int64)
    if len(sizes) == 0:
        return np.zeros((0, 3, 2))
    width = max(int(sizes.max()), 3)
    starts = np.cumsum(sizes) - sizes
    index = starts[:, None] + np.minimum(np.arange(width)[None, :], sizes[:, None] - 1)
    loops: np.ndarray = points[index]
    return loops


def _perimeter(points: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(n,) position of points on their boxes' edges, counter-clockwise from
    the lower left corner: 0 to 1 along the bottom, 1 to 2 up the right side,
    2 to 3 along the top, 3 to 4 down the left side (the nearest side)."""
    x, y = points[:, 0], points[:, 1]
    width = np.maximum(high[:, 0] - low[:, 0], TINY)
    height = np.maximum(high[:, 1] - low[:, 1], TINY)
    distance = np.stack(
        [
            np.abs(y - low[:, 1]),
            np.abs(x - high[:, 0]),
            np.abs(y - high[:, 1]),
            np.abs(x - low[:, 0]),
        ],
        axis=1,
    )
    side = np.argmin(distance, axis=1)
    along = np.choose(
        side,
        [
            (x - low[:, 0]) / width,
            (y - low[:, 1]) / height,
            (high[:, 0] - x) / width,
            (high[:, 1] - y) / height,
        ],
    )
    position: np.ndarray = side + np.clip(along, 0.0, 1.0)
    return position


@dataclass(frozen=True)
class _Rings:
    """An outline's boundary loops as segments, one after another.

    Attributes
    ----------
    segments : (s, 2, 2) float64
        Each segment's start and end, in frame coordinates.
    boxes : (s, 4) float64
        Each segment's (xmin, ymin, xmax, ymax) box.
    loop : (s,) int64
        The loop of each segment.
    following : (s,) int64
        The segment after each one on its loop.
    n_loops : int
    """

    segments: np.ndarray
    boxes: np.ndarray
    loop: np.ndarray
    following: np.ndarray
    n_loops: int

    @classmethod
    def of(cls, points: np.ndarray, sizes: np.ndarray) -> _Rings:
        """The rings of loops given as (n, 2) ``points``, ``sizes[i]`` in turn."""
        sizes = np.asarray(sizes, dtype=np.int64)
        starts, following = loop_rings(sizes)
        end = points[following]
        return cls(
            np.stack([points, end], axis=1),
            np.column_stack([np.minimum(points, end), np.maximum(points, end)]),
            np.repeat(np.arange(len(sizes)), sizes),
            following,
            len(sizes),
        )


class _Cutter:
    """What cuts the region of one outline, or of several casters' outlines
    of one light, to triangles: :class:`Outline` and :class:`OutlineSet`.

    Subclasses give their :meth:`boundary` and say which boundary
    segments may meet which triangles, which region each triangle is cut
    by (its shapely geometry, its box and its loops), and how a triangle is
    cut by Clipper2 alone."""

    def boundary(self) -> _Rings:
        """The boundary's segments, loop after loop."""
        raise NotImplementedError

    def _segment_pairs(
        self, boxes: np.ndarray, owner: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(triangle, segment) pairs whose boxes overlap, sorted by triangle,
        the segments of each triangle's own outline (``owner``) only."""
        raise NotImplementedError

    def _region_of(
        self, triangles: np.ndarray, owner: np.ndarray | None
    ) -> shapely.Geometry | np.ndarray:
        """The region (or, per triangle, the regions) that cuts ``triangles``."""
        raise NotImplementedError

    def _clip_unsure(
        self, images: np.ndarray, triangles: np.ndarray, owner: np.ndarray | None
    ) -> tuple[list[np.ndarray], np.ndarray]:
        """The region of each of ``triangles`` (indices into ``images``) cut to
        it by Clipper2: loops, and the triangle of each."""
        raise NotImplementedError

    def _region_boxes(self, triangles: np.ndarray, owner: np.ndarray | None) -> np.ndarray:
        """(t, 4) the box of the region that cuts each of ``triangles``."""
        raise NotImplementedError

    def _region_loops(
        self, triangles: np.ndarray, owner: np.ndarray | None
    ) -> tuple[list[np.ndarray], np.ndarray]:
        """The loops of the region that cuts each of ``triangles``, whole, and
        the triangle of each loop."""
        raise NotImplementedError

    def cut(
        self, images: np.ndarray, margin: float | np.ndarray, owner: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The region cut to each of (f, 3, 2) triangles in the frame (for an
        :class:`OutlineSet`, triangle i by the outline ``owner[i]``).

        1. Triangles whose box meets no boundary segment's box lie wholly
           inside or wholly outside the region, as their first corner does;
           the others are tested as polygons (shapely). A triangle that
           holds the region's box beyond rounding gets the region's loops
           as they are.
        2. A triangle the boundary crosses is cut from the boundary segments
           whose boxes meet a box around it (:meth:`_local_cut`): the work per
           triangle grows with the boundary near it, not with the whole
           outline. Its reference point ``r`` (the centroid) must be sure to
           lie off the boundary: farther than its ``margin``.
        3. A triangle whose ``r`` lies within its ``margin`` of the boundary is
           cut against the whole outline by Clipper2 instead.

        Returns
        -------
        covered : (f,) bool
            Triangles wholly inside the region (they get no pieces).
        pieces : (n, k, 2) float64
            The region's loops inside each other triangle, in the frame (outer
            loops counter-clockwise, holes clockwise), padded by repeating the
            last corner.
        owners : (n,) int64
            The triangle of each loop.
        """
        count = len(images)
        covered = np.zeros(count, dtype=bool)
        nothing = (covered, np.zeros((0, 3, 2)), np.zeros(0, np.int64))
        rings = self.boundary()
        if count == 0 or rings.n_loops == 0:
            return nothing
        boxes = np.column_stack([corner_min(images), corner_max(images)])
        tri, seg = self._segment_pairs(boxes, owner)
        crossing = np.zeros(count, dtype=bool)
        crossing[tri] = True
        clear = np.flatnonzero(~crossing)
        region = self._region_of(clear, owner)
        covered[clear] = shapely.contains_xy(region, images[clear, 0, 0], images[clear, 0, 1])
        near = np.flatnonzero(crossing)
        polygons = shapely.polygons(images[near])
        region = self._region_of(near, owner)
        inside = shapely.covers(region, polygons)
        covered[near] = inside
        touched = np.zeros(count, dtype=bool)
        touched[near] = shapely.intersects(region, polygons) & ~inside
        if not touched.any():
            return nothing
        clockwise = twice_areas(images) < 0
        images = np.where(clockwise[:, None, None], images[:, ::-1], images)
        # A region wholly inside its triangle (a small caster's outline on a
        # large face) is its own cut: its loops as they are, no clipping.
        candidates = np.flatnonzero(touched)
        held = candidates[_box_within(images[candidates], self._region_boxes(candidates, owner))]
        touched[held] = False
        keep = touched[tri]
        tri, seg = tri[keep], seg[keep]

        # 2. each triangle's own stretch of the boundary, closed around it
        reference = images.mean(axis=1)
        a, b, r = rings.segments[seg, 0], rings.segments[seg, 1], reference[tri]
        ab, ar = b - a, r - a
        length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), TINY)
        along = np.clip(np.einsum("ij,ij->i", ar, ab) / length2, 0.0, 1.0)
        gap = np.hypot(*(ar - along[:, None] * ab).T)  # from r to the segment
        unsure = np.zeros(count, dtype=bool)
        unsure[tri[gap <= np.broadcast_to(margin, (count,))[tri]]] = True
        sure = np.flatnonzero(touched & ~unsure)
        points, sizes, owners = self._local_cut(images, reference, sure, tri, seg, owner)

        # 3. Clipper2 where the reference point is not sure
        exact, exact_owners = self._clip_unsure(images, np.flatnonzero(unsure), owner)
        whole, whole_owners = self._region_loops(held, owner)
        found = exact + whole
        if found:
            points = np.concatenate([points, *found])
            sizes = np.concatenate([sizes, [len(loop) for loop in found]])
            owners = np.concatenate([owners, exact_owners, whole_owners])
        return covered, padded_loops(points, sizes), owners.astype(np.int64)

    def _local_cut(
        self,
        images: np.ndarray,
        reference: np.ndarray,
        sure: np.ndarray,
        tri: np.ndarray,
        seg: np.ndarray,
        owner: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The region cut to each triangle ``sure`` (counter-clockwise in
        ``images``), from the boundary segments near it only (pairs ``tri``,
        ``seg``, sorted).

        Each segment is clipped to a box around the triangle; consecutive
        pieces of one loop are joined along the box's edge, counter-clockwise.
        Inside the box that polygon winds as the region does, up to one
        constant (the ways around the box it took or missed): the region's
        winding at the reference point, against the polygon's there, gives it,
        and as many loops of the box put it right. The triangle's part of that
        is then cut by Clipper2: every triangle in its own cell of one plane,
        one call. Returns the loops' points, their sizes, and their triangles.
        """
        if len(sure) == 0:
            return np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64)
        low, high = corner_min(images[sure]), corner_max(images[sure])
        pad = 0.05 * np.maximum(high[:, 0] - low[:, 0], high[:, 1] - low[:, 1])[:, None]
        box_low = np.zeros((len(images), 2))
        box_high = np.zeros((len(images), 2))
        box_low[sure], box_high[sure] = low - pad, high + pad
        is_sure = np.zeros(len(images), dtype=bool)
        is_sure[sure] = True
        polygons = _box_polygons(self.boundary(), box_low, box_high, is_sure, tri, seg)
        # The polygon's winding at each triangle's reference point.
        successor = np.arange(len(polygons.points)) + 1
        successor[polygons.offsets + polygons.sizes - 1] = polygons.offsets
        p, q = polygons.points, polygons.points[successor]
        rp = reference[polygons.point_tri]
        side = (q[:, 0] - p[:, 0]) * (rp[:, 1] - p[:, 1]) - (rp[:, 0] - p[:, 0]) * (
            q[:, 1] - p[:, 1]
        )
        up = (p[:, 1] <= rp[:, 1]) & (rp[:, 1] < q[:, 1]) & (side > 0)
        down = (q[:, 1] <= rp[:, 1]) & (rp[:, 1] < p[:, 1]) & (side < 0)
        winding = np.bincount(
            polygons.point_tri, weights=up.astype(float) - down, minlength=len(images)
        )
        region = self._region_of(np.arange(len(images)), owner)
        truth = shapely.contains_xy(region, reference[:, 0], reference[:, 1])
        boxes_needed = np.rint(truth - winding).astype(np.int64)
        return _cut_in_cells(images, sure, box_low, box_high, polygons, boxes_needed)


@dataclass(frozen=True)
class _BoxPolygons:
    """Each triangle's polygons inside its box: ``points`` (m, 2) loop by
    loop, each point's triangle ``point_tri``, the loops' ``sizes`` and
    ``offsets`` into ``points``."""

    points: np.ndarray
    point_tri: np.ndarray
    sizes: np.ndarray
    offsets: np.ndarray


def _box_polygons(
    rings: _Rings,
    box_low: np.ndarray,
    box_high: np.ndarray,
    is_sure: np.ndarray,
    tri: np.ndarray,
    seg: np.ndarray,
) -> _BoxPolygons:
    """Each segment clipped to the boxes of the triangles ``is_sure`` marks
    near it (pairs ``tri``, ``seg``); consecutive pieces of one loop joined
    along the box's edge, counter-clockwise."""
    keep = is_sure[tri]
    order = np.lexsort((seg[keep], tri[keep]))
    tri, seg = tri[keep][order], seg[keep][order]
    a, b = rings.segments[seg, 0], rings.segments[seg, 1]
    step = b - a
    # Liang-Barsky: the part a + t (b - a), t0 <= t <= t1, inside the box.
    t0, t1 = np.zeros(len(tri)), np.ones(len(tri))
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis in range(2):
            first = (box_low[tri, axis] - a[:, axis]) / step[:, axis]
            second = (box_high[tri, axis] - a[:, axis]) / step[:, axis]
            flat = step[:, axis] == 0
            within = (a[:, axis] >= box_low[tri, axis]) & (a[:, axis] <= box_high[tri, axis])
            enter = np.where(flat, np.where(within, -np.inf, np.inf), np.minimum(first, second))
            leave = np.where(flat, np.where(within, np.inf, -np.inf), np.maximum(first, second))
            t0, t1 = np.maximum(t0, enter), np.minimum(t1, leave)
    keep = t0 < t1
    tri, seg, a, b, step, t0, t1 = (x[keep] for x in (tri, seg, a, b, step, t0, t1))
    start = np.where((t0 == 0)[:, None], a, a + t0[:, None] * step)
    end = np.where((t1 == 1)[:, None], b, a + t1[:, None] * step)
    # Pieces grouped by (triangle, loop); each followed by the next of its group.
    group_key = tri * rings.n_loops + rings.loop[seg]
    new_group = np.ones(len(tri), dtype=bool)
    new_group[1:] = group_key[1:] != group_key[:-1]
    group = np.cumsum(new_group) - 1
    group_start = np.flatnonzero(new_group)
    following = np.arange(len(tri)) + 1
    last = np.append(group_start[1:], len(tri)) - 1
    following[last] = group_start
    joined = (seg[following] == rings.following[seg]) & (t1 == 1)
    # The way along the box, counter-clockwise, from each piece's end to
    # the next piece's start: the box corners passed.
    lo, hi = box_low[tri], box_high[tri]
    leave_at = _perimeter(end, lo, hi)
    enter_at = _perimeter(start[following], lo, hi)
    travel = np.mod(enter_at - leave_at, 4.0)
    steps = np.floor(leave_at)[:, None] + np.arange(1, 5)[None, :]
    passed = ((steps - leave_at[:, None]) < travel[:, None]) & ~joined[:, None]
    corner = np.mod(steps, 4).astype(np.int64)
    corner_x = np.where((corner == 1) | (corner == 2), hi[:, :1], lo[:, :1])
    corner_y = np.where(corner >= 2, hi[:, 1:], lo[:, 1:])
    # Each piece: its start, its end, the corners it passes (masked).
    points = np.concatenate(
        [start[:, None], end[:, None], np.stack([corner_x, corner_y], axis=2)], axis=1
    )
    used = np.concatenate([np.ones((len(tri), 2), dtype=bool), passed], axis=1)
    flat_points = points[used]
    point_group = np.repeat(group, used.sum(axis=1))
    point_tri = tri[group_start][point_group]
    sizes = np.bincount(point_group, minlength=len(group_start))
    offsets = np.cumsum(sizes) - sizes
    return _BoxPolygons(flat_points, point_tri, sizes, offsets)


def _cut_in_cells(
    images: np.ndarray,
    sure: np.ndarray,
    box_low: np.ndarray,
    box_high: np.ndarray,
    polygons: _BoxPolygons,
    boxes_needed: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each triangle's part of its box polygons (with ``boxes_needed`` loops
    of its box added) cut by Clipper2, every triangle in its own cell of one
    plane, one call: the loops' points, their sizes, and their triangles."""
    # One Clipper2 call: triangle k in cell k of a square grid, scaled alike
    # along x and y, its box within the cell.
    slot = np.full(len(images), -1, dtype=np.int64)
    slot[sure] = np.arange(len(sure))
    middle = 0.5 * (box_low + box_high)
    size = np.maximum((box_high - box_low).max(axis=1), TINY)
    cells = grid_cells(middle[sure], size[sure])
    mapped = cells.place(polygons.points, slot[polygons.point_tri])
    subject = [
        mapped[o : o + n]
        for o, n in zip(polygons.offsets.tolist(), polygons.sizes.tolist(), strict=True)
    ]
    square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    for k in np.flatnonzero(boxes_needed[sure] != 0):
        face = sure[k]
        half = 0.5 * (box_high[face] - box_low[face])
        loop = (square * half) * cells.scale[k] + cells.centre[k]
        count = int(boxes_needed[face])
        subject += [loop if count > 0 else loop[::-1]] * abs(count)
    clip = cells.place(images[sure], np.arange(len(sure))[:, None])
    region = unite(subject) ^ unite(list(clip))
    out = [loop for loop in region.to_polygons() if len(loop) >= 3]
    nothing = (np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64))
    if not out:
        return nothing
    out_sizes = np.array([len(loop) for loop in out], dtype=np.int64)
    out_points = np.concatenate(out)
    found = cells.cell_of(out_points[np.cumsum(out_sizes) - out_sizes])
    owner = sure[found]
    out_points = cells.restore(out_points, np.repeat(found, out_sizes))
    return out_points, out_sizes, owner


class Outline(_Cutter):
    """A closed caster's shadow seen from the light: its silhouette loops
    projected once into a 2-D frame across the light's rays, and united.

    The caster's shadow on any plane wholly behind it (seen from the light) is
    this region mapped onto the plane; on a receiver face it is the region
    clipped to the face's own image in this frame.

    Attributes
    ----------
    region : shapely geometry
        The united outline in frame coordinates (after :meth:`unite`).
    cross_section : manifold3d.CrossSection
        The same, scaled by ``scale`` for Clipper2.
    """

    def __init__(
        self,
        light_point: np.ndarray | None,
        axis: np.ndarray,
        first: np.ndarray,
        second: np.ndarray,
        direction: np.ndarray | None,
    ) -> None:
        self.light_point = light_point
        self.axis, self.first, self.second = axis, first, second
        self.direction = direction
        # a point light's: the least depth of the caster's vertices along the
        # axis (no ray from the light reaches it any shallower)
        self.nearest = 0.0

    def unite(self, points2d_loops: list[np.ndarray]) -> None:
        """Set the region: the positive-winding union of the projected loops."""
        self.scale = float(_scale_for(np.abs(np.concatenate(points2d_loops)).max()))
        united = unite([loop * self.scale for loop in points2d_loops])
        self.__dict__["cross_section"] = united
        self._hold(components(united))

    def take_convex(self, loop: np.ndarray, scale: float) -> None:
        """Set the region to the inside of one projected ``loop`` that is
        strictly convex and counter-clockwise (beyond rounding: the caller
        has tested it), which is what :meth:`unite` would make of it, without
        a Clipper2 call; ``scale``: Clipper2's scale of it, as :meth:`unite`
        sets it."""
        self.scale = scale
        self._hold([[loop * scale]], [loop])  # (the loop exactly, not scaled and back)

    def _hold(self, parts: list[list[np.ndarray]], loops: list[np.ndarray] | None = None) -> None:
        """Keep the region's ``parts`` (scaled for Clipper2) and its loops in
        frame coordinates (``loops``, or the parts' scaled back)."""
        self.parts = parts
        if loops is None:
            loops = [loop / self.scale for part in parts for loop in part]
        self.loops = loops
        self.n_loops = len(loops)

    @functools.cached_property
    def cross_section(self) -> CrossSection:
        """The region scaled by ``scale``, for Clipper2 (made from
        :attr:`parts` when :meth:`take_convex` set the region)."""
        return unite([loop for part in self.parts for loop in part])

    def boundary(self) -> _Rings:
        return self._rings

    @functools.cached_property
    def _rings(self) -> _Rings:
        sizes = np.array([len(loop) for loop in self.loops], dtype=np.int64)
        return _Rings.of(np.concatenate([*self.loops, np.zeros((0, 2))]), sizes)

    def _segment_pairs(
        self, boxes: np.ndarray, owner: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        return overlapping_boxes(boxes, self._rings.boxes)

    def _region_of(self, triangles: np.ndarray, owner: np.ndarray | None) -> shapely.Geometry:
        return self.region

    def _clip_unsure(
        self, images: np.ndarray, triangles: np.ndarray, owner: np.ndarray | None
    ) -> tuple[list[np.ndarray], np.ndarray]:
        loops, owners = self.clip_to(images[triangles])
        return loops, triangles[owners]

    def _region_boxes(self, triangles: np.ndarray, owner: np.ndarray | None) -> np.ndarray:
        return np.broadcast_to(np.array(self.bounds), (len(triangles), 4))

    def _region_loops(
        self, triangles: np.ndarray, owner: np.ndarray | None
    ) -> tuple[list[np.ndarray], np.ndarray]:
        return self.loops * len(triangles), np.repeat(triangles, self.n_loops)

    @functools.cached_property
    def region(self) -> shapely.MultiPolygon:
        """The united outline as a prepared shapely geometry, in frame
        coordinates: made when first asked for (a caster whose outline
        meets no receiving face never needs it)."""
        region = shapely.MultiPolygon(
            [
                shapely.Polygon(p[0] / self.scale, [h / self.scale for h in p[1:]])
                for p in self.parts
            ]
        )
        shapely.prepare(region)
        return region

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the region, as :attr:`region`'s
        ``bounds`` (NaN when it is empty)."""
        if not self.loops:
            return (math.nan,) * 4
        points = np.concatenate(self.loops)
        low, high = points.min(axis=0), points.max(axis=0)
        return float(low[0]), float(low[1]), float(high[0]), float(high[1])

    def clip_to(self, images: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """The region cut to each of (f, 3, 2) counter-clockwise triangles in
        the frame: loops, and (n,) the triangle of each loop."""
        loops: list[np.ndarray] = []
        owners: list[int] = []
        for k, image in enumerate(images):
            piece = self.cross_section ^ unite([image * self.scale])
            for loop in piece.to_polygons():
                loops.append(np.asarray(loop) / self.scale)
                owners.append(k)
        return loops, np.array(owners, dtype=np.int64)

    def to_frame(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) points to (..., 2) frame coordinates (their rays)."""
        if self.light_point is None:
            return np.stack([points @ self.first, points @ self.second], axis=-1)
        return _central_images(points - self.light_point, self.axis, self.first, self.second)[0]

    def onto_planes(self, flat: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """(n, 2) frame points to (n, 3) points where their rays meet the planes
        ``normals[i] . x + offsets[i] = 0``, one plane per point."""
        if self.light_point is None:
            base = np.outer(flat[:, 0], self.first) + np.outer(flat[:, 1], self.second)
            height = np.einsum("ij,ij->i", base, normals) + offsets
            # Without a light point the outline is a directional light's: it has a direction.
            direction = cast(np.ndarray, self.direction)
            lowered: np.ndarray = base - (height / (normals @ direction))[:, None] * direction
            return lowered
        frame = (self.axis, self.first, self.second)
        return _central_onto_planes(flat, normals, offsets, self.light_point, *frame)


class OutlineSet(_Cutter):
    """Several casters' :class:`Outline` of one light, cut to triangles all
    at once.

    Each triangle is cut by its own caster's outline (``owner``), in that
    outline's frame, as its :meth:`Outline.cut` would, but the cuts go
    through one Clipper2 call, and under a directional light (whose frame
    all the outlines share) the boundary segments of all the outlines are
    paired with the triangles in one search: a scene of a thousand
    buildings pays the per-call costs once, not once per building.
    """

    def __init__(self, outlines: list[Outline]) -> None:
        self.outlines = outlines
        loops = [loop for outline in outlines for loop in outline.loops]
        sizes = np.array([len(loop) for loop in loops], dtype=np.int64)
        self._rings = _Rings.of(np.concatenate([*loops, np.zeros((0, 2))]), sizes)
        loop_counts = np.array([outline.n_loops for outline in outlines], dtype=np.int64)
        loop_owner = np.repeat(np.arange(len(outlines)), loop_counts)
        segment_counts = np.bincount(loop_owner, weights=sizes, minlength=len(outlines))
        segment_counts = segment_counts.astype(np.int64)
        self.segment_owner = np.repeat(np.arange(len(outlines)), segment_counts)
        self._segment_start = np.concatenate([[0], np.cumsum(segment_counts)]).astype(np.int64)
        self._regions: np.ndarray | None = None
        # A directional light's outlines share its frame; a point light's
        # each have their own (the axis towards their caster).
        self.shared = not outlines or outlines[0].light_point is None
        self._light = None if self.shared else outlines[0].light_point
        # (k, 3, 3) each outline's axis, first and second frame vector
        self.frames = np.array([(o.axis, o.first, o.second) for o in outlines]).reshape(-1, 3, 3)
        self.nearest = np.array([outline.nearest for outline in outlines], dtype=float)

    def boundary(self) -> _Rings:
        return self._rings

    @functools.cached_property
    def bounds(self) -> np.ndarray:
        """(k, 4) each outline's :attr:`Outline.bounds`, all at once."""
        bounds = np.full((len(self.outlines), 4), np.nan)
        counts = np.diff(self._segment_start)
        present = np.flatnonzero(counts > 0)
        if len(present):
            starts = self._segment_start[present]  # (the segments' starts: the loops' points)
            points = self._rings.segments[:, 0]
            bounds[present, :2] = np.minimum.reduceat(points, starts, axis=0)
            bounds[present, 2:] = np.maximum.reduceat(points, starts, axis=0)
        return bounds

    def to_frame(self, points: np.ndarray, owner: np.ndarray) -> np.ndarray:
        """(p, c, 3) points to (p, c, 2) coordinates in the frame of outline
        ``owner[i]`` (p,) for row i (under a directional light, every
        outline's frame is one and ``points`` may be (n, 3), ``owner`` unused)."""
        if self.shared:
            return self.outlines[0].to_frame(points)
        return self._central(points, owner)[0]

    def _central(self, points: np.ndarray, owner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(p, c, 2) images of (p, c, 3) points from the point light, row i
        in the frame of outline ``owner[i]``, and (p, c) their depths."""
        frames = self.frames[owner][:, None]  # against each row's points
        return _central_images(points - self._light, frames[..., 0, :], *_sides(frames))

    def onto_planes(
        self, flat: np.ndarray, normals: np.ndarray, offsets: np.ndarray, owner: np.ndarray
    ) -> np.ndarray:
        """:meth:`Outline.onto_planes`, point i from the frame of outline
        ``owner[i]``."""
        if self.shared:
            return self.outlines[0].onto_planes(flat, normals, offsets)
        frames = self.frames[owner]
        light = cast(np.ndarray, self._light)  # not shared: a point light's
        return _central_onto_planes(flat, normals, offsets, light, frames[:, 0], *_sides(frames))

    def may_reach(self, points: np.ndarray, faces: np.ndarray, owner: np.ndarray) -> np.ndarray:
        """(n,) bool for the n triangles ``points[faces]``: False where caster
        ``owner[i]`` surely casts nothing on triangle i (the triangle lies
        ahead of the light and its image misses the outline's box, in which
        the caster's image lies), every pair at once."""
        out = np.ones(len(faces), dtype=bool)
        if len(faces) == 0:
            return out
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.shared:  # ahead of the light is everything; each point once
                images = self.to_frame(points, owner)[faces]
                ahead = np.ones(len(faces), dtype=bool)
            else:
                images, depth = self._central(points[faces], owner)
                ahead = corner_min(depth) > 0
        out[ahead & misses_boxes(images, self.bounds[owner])] = False
        return out

    @property
    def regions(self) -> np.ndarray:
        """(k,) each outline's prepared region (its :attr:`Outline.region`,
        the same coordinates), made when first asked for: all of them in one
        call from their rings, not one shapely constructor per outline."""
        if self._regions is None:
            rings = [ring for outline in self.outlines for ring in outline.loops]
            closed = [np.concatenate([ring, ring[:1]]) for ring in rings]
            ring_sizes = np.array([len(ring) for ring in closed], dtype=np.int64)
            part_sizes = [len(part) for outline in self.outlines for part in outline.parts]
            part_counts = [len(outline.parts) for outline in self.outlines]
            offsets = tuple(
                np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
                for sizes in (ring_sizes, part_sizes, part_counts)
            )
            coordinates = np.concatenate([*closed, np.zeros((0, 2))])
            regions = shapely.from_ragged_array(
                shapely.GeometryType.MULTIPOLYGON, coordinates, offsets
            )
            shapely.prepare(regions)
            self._regions = regions
        return self._regions

    def _segment_pairs(
        self, boxes: np.ndarray, owner: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        owner = cast(np.ndarray, owner)
        # Each outline's boxes moved into a cell of its own along x: one
        # search, and no pair across outlines (whose frames may differ, and
        # which, in one frame, may lie over one another: a face under a
        # thousand casters would be paired with all their segments). The
        # triangles' boxes are first cut to their outline's box, which holds
        # all its segments' boxes.
        bounds = self.bounds  # (NaN for an outline with no loops: its boxes drop out)
        mine = bounds[owner]
        low = np.maximum(boxes[:, :2], mine[:, :2])
        high = np.minimum(boxes[:, 2:], mine[:, 2:])
        kept = np.flatnonzero(np.all(low <= high, axis=1))
        if not len(kept):
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        width = np.nan_to_num(bounds[:, 2] - bounds[:, 0])
        height = np.nan_to_num(bounds[:, 3] - bounds[:, 1])
        step = 2.0 * float(max(width.max(), height.max(), TINY))
        # Moved by cell: rounding of the moved corners is within a few ulps
        # of the largest coordinate; boxes grown by more keep every overlap.
        shift = np.column_stack([np.arange(len(bounds)) * step, np.zeros(len(bounds))])
        shift -= np.nan_to_num(bounds[:, :2])
        pad = 8.0 * float(np.spacing(step * (len(bounds) + 1)))
        tri_boxes = np.column_stack(
            [low[kept] + shift[owner[kept]] - pad, high[kept] + shift[owner[kept]] + pad]
        )
        theirs = shift[self.segment_owner]
        segment_boxes = self._rings.boxes
        segment_boxes = np.column_stack(
            [segment_boxes[:, :2] + theirs - pad, segment_boxes[:, 2:] + theirs + pad]
        )
        tri, seg = overlapping_boxes(tri_boxes, segment_boxes)
        tri = kept[tri]
        own = self.segment_owner[seg] == owner[tri]  # (cells apart: always)
        return tri[own], seg[own]

    def _region_of(self, triangles: np.ndarray, owner: np.ndarray | None) -> np.ndarray:
        regions: np.ndarray = self.regions[cast(np.ndarray, owner)[triangles]]
        return regions

    def _clip_unsure(
        self, images: np.ndarray, triangles: np.ndarray, owner: np.ndarray | None
    ) -> tuple[list[np.ndarray], np.ndarray]:
        loops: list[np.ndarray] = []
        owners: list[np.ndarray] = []
        for triangle in triangles.tolist():
            outline = self.outlines[int(cast(np.ndarray, owner)[triangle])]
            found, _ = outline.clip_to(images[triangle : triangle + 1])
            loops += found
            owners.append(np.full(len(found), triangle, dtype=np.int64))
        return loops, np.concatenate([*owners, np.zeros(0, np.int64)])

    def _region_boxes(self, triangles: np.ndarray, owner: np.ndarray | None) -> np.ndarray:
        boxes: np.ndarray = self.bounds[cast(np.ndarray, owner)[triangles]]
        return boxes

    def _region_loops(
        self, triangles: np.ndarray, owner: np.ndarray | None
    ) -> tuple[list[np.ndarray], np.ndarray]:
        outlines = [self.outlines[k] for k in cast(np.ndarray, owner)[triangles].tolist()]
        loops = [loop for outline in outlines for loop in outline.loops]
        counts = [outline.n_loops for outline in outlines]
        return loops, np.repeat(triangles, counts)


def _box_within(triangles: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(t,) bool: whether each box (t, 4) lies strictly inside its
    counter-clockwise triangle (t, 3, 2), beyond the rounding of the tests:
    each box corner left of each triangle edge."""
    low_x, low_y, high_x, high_y = boxes.T
    corners = np.stack(
        [
            np.column_stack([low_x, low_y]),
            np.column_stack([high_x, low_y]),
            np.column_stack([high_x, high_y]),
            np.column_stack([low_x, high_y]),
        ],
        axis=1,
    )  # (t, 4, 2)
    start = triangles[:, :, None, :]  # (t, 3, 1, 2): each edge's start
    step = (triangles[:, [1, 2, 0]] - triangles)[:, :, None, :]
    to_corner = corners[:, None, :, :] - start  # (t, 3, 4, 2)
    first = step[..., 0] * to_corner[..., 1]
    second = step[..., 1] * to_corner[..., 0]
    # each difference is rounded once (relative), then two products and
    # their difference: a few eps of the products' size, far below 1e-12
    with np.errstate(invalid="ignore"):  # (NaN boxes: an outline with no loops)
        left = first - second > PRODUCT_ROUNDING * (np.abs(first) + np.abs(second))
    within: np.ndarray = np.all(left, axis=(1, 2))
    return within


def _scale_for(extent: np.ndarray) -> np.ndarray:
    """Clipper2's scale for regions whose largest coordinates (frame
    coordinates) are ``extent``: those at a quarter of MAX_COORDINATE."""
    scale: np.ndarray = MAX_COORDINATE / np.maximum(extent, TINY) / 4.0
    return scale


def _sides(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first and second vectors of (..., 3, 3) frames (axis, first, second)."""
    return frames[..., 1, :], frames[..., 2, :]


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products along the last axis, broadcast."""
    dots: np.ndarray = np.einsum("...d,...d->...", a, b)
    return dots


def _central_images(
    relative: np.ndarray, axis: np.ndarray, first: np.ndarray, second: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(..., 2) frame coordinates of points ``relative`` to a point light (its
    rays' slopes), and (...) their depths along ``axis``; the frame vectors
    (3,) or broadcast against the points."""
    depth = _dot(relative, axis)
    images = np.stack([_dot(relative, first) / depth, _dot(relative, second) / depth], axis=-1)
    return images, depth


def _central_onto_planes(
    flat: np.ndarray,
    normals: np.ndarray,
    offsets: np.ndarray,
    light: np.ndarray,
    axis: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
) -> np.ndarray:
    """(n, 3) points where the point light's rays through (n, 2) frame points
    ``flat`` meet the planes ``normals[i] . x + offsets[i] = 0``; the frame
    vectors (3,) or one per point (n, 3)."""
    rays = axis + flat[:, :1] * first + flat[:, 1:] * second
    height = normals @ light + offsets
    along = -height / np.einsum("ij,ij->i", rays, normals)
    met: np.ndarray = light + rays * along[:, None]
    return met


def make_outlines(
    casters: list[tuple[np.ndarray, list[np.ndarray]]],
    light_point: np.ndarray | None,
    direction: np.ndarray | None,
    margin: float,
) -> list[Outline | None]:
    """The :class:`Outline` of each closed caster given as (vertices, its
    silhouette loops, indices into them), every caster at once; None for a
    caster with no loops, or when a point light is not wholly behind one
    plane through the light and the caster, which a central projection
    needs.

    All the loops are projected at once: under a directional light in the
    frame every outline shares, under a point light each caster's in its
    own (its axis from the light to the mean of its vertices). A caster
    whose silhouette is one
    loop, strictly convex and counter-clockwise in the frame beyond
    rounding (a box, a cylinder: most buildings), takes that loop as its
    region with no Clipper2 call (:meth:`Outline.take_convex`), the test
    made on all such loops at once; the others are united by Clipper2
    (:meth:`Outline.unite`).
    """
    outlines: list[Outline | None] = [None] * len(casters)
    images: list[list[np.ndarray]] = [[] for _ in casters]
    if light_point is None:
        _directional_lit(casters, cast(np.ndarray, direction), outlines, images)
    else:
        _point_lit(casters, light_point, margin, outlines, images)
    convex = _convex_singles(outlines, images)
    for k, scale in convex.items():
        cast(Outline, outlines[k]).take_convex(images[k][0], scale)
    for k, outline in enumerate(outlines):
        if outline is not None and k not in convex:
            outline.unite(images[k])
    return outlines


def _directional_lit(
    casters: list[tuple[np.ndarray, list[np.ndarray]]],
    direction: np.ndarray,
    outlines: list[Outline | None],
    images: list[list[np.ndarray]],
) -> None:
    """Under a directional light: every caster with loops gets an outline in
    the one frame they all share, and its loops' images in it."""
    shared = _framed(direction)
    chosen = [k for k, (_, loops) in enumerate(casters) if loops]
    every = [casters[k][0][loop] for k in chosen for loop in casters[k][1]]
    if not every:
        return
    counts = [len(loop) for loop in every]
    flat = shared.to_frame(np.concatenate(every))
    pieces = np.split(flat, np.cumsum(counts)[:-1])
    at = 0
    for k in chosen:
        count = len(casters[k][1])
        images[k], at = pieces[at : at + count], at + count
        outlines[k] = Outline(None, shared.axis, shared.first, shared.second, direction)


def _convex_singles(
    outlines: list[Outline | None], images: list[list[np.ndarray]]
) -> dict[int, float]:
    """The casters whose outline is one strictly convex loop, tested all at
    once: each with the scale :meth:`Outline.take_convex` takes, in order."""
    single = [k for k, made in enumerate(outlines) if made is not None and len(images[k]) == 1]
    if not single:
        return {}
    loops = [images[k][0] for k in single]
    sizes = np.array([len(loop) for loop in loops], dtype=np.int64)
    points = np.concatenate(loops)
    convex = strictly_convex_loops(points, sizes)
    starts = np.cumsum(sizes) - sizes
    scales = _scale_for(np.maximum.reduceat(np.abs(points).max(axis=1), starts)).tolist()
    return {single[position]: scales[position] for position in np.flatnonzero(convex).tolist()}


def _point_lit(
    casters: list[tuple[np.ndarray, list[np.ndarray]]],
    light_point: np.ndarray,
    margin: float,
    outlines: list[Outline | None],
    images: list[list[np.ndarray]],
) -> None:
    """:func:`make_outlines`' frames and loop images under a point light,
    every caster at once: each caster's axis from the light to the mean of
    its vertices (which must all lie ahead of the light by ``margin``
    along it), its frame (:func:`_frame_vectors`), and its loops' points
    projected in it. Sets ``outlines[k]`` and ``images[k]``, and each
    outline's least depth of its caster (:attr:`Outline.nearest`)."""
    chosen = [k for k, (_, loops) in enumerate(casters) if loops]
    if not chosen:
        return
    counts = np.array([len(casters[k][0]) for k in chosen], dtype=np.int64)
    starts = np.cumsum(counts) - counts
    relative = np.concatenate([casters[k][0] for k in chosen]) - light_point
    axes = np.add.reduceat(relative, starts, axis=0) / counts[:, None]
    axes /= np.sqrt(np.einsum("ij,ij->i", axes, axes))[:, None]
    depth = np.einsum("ij,ij->i", relative, np.repeat(axes, counts, axis=0))
    nearest = np.minimum.reduceat(depth, starts)
    ahead = nearest > margin
    first, second = _frame_vectors(axes)
    kept = np.flatnonzero(ahead)
    loops = [casters[chosen[i]][0][loop] for i in kept.tolist() for loop in casters[chosen[i]][1]]
    if not loops:
        return
    loop_counts = [len(casters[chosen[i]][1]) for i in kept.tolist()]
    sizes = np.array([len(loop) for loop in loops], dtype=np.int64)
    owner = np.repeat(np.repeat(kept, loop_counts), sizes)
    flat = _central_images(
        np.concatenate(loops) - light_point, axes[owner], first[owner], second[owner]
    )[0]
    pieces = np.split(flat, np.cumsum(sizes)[:-1])
    at = 0
    for i, count in zip(kept.tolist(), loop_counts, strict=True):
        k = chosen[i]
        outline = Outline(light_point, axes[i], first[i], second[i], None)
        outline.nearest = float(nearest[i])
        outlines[k], images[k], at = outline, pieces[at : at + count], at + count


def _framed(direction: np.ndarray) -> Outline:
    """An :class:`Outline` of a directional light travelling along
    ``direction``, with its frame and no region yet."""
    first, second = _frame_vectors(direction[None])
    return Outline(None, direction, first[0], second[0], direction)


def _frame_vectors(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, 3) each unit axis's first and second frame vectors: across it,
    from the world axis it leans on least, and with first x second = -axis,
    so loops counter-clockwise seen from the light stay so."""
    helper = np.zeros_like(axes)
    helper[np.arange(len(axes)), np.argmin(np.abs(axes), axis=1)] = 1.0
    first = np.cross(axes, helper)
    first /= np.sqrt(np.einsum("ij,ij->i", first, first))[:, None]
    return first, np.cross(first, axes)
