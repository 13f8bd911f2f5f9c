"""Whether a shape may hold a flat patch of a given size, decided from a
histogram of its face normals before any per-patch work: the receiver search
(:mod:`shadowgeo.scene.receivers`) skips the shapes that cannot (a sphere has
no large flat part: each of its patches is a face or two).

The bounds are exact: a shape ruled out has no patch (:func:`~.receivers.patches`)
that large. :func:`may_hold_patch` tries big shapes by a coarse bound of
their normals' cells alone first (:func:`_normal_bound`, no sort; a sphere of
a million faces is ruled out in one pass over its faces), then the rest by a
finer one that also bins the planes' offsets (:func:`_patch_bound`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np

from ..limits import RELATIVE_ROUNDING
from ..tolerance import Tolerance
from .casters import CasterSet

__all__ = ["may_hold_patch"]

# Side of the cells of the normal histogram (unit-normal components), and the
# faces binned per pass (bounds its memory).
_NORMAL_CELL = 1.0 / 16.0
_FACES_PER_PASS = 1 << 19


def may_hold_patch(
    stacked: CasterSet, indices: np.ndarray, size: float, tolerance: Tolerance
) -> np.ndarray:
    """(len(indices),) bool: False for a shape none of whose flat patches
    (:func:`~.receivers.patches`) can reach ``size`` across. Decided from a histogram of
    its face normals, before any per-patch work (a sphere has no large flat
    part: each of its patches is a face or two).

    A patch's faces all lie within ``coplanar_length`` of its seed face's
    plane. A face whose smallest height is ``w`` turns by at most an angle
    ``t`` with ``sin t <= 2 coplanar_length / w`` from that plane, so its unit
    normal (or its opposite) lies within ``pi coplanar_length / w`` of the
    seed's, and its plane's offset (from the middle of the faces, ``R`` away
    at most) within ``R`` times that plus ``coplanar_length`` of the seed's.
    Faces with ``w`` large enough that the turn is below half a cell of the
    histogram (cells of direction and offset) fall in the cells next to the
    seed's; thinner faces (and degenerate ones) may join any patch. A patch
    therefore lies in the box of the faces binned in the 81 cells around its
    seed's plus the thin faces, and a shape where every such box is smaller
    than ``size`` is skipped:
    exactly the shapes whose patches :func:`~.receivers.found` would all have dropped.
    """
    keep = np.zeros(len(indices), dtype=bool)
    limit = tolerance.coplanar_length
    cell = _NORMAL_CELL
    width = 2.0 * np.pi * limit / cell
    side = int(np.ceil(1.0 / cell))  # cells from the middle to a side, each axis
    offsets = np.array(
        [
            (i, j, k, m)
            for i in (-1, 0, 1)
            for j in (-1, 0, 1)
            for k in (-1, 0, 1)
            for m in (-1, 0, 1)
        ],
        dtype=np.int64,
    )
    counts = stacked.face_counts[indices]
    # A big shape is first tried by its normals' cells alone (no offsets, no
    # sort): a sphere of a million faces is ruled out in one pass.
    coarse = np.flatnonzero(counts >= _COARSE_FACES)
    ruled_out = np.zeros(len(indices), dtype=bool)
    for k in coarse.tolist():
        ruled_out[k] = not _normal_bound(stacked, int(indices[k]), size, limit)
    remaining = np.flatnonzero(~ruled_out)
    indices, counts = indices[remaining], counts[remaining]
    start = 0
    while start < len(indices):
        stop = start + 1
        total = counts[start]
        while stop < len(indices) and total + counts[stop] <= _FACES_PER_PASS:
            total += counts[stop]
            stop += 1
        chunk = np.arange(start, stop)
        keep[remaining[chunk]] = _patch_bound(
            stacked, indices[chunk], size, limit, width, side, offsets
        )
        start = stop
    return keep


def _normal_bound(stacked: CasterSet, index: int, size: float, limit: float) -> bool:
    """Whether shape ``index`` may hold a patch ``size`` across, by a bound
    coarser than :func:`_patch_bound`'s and with no sort: faces binned by
    their unit normal in cells of side ``_COARSE_CELL`` and by their plane's
    offset in levels of ``band``, each cell's box accumulated in a dense grid.

    With ``C = _COARSE_CELL``, a face is sharp here when its smallest height
    ``w`` is at least ``2 pi limit / C``. A sharp member of a patch turns
    from the seed's plane by ``t`` with ``sin t <= 2 limit / w <= C / pi``
    (:func:`may_hold_patch`), so two sharp members' unit normals differ by
    less than ``2 asin(C / pi) < C`` in each component, or their opposites
    do, and their offsets (from the middle of the shape's box, ``R`` away at
    most) by less than ``R 2 asin(C / pi) + 2 limit < band``. Take any sharp
    member's cell ``c``: every other sharp member lies in the cells within
    one of ``c``, or within one of the cell of its opposite normal and
    offset, which is the mirrored cell (the grid flipped along each axis) or
    the one before it along an axis (a value on a cell's edge mirrors to an
    edge), so within two of the mirror of ``c``. The patch therefore lies in
    the box of those cells and of the thin faces; a patch with no sharp face
    lies in the thin faces' box. A shape where all such boxes are smaller
    than ``size`` has no patch that large.

    Most faces are filed a run of ``_CHUNK`` at a time (:meth:`_Cells.runs`):
    a run whose faces all fall within two cells along each axis is filed
    under each of those cells with the run's box, which holds each face's;
    every cell a face would be filed under then holds a box at least as
    large, so the bound stands (a cell filed with no face of its own only
    adds boxes to look at)."""
    start, count = int(stacked.face_starts[index]), int(stacked.face_counts[index])
    low_box, high_box = stacked.low[index], stacked.high[index]
    middle = 0.5 * (low_box + high_box)
    radius = float(np.sqrt(((high_box - low_box) ** 2).sum())) / 2.0
    cell = _COARSE_CELL
    band = cell * radius * (1.0 + RELATIVE_ROUNDING) + 2.0 * limit
    if not (np.isfinite(band) and band > 0):
        return True
    side = int(np.ceil(1.0 / cell))
    levels = int(np.ceil(radius / band))
    span, depth = 2 * side + 3, 2 * levels + 3  # an empty cell past each end
    cells = _Cells(
        scales=(1.0 / cell, 1.0 / cell, 1.0 / cell, 1.0 / band),
        bounds=(side, side, side, levels),
        weights=(1, span, span * span, span**3),
        width=2.0 * np.pi * limit / cell,
    )
    faces = stacked.faces[start : start + count]
    # the face normals, kept for the casters' mesh of the first light
    binned = _binned(faces, stacked.columns, middle, stacked.normal_rows(index), cells, size)
    stacked.normals_known(index, binned.used)
    return _grid_may_hold(binned, cells.weights, (3, depth, span, span, span), size)


@dataclasses.dataclass(frozen=True)
class _Binned:
    """:func:`_normal_bound`'s faces filed: the boxes under cells
    (``records``), the box of the thin faces (``loose_low``, ``loose_high``,
    (3,) each; inf and -inf when none) and of every corner (``used``, (2, 3))."""

    records: list[_Records]
    loose_low: np.ndarray
    loose_high: np.ndarray
    used: np.ndarray


def _binned(
    faces: np.ndarray,
    columns: np.ndarray,
    middle: np.ndarray,
    normals: np.ndarray,
    cells: _Cells,
    size: float,
) -> _Binned:
    """The faces filed under the cells of ``cells``, ``_BIN_BLOCK`` at a
    time: whole runs first, then the other runs' faces one by one, each under
    its own cell, the thin ones into the loose box."""
    loose_low = np.full(3, np.inf)
    loose_high = np.full(3, -np.inf)
    used_low, used_high = [np.inf] * 3, [-np.inf] * 3  # the box of the faces' corners
    records: list[_Records] = []
    for first in range(0, len(faces), _BIN_BLOCK):
        stop = first + _BIN_BLOCK
        low, high, unit, height, doubled = _face_values(
            faces[first:stop], columns, middle, normals[first:stop]
        )
        values = [*unit, height]
        whole, runs = cells.runs(low, high, values, doubled, size)
        records.append(runs)
        for axis in range(3):
            used_low[axis] = min(used_low[axis], float(low[axis].min()))
            used_high[axis] = max(used_high[axis], float(high[axis].max()))
        if whole.all():
            continue
        rest = np.flatnonzero(np.repeat(~whole, _CHUNK)[: len(doubled)])
        low, high = [x[rest] for x in low], [x[rest] for x in high]
        values, doubled = [x[rest] for x in values], doubled[rest]
        _, sharp = _sharpness(low, high, values[:3], doubled, cells.width)
        if not sharp.all():
            loose = ~sharp
            for axis in range(3):
                loose_low[axis] = min(loose_low[axis], float(low[axis][loose].min()))
                loose_high[axis] = max(loose_high[axis], float(high[axis][loose].max()))
            chosen = np.flatnonzero(sharp)
            if not len(chosen):
                continue
            low, high = [x[chosen] for x in low], [x[chosen] for x in high]
            values = [x[chosen] for x in values]
        records.append(cells.faces(low, high, values))
    return _Binned(records, loose_low, loose_high, np.array([used_low, used_high]))


def _grid_may_hold(
    binned: _Binned, weights: tuple[int, ...], shape: tuple[int, ...], size: float
) -> bool:
    """Whether a patch ``size`` across may lie in the box of a cell's
    neighbours and its mirror's (the grid of ``shape``: rows, then the
    offset and normal axes) with the thin faces, or in the thin faces' box."""
    grid_low = np.full((3, int(np.prod(shape[1:]))), np.inf)
    grid_high = np.full((3, int(np.prod(shape[1:]))), -np.inf)
    for offset, at, box_low, box_high in _Records.filed(binned.records, weights):
        for axis in range(3):
            np.minimum.at(grid_low[axis], at + offset, box_low[axis])
            np.maximum.at(grid_high[axis], at + offset, box_high[axis])
    grid_low, grid_high = grid_low.reshape(shape), grid_high.reshape(shape)
    occupied = np.nonzero(np.isfinite(grid_low[0]))
    # the mirror of each occupied cell (the grid flipped along each axis)
    mirrored = tuple(length - 1 - at for length, at in zip(shape[1:], occupied, strict=True))
    near_low = np.minimum(
        _window_at(grid_low, 1, np.minimum, occupied, occupied),
        _window_at(grid_low, 2, np.minimum, occupied, mirrored),
    )
    near_high = np.maximum(
        _window_at(grid_high, 1, np.maximum, occupied, occupied),
        _window_at(grid_high, 2, np.maximum, occupied, mirrored),
    )
    loose_low, loose_high = binned.loose_low, binned.loose_high
    near_low = np.minimum(near_low, loose_low[:, None])
    near_high = np.maximum(near_high, loose_high[:, None])
    with np.errstate(invalid="ignore", over="ignore"):
        reach = np.sqrt(((near_high - near_low) ** 2).sum(axis=0))
        loose_reach = float(np.sqrt(((loose_high - loose_low) ** 2).sum()))
    if np.any(~(reach < size * (1.0 - RELATIVE_ROUNDING))):  # NaN or inf: keep the shape
        return True
    return bool(np.isfinite(loose_low).all() and not loose_reach < size * (1.0 - RELATIVE_ROUNDING))


def _window_at(
    grid: np.ndarray,
    reach: int,
    pick: np.ufunc,
    occupied: tuple[np.ndarray, ...],
    cells: tuple[np.ndarray, ...],
) -> np.ndarray:
    """(rows, k) :func:`_window` of ``grid`` at the ``cells`` (index arrays,
    one per cell axis), its ``occupied`` cells given (every other cell holds
    ``pick``'s identity, inf or -inf): the window is taken over the box of
    the occupied cells and ``reach`` around it only, and a cell beyond that
    box has no occupied cell within reach."""
    empty = np.inf if pick is np.minimum else -np.inf
    if not len(occupied[0]):
        return np.full((grid.shape[0], len(cells[0])), empty)
    starts = [max(int(at.min()) - reach, 0) for at in occupied]
    stops = [
        min(int(at.max()) + reach + 1, length)
        for at, length in zip(occupied, grid.shape[1:], strict=True)
    ]
    crop = (slice(None), *(slice(a, b) for a, b in zip(starts, stops, strict=True)))
    window = _window(grid[crop], reach, pick)
    inside = np.ones(len(cells[0]), dtype=bool)
    for at, a, b in zip(cells, starts, stops, strict=True):
        inside &= (at >= a) & (at < b)
    result = np.full((grid.shape[0], len(inside)), empty)
    local: tuple[slice | np.ndarray, ...] = (
        slice(None),
        *(at[inside] - a for at, a in zip(cells, starts, strict=True)),
    )
    result[:, inside] = window[local]
    return result


def _window(grid: np.ndarray, reach: int, pick: np.ufunc) -> np.ndarray:
    """``pick`` (minimum or maximum) of the cells of ``grid`` (a leading axis
    of rows, then the cells' axes) within ``reach`` cells of each cell along
    every axis, row by row."""
    result = grid
    for axis in range(1, grid.ndim):
        out = result.copy()
        length = result.shape[axis]
        for shift in range(1, reach + 1):
            ahead = [slice(None)] * grid.ndim
            behind = [slice(None)] * grid.ndim
            ahead[axis], behind[axis] = slice(shift, length), slice(0, length - shift)
            pick(out[tuple(behind)], result[tuple(ahead)], out=out[tuple(behind)])
            pick(out[tuple(ahead)], result[tuple(behind)], out=out[tuple(ahead)])
        result = out
    return result


@dataclasses.dataclass(frozen=True)
class _Records:
    """Boxes filed under cells of :func:`_normal_bound`'s grid: ``cells``
    (k,) each box's lowest cell, ``spans`` (k,) a bit per axis of the four
    (normal x, y, z, offset) along which it is filed under the next cell
    too, and the boxes' ``low`` and ``high`` columns."""

    cells: np.ndarray
    spans: np.ndarray
    low: _Columns
    high: _Columns

    @staticmethod
    def joined(records: list[_Records]) -> _Records:
        """The ``records`` as one."""
        return _Records(
            np.concatenate([r.cells for r in records]),
            np.concatenate([r.spans for r in records]),
            [np.concatenate([r.low[axis] for r in records]) for axis in range(3)],
            [np.concatenate([r.high[axis] for r in records]) for axis in range(3)],
        )

    @staticmethod
    def filed(
        records: list[_Records], weights: tuple[int, ...]
    ) -> Iterator[tuple[int, np.ndarray, _Columns, _Columns]]:
        """Every ``(offset, cells, low, high)`` to file, for each of the 16
        ways of stepping to the next cell along some of the axes: the boxes
        spanning those axes, under their lowest cell plus ``offset``."""
        if not records:
            return
        joined = _Records.joined(records)
        cells, spans, low, high = joined.cells, joined.spans, joined.low, joined.high
        for step in range(16):
            at = np.flatnonzero((spans & step) == step) if step else np.arange(len(cells))
            if len(at):
                offset = sum(weights[k] for k in range(4) if step >> k & 1)
                yield offset, cells[at], [x[at] for x in low], [x[at] for x in high]


@dataclasses.dataclass(frozen=True)
class _Cells:
    """The cells of :func:`_normal_bound`'s grid along its four axes (a
    face's unit normal x, y and z, and its plane's offset): ``scales``,
    the inverse cell sides; ``bounds``, the highest cell each way (values
    past it are clipped to it); ``weights``, each axis's step in a cell's
    number; ``width``, the smallest height of a sharp face."""

    scales: tuple[float, ...]
    bounds: tuple[int, ...]
    weights: tuple[int, ...]
    width: float

    @property
    def base(self) -> int:
        """The number of the cell of all values 0 (cells count from an empty
        one below each axis's lowest)."""
        return sum((b + 1) * w for b, w in zip(self.bounds, self.weights, strict=True))

    def runs(
        self,
        low: _Columns,
        high: _Columns,
        values: _Columns,
        doubled: np.ndarray,
        size: float,
    ) -> tuple[np.ndarray, _Records]:
        """Runs of ``_CHUNK`` consecutive faces (a mesh's faces mostly follow
        each other across its surface) filed whole: the run's box under every
        cell its faces' values (the four axes' columns) may fall in, where
        that is a cell or two along each axis, every face is sharp by the
        run's box (a face's diagonal is at most the run's) and the run is
        small beside ``size``. Returns (runs,) bool, the runs taken whole, and
        their records; ``low``, ``high``: the faces' boxes, ``doubled``:
        twice their areas."""
        starts = np.arange(0, len(doubled), _CHUNK)
        box_low = [_runs_reduced(np.minimum, x, starts) for x in low]
        box_high = [_runs_reduced(np.maximum, x, starts) for x in high]
        with np.errstate(invalid="ignore", over="ignore"):
            diagonal = _diagonal(box_low, box_high)
            least = _runs_reduced(np.minimum, doubled, starts)
            whole = (least > 0) & (least >= self.width * diagonal)
            whole &= diagonal <= size * _CHUNK_REACH
            whole &= _runs_reduced(np.maximum, doubled, starts) < np.inf
            cells = np.full(len(starts), self.base, dtype=np.int64)
            spans = np.zeros(len(starts), dtype=np.int64)
            for k, (column, scale, bound) in enumerate(
                zip(values, self.scales, self.bounds, strict=True)
            ):
                a = np.floor(_runs_reduced(np.minimum, column, starts) * scale)
                b = np.floor(_runs_reduced(np.maximum, column, starts) * scale)
                whole &= b - a <= 1  # False for NaN
                np.clip(a, -bound, bound, out=a)
                np.clip(b, -bound, bound, out=b)
                a[~whole] = 0  # (runs not taken: any whole number)
                cells += a.astype(np.int64) * self.weights[k]
                spans |= (b > a).astype(np.int64) << k
        taken = np.flatnonzero(whole)
        return whole, _Records(
            cells[taken], spans[taken], [x[taken] for x in box_low], [x[taken] for x in box_high]
        )

    def faces(self, low: _Columns, high: _Columns, values: _Columns) -> _Records:
        """Sharp faces each filed under its own cell, runs of faces in one
        cell reduced first (each run's box filed once)."""
        key = np.full(len(values[0]), float(self.base))
        for column, scale, bound, weight in zip(
            values, self.scales, self.bounds, self.weights, strict=True
        ):
            bin_ = np.floor(column * scale)
            np.clip(bin_, -bound, bound, out=bin_)
            bin_ *= weight
            key += bin_  # whole numbers, exact in floats
        cells = key.astype(np.int64)
        runs = np.flatnonzero(np.concatenate([[True], cells[1:] != cells[:-1]]))
        return _Records(
            cells[runs],
            np.zeros(len(runs), dtype=np.int64),
            [np.minimum.reduceat(x, runs) for x in low],
            [np.maximum.reduceat(x, runs) for x in high],
        )


def _diagonal(low: _Columns, high: _Columns) -> np.ndarray:
    """The diagonals of boxes given by their ``low`` and ``high`` columns."""
    extent = [b - a for a, b in zip(low, high, strict=True)]
    result: np.ndarray = np.sqrt(
        extent[0] * extent[0] + extent[1] * extent[1] + extent[2] * extent[2]
    )
    return result


def _patch_bound(
    stacked: CasterSet,
    indices: np.ndarray,
    size: float,
    limit: float,
    width: float,
    side: int,
    offsets: np.ndarray,
) -> np.ndarray:
    """:func:`may_hold_patch` of the shapes ``indices``, a block of faces at a
    time: each block's faces binned and their boxes reduced per cell, then
    the cells of all blocks merged (the temporaries stay a few MB however
    large the shape)."""
    count = len(indices)
    rows = np.concatenate(
        [np.arange(stacked.face_starts[i], stacked.face_starts[i] + stacked.face_counts[i])
         for i in indices.tolist()]
    )  # fmt: skip
    owner = np.repeat(np.arange(count), stacked.face_counts[indices])
    # Offsets from the middle of the shapes' boxes: every face (its
    # centroid) lies within ``radius`` of it, as the band below needs.
    low_all, high_all = stacked.low[indices].min(axis=0), stacked.high[indices].max(axis=0)
    middle = 0.5 * (low_all + high_all)
    grid = _PatchGrid.of(float(np.sqrt(((high_all - low_all) ** 2).sum())) / 2.0, limit, side)
    # thin and degenerate faces: members of any patch of their shape
    loose_low = np.full((count, 3), np.inf)
    loose_high = np.full((count, 3), -np.inf)
    cells: list[tuple[np.ndarray, _Columns, _Columns]] = []
    for start in range(0, len(rows), _BIN_BLOCK):
        block = rows[start : start + _BIN_BLOCK]
        holder = owner[start : start + _BIN_BLOCK]
        low, high, unit, height, doubled = _face_values(
            stacked.faces[block], stacked.columns, middle
        )
        binned, sharp = _sharpness(low, high, unit, doubled, width)
        _widen_loose(loose_low, loose_high, holder, np.flatnonzero(~sharp), low, high)
        chosen = np.flatnonzero(binned)
        if len(chosen):
            keys = grid.keys(holder[chosen], [x[chosen] for x in unit], height[chosen])
            cells.append(_cell_boxes(keys, np.concatenate([chosen, chosen]), low, high))
    keep = np.zeros(count, dtype=bool)
    if cells:
        group_keys, group_low, group_high = _merged_cells(cells)
        near_low, near_high = _near_boxes(
            group_keys, group_low, group_high, loose_low, loose_high, offsets, grid
        )
        with np.errstate(invalid="ignore", over="ignore"):
            reach = np.sqrt(((near_high - near_low) ** 2).sum(axis=1))
        large = ~(reach < size * (1.0 - RELATIVE_ROUNDING))  # NaN or inf: keep the shape
        keep[group_keys[large] // grid.per_shape] = True
    # a shape whose faces are all thin or degenerate has no sharp seed
    # cell; its patches lie within its loose box
    with np.errstate(invalid="ignore", over="ignore"):
        loose_reach = np.sqrt(((loose_high - loose_low) ** 2).sum(axis=1))
    keep |= np.isfinite(loose_low).all(axis=1) & ~(loose_reach < size * (1.0 - RELATIVE_ROUNDING))
    return keep


@dataclasses.dataclass(frozen=True)
class _PatchGrid:
    """:func:`_patch_bound`'s cells: ``side`` normal cells each way from 0
    along each axis, ``levels`` offset levels of ``band`` each way (none for
    an unbounded band), an empty cell past each end; ``span`` cells along a
    normal axis, ``per_shape`` cells in all."""

    side: int
    span: int
    levels: int
    band: float
    per_shape: int

    @staticmethod
    def of(radius: float, limit: float, side: int) -> _PatchGrid:
        band = 0.5 * _NORMAL_CELL * radius * (1.0 + RELATIVE_ROUNDING) + 2.0 * limit
        if not np.isfinite(band) or band <= 0:
            band = np.inf
        levels = int(min(np.ceil(radius / band), 1 << 20)) if np.isfinite(band) else 0
        span = 2 * side + 3
        return _PatchGrid(side, span, levels, band, span**3 * (2 * levels + 3))

    def keys(self, holder: np.ndarray, unit: _Columns, height: np.ndarray) -> np.ndarray:
        """Every face's cell numbers: by its normal and by its opposite, and
        by its plane's offset from the middle (a member's offset is within
        (cell / 2) * reach + limit of its seed's), its shape's cells first."""
        side, span, levels = self.side, self.span, self.levels
        keys = []
        for sign in (1.0, -1.0):
            code = holder * self.per_shape
            for axis, weight in enumerate((1, span, span * span)):
                cell = np.floor(sign * unit[axis] / _NORMAL_CELL)
                code += (np.clip(cell, -side, side).astype(np.int64) + side + 1) * weight
            if levels:
                level = np.floor(sign * height / self.band)
                code += (np.clip(level, -levels, levels).astype(np.int64) + levels + 1) * span**3
            else:
                code += span**3
            keys.append(code)
        return np.concatenate(keys)


def _widen_loose(
    loose_low: np.ndarray,
    loose_high: np.ndarray,
    holder: np.ndarray,
    loose: np.ndarray,
    low: _Columns,
    high: _Columns,
) -> None:
    """Widen each shape's box of thin faces (``loose_low``, ``loose_high``,
    (count, 3), in place) by the boxes of the faces ``loose`` of a block;
    ``holder`` is each face's shape."""
    if not len(loose):
        return
    # owners are non-decreasing: the shapes' faces follow each other
    held = holder[loose]
    runs = np.flatnonzero(np.concatenate([[True], held[1:] != held[:-1]]))
    for axis in range(3):
        np.minimum.at(loose_low[:, axis], held[runs], np.minimum.reduceat(low[axis][loose], runs))
        np.maximum.at(loose_high[:, axis], held[runs], np.maximum.reduceat(high[axis][loose], runs))


def _merged_cells(
    cells: list[tuple[np.ndarray, _Columns, _Columns]],
) -> tuple[np.ndarray, _Columns, _Columns]:
    """The blocks' cells merged: one box per cell."""
    if len(cells) == 1:
        return cells[0]
    group_keys = np.concatenate([keys for keys, _, _ in cells])
    group_low = [np.concatenate([c[1][axis] for c in cells]) for axis in range(3)]
    group_high = [np.concatenate([c[2][axis] for c in cells]) for axis in range(3)]
    everyone = np.arange(len(group_keys))
    return _cell_boxes(group_keys, everyone, group_low, group_high)


def _near_boxes(
    group_keys: np.ndarray,
    group_low: _Columns,
    group_high: _Columns,
    loose_low: np.ndarray,
    loose_high: np.ndarray,
    offsets: np.ndarray,
    grid: _PatchGrid,
) -> tuple[np.ndarray, np.ndarray]:
    """(k, 3) each: the box of each cell's neighbours at ``offsets`` (cell
    steps along the four axes) and of its shape's thin faces."""
    span = grid.span
    box_low, box_high = np.column_stack(group_low), np.column_stack(group_high)
    group_owner = group_keys // grid.per_shape
    near_low = loose_low[group_owner]
    near_high = loose_high[group_owner]
    for shift in offsets:
        wanted = group_keys + int(
            shift[0] + span * shift[1] + span * span * shift[2] + span**3 * shift[3]
        )
        at = np.minimum(np.searchsorted(group_keys, wanted), len(group_keys) - 1)
        hit = np.flatnonzero(group_keys[at] == wanted)
        near_low[hit] = np.minimum(near_low[hit], box_low[at[hit]])
        near_high[hit] = np.maximum(near_high[hit], box_high[at[hit]])
    return near_low, near_high


# Faces binned at a time by _patch_bound and _normal_bound.
_BIN_BLOCK = 1 << 14
# Shapes of this many faces or more are tried by _normal_bound first, with
# normal cells of this side (its grid: 19 x 19 x 19 cells by 19 levels).
_COARSE_FACES = 1 << 16
_COARSE_CELL = 1.0 / 8.0
# _normal_bound files runs of this many consecutive faces whole, when a run's
# box is at most _CHUNK_REACH of the size looked for across.
_CHUNK = 32
_CHUNK_REACH = 1.0 / 16.0
# x, y and z of points or vectors, one array each.
_Columns = list[np.ndarray]


def _face_values(
    faces: np.ndarray,
    columns: np.ndarray,
    middle: np.ndarray,
    normals: np.ndarray | None = None,
) -> tuple[_Columns, _Columns, _Columns, np.ndarray, np.ndarray]:
    """Per face of ``faces`` (rows of vertex indices into the coordinate
    ``columns``, (3, n)): its box (low and high columns), unit normal
    (columns), the offset of its plane from ``middle`` (through its first
    corner) and twice its area. ``normals``, when given, (k, 3): the faces'
    unnormalised normals written into it, the numbers of
    :func:`shadowgeo.topology.block_normals`."""
    first, second, third = faces[:, 0], faces[:, 1], faces[:, 2]
    corners = [[column[first], column[second], column[third]] for column in columns]
    # block_normals' arithmetic, on the corners gathered here
    (ux, uy, uz), (vx, vy, vz) = ([b - a for a, b, _ in corners], [c - a for a, _, c in corners])
    normal = [uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx]
    if normals is not None:
        for axis in range(3):
            normals[:, axis] = normal[axis]
    low = [np.minimum(np.minimum(a, b), c) for a, b, c in corners]
    high = [np.maximum(np.maximum(a, b), c) for a, b, c in corners]
    doubled = np.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        unit = [axis / doubled for axis in normal]
        height = sum(
            u * (a - m) for u, (a, _, _), m in zip(unit, corners, middle.tolist(), strict=True)
        )
    return low, high, unit, height, doubled


def _sharpness(
    low: _Columns, high: _Columns, unit: _Columns, doubled: np.ndarray, width: float
) -> tuple[np.ndarray, np.ndarray]:
    """Per face (its :func:`_face_values`): whether it has a normal, and
    whether it is sharp (its smallest height at least ``width``, so that it
    turns from a patch's plane by less than half a cell).

    A face is taken for sharp when twice its area is at least ``width``
    times its box's diagonal, which is at least its longest side: a face
    taken is sharp, and one on the edge counts as thin, which only widens a
    bound."""
    with np.errstate(invalid="ignore", over="ignore"):
        binned = np.isfinite(unit[0]) & np.isfinite(unit[1]) & np.isfinite(unit[2])
        binned &= doubled > 0
        sharp = binned & (doubled >= width * _diagonal(low, high))
    return binned, sharp


def _runs_reduced(pick: np.ufunc, values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``pick`` (minimum or maximum) of each run of ``_CHUNK`` consecutive
    ``values`` (``starts``: every run's first), the last run perhaps shorter:
    ``pick.reduceat(values, starts)``, by halving the whole runs (twice as
    quick). NaN propagates, as it does through reduceat."""
    whole = len(values) // _CHUNK * _CHUNK
    if whole < len(values) or _CHUNK & (_CHUNK - 1):
        return pick.reduceat(values, starts)
    runs = values
    while len(runs) > len(starts):
        runs = pick(runs[0::2], runs[1::2])
    return runs


def _cell_boxes(
    keys: np.ndarray, faces: np.ndarray, low: _Columns, high: _Columns
) -> tuple[np.ndarray, _Columns, _Columns]:
    """The distinct ``keys`` (sorted) and the box of the boxes filed under
    each (box ``faces[i]`` of the columns ``low``, ``high`` under
    ``keys[i]``): a block's faces into cells, and the blocks' cells into one."""
    order = np.argsort(keys, kind="stable")
    keys, faces = keys[order], faces[order]
    starts = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
    box_low = [np.minimum.reduceat(column[faces], starts) for column in low]
    box_high = [np.maximum.reduceat(column[faces], starts) for column in high]
    return keys[starts], box_low, box_high
