"""The layout of many small 2-D problems in cells of Clipper2's range.

* hand-derived: two regions in a column sit at y = -M/2 and +M/2 (M the
  largest coordinate), x stretched to M/2 at the region's reach, y to a
  quarter of the cell; a grid of five regions is three by three;
* each region lands inside its own cell, apart from every other, and is
  found there again and mapped back to where it was;
* a region alone is stretched about the origin by its scale and nothing
  else: the plane's coordinates are its own times the scale, exactly.
"""

from __future__ import annotations

import numpy as np

from shadowgeo.cells import column_cells, grid_cells, own_cell
from shadowgeo.orientation import MAX_COORDINATE as M


def test_two_regions_in_a_column_by_hand():
    middle = np.array([[1.0, 2.0], [-3.0, 0.0]])
    cells = column_cells(np.array([2.0, 0.5]), middle)
    corners = np.array([[3.0, 2.0], [-3.0, 0.5]])  # at reach along x, at a quarter along y
    placed = cells.place(corners, np.array([0, 1]))
    # cell height M: y = centre + (reach / 4 of it) * (offset / reach)
    assert np.allclose(placed, [[M / 2, -M / 2], [0.0, M / 2 + M / 4]], rtol=1e-15)
    assert cells.cell_of(placed).tolist() == [0, 1]
    assert np.allclose(cells.restore(placed, np.array([0, 1])), corners, rtol=0, atol=1e-8)


def test_a_grid_of_five_is_three_by_three_and_keeps_regions_apart():
    rng = np.random.default_rng(5)
    middle = rng.normal(size=(5, 2)) * 100
    size = rng.uniform(0.1, 10.0, 5)
    cells = grid_cells(middle, size)
    assert (cells.columns, cells.rows) == (3, 3)
    cell = 2 * M / 3
    assert np.allclose(cells.centre[4], [-M + 1.5 * cell, -M + 1.5 * cell])
    # corners of each region's box (half of size about its middle) in the plane
    square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    boxes = middle[:, None] + 0.5 * size[:, None, None] * square[None]
    placed = cells.place(boxes, np.arange(5)[:, None])
    lows, highs = placed.min(axis=1), placed.max(axis=1)
    for k in range(5):
        column, row = k % 3, k // 3
        assert np.all(lows[k] > [-M + column * cell, -M + row * cell])
        assert np.all(highs[k] < [-M + (column + 1) * cell, -M + (row + 1) * cell])
        assert cells.cell_of(placed[k]).tolist() == [k] * 4
    back = cells.restore(placed.reshape(-1, 2), np.repeat(np.arange(5), 4))
    assert np.allclose(back, boxes.reshape(-1, 2), rtol=0, atol=1e-6)


def test_a_region_alone_is_only_stretched_about_the_origin():
    rng = np.random.default_rng(7)
    loop = rng.uniform(-3.0, 3.0, (9, 2))
    scale = M / 6.0  # the largest coordinate at half the range
    cells = own_cell(scale)
    placed = cells.place(loop, np.zeros(9, dtype=np.int64))
    assert np.array_equal(placed, loop * scale)  # bit for bit: the clipper sees loop * scale
    assert np.abs(placed).max() <= M / 2
    assert cells.cell_of(placed).tolist() == [0] * 9
    assert np.array_equal(cells.restore(placed, np.zeros(9, dtype=np.int64)), placed / scale)
