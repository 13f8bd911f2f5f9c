"""Many small 2-D problems laid out in cells of Clipper2's range, for one call.

A union, intersection or triangulation of many small regions (one a receiver
face, or a caster triangle) is one Clipper2 or manifold3d call when each
region is moved by an affine map into a cell of its own in the plane
``[-MAX_COORDINATE, MAX_COORDINATE]^2``: no two regions meet, and the result
is cut back into regions by the cell each loop lies in. An affine map keeps
unions, intersections and valid triangulations.

Clipper2 sweeps along y, so a single column of cells (:func:`column_cells`)
has its scanlines meet one region at a time; a square grid
(:func:`grid_cells`) keeps a uniform scale for both axes. A region worked on
alone takes the whole plane (:func:`own_cell`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .orientation import MAX_COORDINATE

__all__ = ["Cells", "column_cells", "grid_cells", "own_cell"]


@dataclass(frozen=True)
class Cells:
    """Region ``k`` mapped as ``(p - middle[k]) * scale[k] + centre[k]``.

    Attributes
    ----------
    middle : (n, 2) float64 or None
        The point of each region put at its cell's centre (None: the origin).
    scale : (n, 2) float64
        The stretch of each region along x and y.
    centre : (n, 2) float64
        The centre of each region's cell.
    columns, rows : int
        The grid of cells, ``k = row * columns + column``.
    """

    middle: np.ndarray | None
    scale: np.ndarray
    centre: np.ndarray
    columns: int
    rows: int

    def place(self, points: np.ndarray, cell: np.ndarray) -> np.ndarray:
        """Points (..., 2) of regions ``cell`` (broadcast against points'
        leading axes) in the common plane."""
        if self.middle is not None:
            points = points - self.middle[cell]
        placed: np.ndarray = points * self.scale[cell] + self.centre[cell]
        return placed

    def cell_of(self, points: np.ndarray) -> np.ndarray:
        """(m,) the cell that holds each point (m, 2) of the common plane."""
        if len(self.scale) == 1:  # (a region alone: no arithmetic to do)
            return np.zeros(len(points), dtype=np.int64)
        column = np.floor((points[:, 0] + MAX_COORDINATE) / (2.0 * MAX_COORDINATE / self.columns))
        row = np.floor((points[:, 1] + MAX_COORDINATE) / (2.0 * MAX_COORDINATE / self.rows))
        column = np.clip(column, 0, self.columns - 1)
        row = np.clip(row, 0, self.rows - 1)
        index = (row * self.columns + column).astype(np.int64)
        found: np.ndarray = np.minimum(index, len(self.scale) - 1)
        return found

    def restore(self, points: np.ndarray, cell: np.ndarray) -> np.ndarray:
        """Points (m, 2) of the common plane, ``cell`` (m,) theirs, back in
        their regions' own frames."""
        points = (points - self.centre[cell]) / self.scale[cell]
        if self.middle is not None:
            points = points + self.middle[cell]
        return points


def column_cells(reach: np.ndarray, middle: np.ndarray | None = None) -> Cells:
    """n regions, each within ``reach`` (n,) of its ``middle`` (n, 2), in one
    column of cells: x stretched to half the plane's width, y to a quarter of
    the cell's height (with n regions, rounding on Clipper2's 1e-8 grid stays
    near n * 1e-16 of a region)."""
    count = len(reach)
    cell = 2.0 * MAX_COORDINATE / count
    centre = np.column_stack([np.zeros(count), -MAX_COORDINATE + cell * (np.arange(count) + 0.5)])
    scale = np.column_stack([0.5 * MAX_COORDINATE / reach, 0.25 * cell / reach])
    return Cells(middle, scale, centre, 1, count)


def grid_cells(middle: np.ndarray, size: np.ndarray) -> Cells:
    """n regions, each of width and height at most ``size`` (n,) about its
    ``middle`` (n, 2), in a square grid, scaled alike along x and y to
    0.45 of a cell."""
    count = len(size)
    columns = int(np.ceil(np.sqrt(count)))
    cell = 2.0 * MAX_COORDINATE / columns
    slot = np.arange(count)
    centre = np.column_stack(
        [
            -MAX_COORDINATE + cell * (slot % columns + 0.5),
            -MAX_COORDINATE + cell * (slot // columns + 0.5),
        ]
    )
    scale = 0.45 * cell / size
    return Cells(middle, np.column_stack([scale, scale]), centre, columns, columns)


def own_cell(scale: float) -> Cells:
    """One region alone in the plane, stretched by ``scale`` alike along x and
    y about the origin (its frame's origin stays the plane's centre)."""
    return Cells(None, np.array([[scale, scale]]), np.zeros((1, 2)), 1, 1)
