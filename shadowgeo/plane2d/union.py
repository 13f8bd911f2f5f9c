"""The 2-D union: the one entry every union of loops in shadowgeo goes
through (:func:`unite`), with Clipper2's budgets checked in it, and the
region operations after it (:func:`intersect`, :func:`subtract`, :func:`add`).

:func:`unite` chooses the road: many strictly convex loops in groups (a city
of box buildings) by their arrangement (:mod:`shadowgeo.arrangement`, no
Clipper2 call); many other loops in groups cell by cell of a grid, then once
more near the cells' borders; the rest in one call of manifold3d's
``CrossSection`` (Clipper2 in C++), refused with a
:class:`~shadowgeo.errors.BudgetError` before it starts when it would take
minutes (:mod:`.budget`). Clipper2 rounds coordinates to 1e-8, so callers work
in a *local frame* whose units make the region as large as Clipper2 handles
safely (:func:`local_scale`, ``MAX_COORDINATE``); rounding then costs about
1e-16 of the region's size.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Literal, overload

import numpy as np
from manifold3d import CrossSection, FillRule

from ..arrangement import convex_union_flat
from ..errors import BudgetError
from ..limits import MAX_UNION_CROSSINGS, MAX_UNION_SWEEP
from ..orientation import MAX_COORDINATE, turns
from ..topology import loop_rings
from .budget import FEWEST_CROSSING_EDGES, crossings_estimate, sweep_work
from .nesting import FlatParts, components, region_loops
from .predicates import signed_areas, whole_loop

__all__ = [
    "ARRANGED_LOOPS",
    "Form",
    "Rule",
    "add",
    "holds_box",
    "intersect",
    "local_scale",
    "subtract",
    "triangles_region",
    "unite",
    "without_copies",
]

# Which points a union keeps: winding number > 0, != 0, or odd.
Rule = Literal["positive", "nonzero", "evenodd"]
# What it gives: the region (to intersect with others), its parts
# ([outer, hole, ...] lists), or, from the arrangement, the parts flat.
Form = Literal["region", "parts", "flat"]
_FILL_RULES = {
    "positive": FillRule.Positive,
    "nonzero": FillRule.NonZero,
    "evenodd": FillRule.EvenOdd,
}

# Unions of at least this many loops drop exact copies first (without_copies).
_COPIES_CHECKED = 64
# Loops in groups above this are united cell by cell first, about
# _CELL_LOOPS to a cell (below it one union is faster).
_GROUPED_LOOPS = 2000
_CELL_LOOPS = 100
# Convex loops in groups are tried by their arrangement from this many on
# (below it the numpy steps' fixed costs outweigh Clipper2's).
ARRANGED_LOOPS = 64


@overload
def unite(
    loops: list[np.ndarray],
    *,
    rule: Rule = ...,
    cells: np.ndarray | None = ...,
    groups: Callable[[], np.ndarray] | None = ...,
    form: Literal["region"] = ...,
) -> CrossSection: ...
@overload
def unite(
    loops: list[np.ndarray],
    *,
    rule: Rule = ...,
    cells: np.ndarray | None = ...,
    groups: Callable[[], np.ndarray] | None = ...,
    form: Literal["parts"],
) -> list[list[np.ndarray]]: ...
@overload
def unite(
    loops: list[np.ndarray],
    *,
    rule: Rule = ...,
    cells: np.ndarray | None = ...,
    groups: Callable[[], np.ndarray] | None = ...,
    form: Literal["flat"],
) -> FlatParts | list[list[np.ndarray]]: ...


def unite(
    loops: list[np.ndarray],
    *,
    rule: Rule = "positive",
    cells: np.ndarray | None = None,
    groups: Callable[[], np.ndarray] | None = None,
    form: Form = "region",
) -> CrossSection | FlatParts | list[list[np.ndarray]]:
    """The region of points whose winding number over ``loops`` passes
    ``rule``: the one 2-D union of shadowgeo.

    Parameters
    ----------
    loops : list of (k, 2) float64
        Closed loops in a local frame (:func:`local_scale`).
    rule : {"positive", "nonzero", "evenodd"}
        Winding number > 0, != 0, or odd.
    cells : (len(loops),) non-decreasing labels, optional
        Loops laid out apart (no edge of one cell's loops meets another
        cell's, as many faces' pieces in cells of one plane): the crossing
        budget then counts pairs within a cell only.
    groups : callable returning (len(loops),) int, optional
        A label per loop, asked for only when there are many loops. The
        loops of one label together wind >= 0 at every point (all the
        outline loops of one connected part of a mesh, or one
        counter-clockwise triangle), so the positive region of the whole is
        the union of the groups' regions: many loops may then be united by
        their arrangement or cell by cell (see Notes). Only with the
        positive rule and without ``cells``.
    form : {"region", "parts", "flat"}
        What to return: the region, a ``CrossSection`` to intersect with
        others; its parts, ``[outer, hole, ...]`` lists of (k, 2) loops
        (outer loops counter-clockwise, holes clockwise, as
        :func:`~shadowgeo.plane2d.nesting.components` gives them); or the
        parts as one :class:`~shadowgeo.plane2d.nesting.FlatParts` when the
        arrangement made them (no array per loop), else as lists.

    Raises
    ------
    BudgetError
        When the loops' edges cross each other more than
        :data:`~shadowgeo.limits.MAX_UNION_CROSSINGS` times (estimated by
        :func:`~shadowgeo.plane2d.budget.crossings_estimate`): Clipper2's
        work grows with the crossings, more than linearly, so such a union
        would take minutes. Or when placing the edges in Clipper2's sweep
        takes more than :data:`~shadowgeo.limits.MAX_UNION_SWEEP` steps
        (counted by :func:`~shadowgeo.plane2d.budget.sweep_work`: many edges
        beginning on scanlines many edges span). Checked before each call of
        Clipper2 (each cell's, when cells are united first).

    Notes
    -----
    With ``groups``, :data:`ARRANGED_LOOPS` or more loops, all strictly
    convex and counter-clockwise (a city of box buildings), are first tried
    by their arrangement, which needs no Clipper2 call; where it cannot
    certify a sign (touching outlines) Clipper2 does the work. Clipper2's
    sweep keeps a list of the edges its scanline crosses, so one union of
    thousands of overlapping outlines scattered over a plane costs about
    n^1.5: more than ``_GROUPED_LOOPS`` loops in groups are therefore first
    united cell by cell of a grid of about ``_CELL_LOOPS`` loops each (every
    group in the cell of its first loop's box centre). A cell's part whose
    box meets no other cell's parts is final as it is; the rest, near the
    cells' borders, are united once more.

    Examples
    --------
    >>> square = np.array([[0.0, 0], [2, 0], [2, 2], [0, 2]])
    >>> unite([square, square + 1]).area()
    7.0
    >>> [len(part) for part in unite([square, square + 1], form="parts")]
    [1]
    """
    if groups is None:
        return _as_form(_clipped(loops, rule, cells), form)
    if rule != "positive" or cells is not None:
        raise ValueError("unite: groups unite by the positive rule, without cells")
    if len(loops) >= ARRANGED_LOOPS:
        boundary = convex_union_flat(loops)
        if boundary is not None:
            return _arranged(*boundary, form)
    if len(loops) <= _GROUPED_LOOPS:
        return _as_form(_clipped(loops), form)
    parts = _cell_parts(loops, groups)
    return _clipped([loop for part in parts for loop in part]) if form == "region" else parts


def _as_form(region: CrossSection, form: Form) -> CrossSection | list[list[np.ndarray]]:
    """A region Clipper2 made, as ``form`` asks for it."""
    return region if form == "region" else components(region)


def _arranged(
    points: np.ndarray, starts: np.ndarray, form: Form
) -> CrossSection | FlatParts | list[list[np.ndarray]]:
    """The boundary loops the arrangement found (``points``, loop ``i``
    from ``starts[i]``), as ``form`` asks for them: filled as a region, or
    nested into parts."""
    if form == "region":
        bounds = [*starts.tolist(), len(points)]
        return _clipped([points[a:b] for a, b in itertools.pairwise(bounds)])
    flat = FlatParts.nested(points, starts)
    return flat if form == "flat" else flat.parts()


def _clipped(
    loops: list[np.ndarray], rule: Rule = "positive", cells: np.ndarray | None = None
) -> CrossSection:
    """:func:`unite` by one call of Clipper2, within its budgets: every
    ``CrossSection`` made from loops in shadowgeo is made here."""
    if not loops:
        return CrossSection()
    if rule != "evenodd" and len(loops) >= _COPIES_CHECKED:
        kept = _without_copies_kept(loops)
        if kept is not None:
            loops = [loops[i] for i in kept]
            cells = None if cells is None else np.asarray(cells)[kept]
    _check_budget(loops, cells)
    contours = [np.ascontiguousarray(loop, dtype=np.float64) for loop in loops]
    return CrossSection(contours, _FILL_RULES[rule])


def _check_crossings(loops: list[np.ndarray], cells: np.ndarray | None, *, where: str = "") -> None:
    """Raise BudgetError when the edges of ``loops`` (within each of
    ``cells``) cross more than MAX_UNION_CROSSINGS times."""
    estimate, sampled = crossings_estimate(loops, cells)
    if estimate > MAX_UNION_CROSSINGS and sampled >= FEWEST_CROSSING_EDGES:
        n_edges = sum(map(len, loops))
        raise BudgetError(
            f"the shadow's outline ({len(loops)} loops, {n_edges} edges) has about "
            f"{estimate:.2g} edge crossings{where}, past the budget of "
            f"{MAX_UNION_CROSSINGS:,} (shadowgeo.limits.MAX_UNION_CROSSINGS)"
        )


def _check_budget(loops: list[np.ndarray], cells: np.ndarray | None) -> None:
    """Raise BudgetError when uniting ``loops`` would take Clipper2 past
    MAX_UNION_CROSSINGS crossings or MAX_UNION_SWEEP steps of its sweep
    (the crossings first: a tangle is named by those)."""
    _check_crossings(loops, cells)
    work = sweep_work(loops)
    if work > MAX_UNION_SWEEP:
        n_edges = sum(map(len, loops))
        raise BudgetError(
            f"the shadow's outline ({len(loops)} loops, {n_edges} edges) needs {work:.2g} "
            f"steps of the union's sweep (many corners on few lines), past the budget of "
            f"{MAX_UNION_SWEEP:,} (shadowgeo.limits.MAX_UNION_SWEEP)"
        )


def triangles_region(triangles: np.ndarray) -> CrossSection:
    """The region a (m, 3, 2) stack of triangles covers (a receiving patch
    seen in its plane): each turned counter-clockwise, those of no area
    dropped, united as one region."""
    areas = signed_areas(list(triangles))
    keep = areas != 0
    oriented = [t if a > 0 else t[::-1] for t, a in zip(triangles[keep], areas[keep], strict=True)]
    return unite(oriented)


def local_scale(extent: float) -> float:
    """Units per length that put the largest coordinate that will occur,
    ``extent``, at ``MAX_COORDINATE``: Clipper2's fixed 1e-8 grid is then
    about 1e-16 of the region's size."""
    return MAX_COORDINATE / extent


def without_copies(loops: list[np.ndarray]) -> list[np.ndarray]:
    """``loops`` less each loop that repeats an earlier one point for point
    (from any starting point), when no loop winds clockwise: a copy then only
    raises a winding that is already positive, so the positive and the
    nonzero region stay as they are, and Clipper2's sweep slows down on every
    coincident edge (twenty thousand clipped copies of four triangles took it
    seconds). With a clockwise loop (a hole) copies count, and all are kept.

    Examples
    --------
    >>> square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    >>> len(without_copies([square, np.roll(square, 1, axis=0), square + 2]))
    2
    >>> len(without_copies([square, np.roll(square, 1, axis=0), square[::-1]]))
    3
    """
    kept = _without_copies_kept(loops)
    return loops if kept is None else [loops[i] for i in kept]


def _without_copies_kept(loops: list[np.ndarray]) -> list[int] | None:
    """:func:`without_copies` as the indices of the loops it keeps (empty
    loops dropped too), or None when it keeps every loop."""
    lengths = np.array([len(loop) for loop in loops], dtype=np.int64)
    index = np.flatnonzero(lengths)  # the loops with points
    some_empty = len(index) < len(loops)
    if some_empty:
        loops = [loops[i] for i in index.tolist()]
        lengths = lengths[index]
    every = index.tolist() if some_empty else None  # (when no copy goes)
    points = np.concatenate(loops).astype(np.float64).reshape(-1, 2)
    starts, following = loop_rings(lengths)  # each loop closes
    with np.errstate(over="ignore", invalid="ignore"):
        cross = points[:, 0] * points[following, 1] - points[:, 1] * points[following, 0]
        doubled = np.add.reduceat(cross, starts)
    if not np.all(doubled >= 0):  # a clockwise loop (or an overflow): copies count
        return every
    # extremes do not depend on where a loop starts: equal for copies
    keys = np.column_stack(
        [
            lengths.astype(np.float64),
            np.minimum.reduceat(points[:, 0], starts),
            np.maximum.reduceat(points[:, 0], starts),
            np.minimum.reduceat(points[:, 1], starts),
            np.maximum.reduceat(points[:, 1], starts),
        ]
    )
    order = np.lexsort(keys.T[::-1])
    same = np.all(keys[order][1:] == keys[order][:-1], axis=1)
    if not same.any():
        return every
    suspects = np.zeros(len(loops), dtype=bool)
    suspects[order[1:][same]] = True
    suspects[order[:-1][same]] = True
    # Each suspect from its least point (by x, then y; the first of equal
    # ones), bit for bit: a copy is a later suspect of the same length with
    # the same points from there. Suspects of one length at a time.
    dropped = np.zeros(len(loops), dtype=bool)
    chosen = np.flatnonzero(suspects)
    for length in np.unique(lengths[chosen]).tolist():
        members = chosen[lengths[chosen] == length]
        rows = points[starts[members][:, None] + np.arange(length)]  # (m, length, 2)
        x, y = rows[:, :, 0], rows[:, :, 1]
        least = np.where(x == x.min(axis=1, keepdims=True), y, np.inf)
        first = np.argmin(least, axis=1)  # (the first of the least)
        turned = np.take_along_axis(
            rows, ((np.arange(length) + first[:, None]) % length)[:, :, None], axis=1
        )
        flat = np.ascontiguousarray(turned).reshape(len(members), 2 * length)
        keys = flat.view(np.dtype((np.void, 16 * length))).ravel()
        _, earliest = np.unique(keys, return_index=True)
        copy = np.ones(len(members), dtype=bool)
        copy[earliest] = False
        dropped[members[copy]] = True
    if not dropped.any():
        return every
    kept: list[int] = index[~dropped].tolist()
    return kept


def _cell_parts(
    loops: list[np.ndarray], groups: Callable[[], np.ndarray]
) -> list[list[np.ndarray]]:
    """The parts of :func:`unite` cell by cell (see its Notes)."""
    low, high = _boxes(loops)
    labels = np.asarray(groups(), dtype=np.int64)
    labels = labels - labels.min()
    first = np.full(int(labels.max()) + 1, len(loops), dtype=np.int64)
    np.minimum.at(first, labels, np.arange(len(loops)))
    centres = 0.5 * (low + high)
    anchor = centres[first[labels]]  # each loop placed by its group's first loop
    count = math.ceil(math.sqrt(len(loops) / _CELL_LOOPS))
    bottom, top = anchor.min(axis=0), anchor.max(axis=0)
    span = np.where(top > bottom, top - bottom, 1.0)
    cell_xy = np.minimum(((anchor - bottom) / span * count).astype(np.int64), count - 1)
    cell = cell_xy[:, 0] * count + cell_xy[:, 1]
    order = np.argsort(cell, kind="stable")
    # All the cells' unions under one budget, counted before the first runs:
    # each alone may pass it while together they take minutes (a twisted
    # Extrusion's shadow of 1,233 loops in cells of near 2e6 crossings
    # each, 8 CPU-s a cell: fuzz campaign, seed 39, x3dz mutant 1236).
    _check_crossings(
        [loops[i] for i in order.tolist()], cell[order], where=" in its cells together"
    )
    bounds = np.searchsorted(cell[order], np.arange(count * count + 1))
    parts: list[list[np.ndarray]] = []
    owner: list[int] = []
    for index in range(count * count):
        members = order[bounds[index] : bounds[index + 1]].tolist()
        if members:
            united = components(_clipped([loops[i] for i in members]))
            parts.extend(united)
            owner.extend([index] * len(united))
    final = _final_parts(parts, np.array(owner, dtype=np.int64))
    rest = [loop for part, done in zip(parts, final, strict=True) if not done for loop in part]
    kept = [part for part, done in zip(parts, final, strict=True) if done]
    return kept + components(_clipped(rest))


def _final_parts(parts: list[list[np.ndarray]], owner: np.ndarray) -> list[bool]:
    """Whether each cell's part is final: its outer loop's box meets no
    other cell's box of parts, so no other cell's part can touch it."""
    low, high = _boxes([part[0] for part in parts])
    n_cells = int(owner.max()) + 1
    cell_low = np.full((n_cells, 2), np.inf)
    cell_high = np.full((n_cells, 2), -np.inf)
    np.minimum.at(cell_low, owner, low)
    np.maximum.at(cell_high, owner, high)
    meets = (low[:, None, 0] <= cell_high[None, :, 0]) & (low[:, None, 1] <= cell_high[None, :, 1])
    meets &= (high[:, None, 0] >= cell_low[None, :, 0]) & (high[:, None, 1] >= cell_low[None, :, 1])
    meets[np.arange(len(parts)), owner] = False
    touched = np.asarray(np.any(meets, axis=1), dtype=bool)
    return [not flag for flag in touched.tolist()]


def _boxes(loops: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2) lower and upper corners of each loop's bounding box."""
    points = np.concatenate(loops)
    lengths = np.fromiter(map(len, loops), dtype=np.int64, count=len(loops))
    starts = np.cumsum(lengths) - lengths  # integers even for one loop
    return np.minimum.reduceat(points, starts, axis=0), np.maximum.reduceat(points, starts, axis=0)


def intersect(region: CrossSection, other: CrossSection) -> CrossSection:
    """The points of both ``region`` and ``other``."""
    return region ^ other


def subtract(region: CrossSection, other: CrossSection) -> CrossSection:
    """The points of ``region`` not in ``other``."""
    return region - other


def add(region: CrossSection, other: CrossSection) -> CrossSection:
    """The points of ``region`` or ``other``."""
    return region + other


def holds_box(region: CrossSection, low: np.ndarray, high: np.ndarray) -> bool:
    """Whether ``region`` certainly holds the box ``low``-``high`` (2-D,
    within +-MAX_COORDINATE): it is one convex counter-clockwise loop and
    every corner of the box lies left of each of its edges beyond rounding.
    Then the region's intersection with anything in the box is that thing,
    and the intersection (a sweep over both) can be skipped."""
    loops = region_loops(region)
    if not whole_loop(loops):
        return False
    loop = loops[0]
    after = np.roll(loop, -1, axis=0)
    if not np.all(turns(loop, after, np.roll(after, -1, axis=0))[0] == 1):
        return False  # not convex beyond rounding
    corners = np.array([low, [high[0], low[1]], high, [low[0], high[1]]], dtype=np.float64)
    origin = np.repeat(loop, 4, axis=0)
    sign, _ = turns(origin, np.repeat(after, 4, axis=0), np.tile(corners, (len(loop), 1)))
    return bool(np.all(sign == 1))
