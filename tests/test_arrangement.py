"""The union of many convex loops by their arrangement, against shapely's
unions (GEOS) and brute force, with the touching, nested and collinear cases
that must either come out right or be handed back (None) to Clipper2."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import shapely

from shadowgeo.arrangement import convex_union, strictly_convex_loops
from shadowgeo.plane2d import nest, parts_area, unite


def _square(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def _random_convex(count: int, seed: int, spread: float = 10.0) -> list[np.ndarray]:
    """``count`` random convex loops (3 to 12 corners, counter-clockwise) of
    radius 0.3 to 3 in a square of side ``spread``."""
    rng = np.random.default_rng(seed)
    loops = []
    for _ in range(count):
        cloud = rng.normal(size=(3 * int(rng.integers(3, 13)), 2)) * rng.uniform(0.3, 3)
        hull = shapely.convex_hull(shapely.multipoints(cloud + rng.uniform(0, spread, 2)))
        loop = np.asarray(hull.exterior.coords)[:-1]
        loops.append(loop if shapely.LinearRing(loop).is_ccw else loop[::-1])
    return loops


def _region(parts: list[list[np.ndarray]]) -> shapely.Geometry:
    return shapely.MultiPolygon([shapely.Polygon(part[0], part[1:]) for part in parts])


def _check_against_shapely(loops: list[np.ndarray], parts: list[list[np.ndarray]]) -> None:
    reference = shapely.union_all([shapely.Polygon(loop) for loop in loops])
    region = _region(parts)
    assert region.is_valid
    assert parts_area(parts) == pytest.approx(reference.area, rel=1e-12)
    assert region.symmetric_difference(reference).area < 1e-12 * reference.area
    assert len(parts) == len(getattr(reference, "geoms", [reference]))
    holes = sum(len(part) - 1 for part in parts)
    assert holes == sum(len(p.interiors) for p in getattr(reference, "geoms", [reference]))


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("count, spread", [(5, 4.0), (60, 10.0), (400, 40.0)])
def test_random_convex_loops_unite_as_shapely_does(seed, count, spread):
    loops = _random_convex(count, seed, spread)
    boundary = convex_union(loops)
    assert boundary is not None  # random floats: no sign within rounding
    _check_against_shapely(loops, nest(boundary))


def test_a_ring_of_squares_leaves_a_courtyard_hole_with_an_island_in_it():
    ring = [_square(0, 0, 10, 2), _square(8, 0.5, 10.5, 10), _square(0, 8, 10, 10.5)]
    ring.append(_square(-0.5, 1, 2, 9))
    island = _square(4, 4, 6, 6)
    boundary = convex_union([*ring, island])
    assert boundary is not None
    parts = nest(boundary)
    _check_against_shapely([*ring, island], parts)
    assert sorted(len(part) for part in parts) == [1, 2]  # the ring with its hole, the island
    hole = next(part for part in parts if len(part) == 2)[1]
    # the courtyard is 2 < x < 8, 2 < y < 8; the island is a part of its own
    assert shapely.Polygon(hole).area == pytest.approx(36.0)


def test_nested_loops_leave_only_the_outer_one():
    outer = _square(0, 0, 10, 10)
    inner = [_square(1, 1, 3, 3), _square(2, 2, 9, 4), _square(5, 5, 6, 6)]
    boundary = convex_union([inner[0], outer, *inner[1:]])
    assert boundary is not None
    assert len(boundary) == 1
    assert shapely.Polygon(boundary[0]).equals(shapely.Polygon(outer))


def test_loops_apart_come_back_as_they_are():
    loops = [_square(3 * k, 0, 3 * k + 1, 1) for k in range(5)]
    boundary = convex_union(loops)
    assert boundary is not None
    assert sorted(map(tuple, (loop.min(axis=0) for loop in boundary))) == [
        (3.0 * k, 0.0) for k in range(5)
    ]


def test_collinear_edges_far_apart_along_one_line_are_not_a_doubt():
    # A row of overlapping pairs along y = 0: the bottom edges all lie on one
    # line (orientations exactly zero) but only overlapping pairs meet.
    loops = []
    for k in range(6):
        loops += [_square(10 * k, 0, 10 * k + 3, 2), _square(10 * k + 1, 1, 10 * k + 4, 5)]
    loops = [loop + [0.0, 0.37] for loop in loops]
    boundary = convex_union(loops)
    assert boundary is not None
    _check_against_shapely(loops, nest(boundary))


@pytest.mark.parametrize(
    "case",
    [
        [_square(0, 0, 1, 1), _square(1, 0, 2, 1)],  # a shared edge (terraced houses)
        [_square(0, 0, 1, 1), _square(1, 1, 2, 2)],  # touching at a corner
        [_square(0, 0, 1, 1), _square(0, 0, 1, 1)],  # the same loop twice
        [_square(0, 0, 2, 2), np.array([[1.0, 2], [3, 3], [1, 4]])],  # a corner on an edge
        [_square(0, 0, 2, 2), _square(0.5, 0, 1.5, 3)],  # collinear overlapping edges
        # three edges through one point
        [
            _square(0, 0, 2, 2),
            np.array([[1.0, 1], [3, 0], [3, 2]]),
            np.array([[1.0, 1], [1, 3], [-1, 3]]),
        ],
    ],
)
def test_uncertain_signs_are_handed_back_and_the_cells_unite_them(case):
    loops = case + [_square(40 + 3 * k, 40, 41 + 3 * k, 41) for k in range(70)]
    assert convex_union(loops) is None
    parts = unite(
        [loop * 1e6 for loop in loops], groups=lambda: np.arange(len(loops)), form="parts"
    )
    reference = shapely.union_all([shapely.Polygon(loop * 1e6) for loop in loops])
    assert parts_area(parts) == pytest.approx(reference.area, rel=1e-12)
    assert _region(parts).symmetric_difference(reference).area < 1e-12 * reference.area
    region = unite([loop * 1e6 for loop in loops], groups=lambda: np.arange(len(loops)))
    assert region.area() == pytest.approx(reference.area, rel=1e-12)


@pytest.mark.parametrize(
    "loop",
    [
        _square(0, 0, 1, 1)[::-1],  # clockwise
        np.array([[0.0, 0], [2, 1], [4, 0], [2, 3]]),  # concave
        np.array([[np.cos(a), np.sin(a)] for a in np.arange(5) * 4 * np.pi / 5]),  # winds twice
        np.array([[0.0, 0], [1, 0], [2, 0], [1, 1]]),  # a straight corner
    ],
)
def test_loops_that_are_not_strictly_convex_are_handed_back(loop):
    assert convex_union([loop, _square(5, 5, 6, 6)]) is None
    # and the test loop by loop says so of that loop alone
    loops = [_square(5, 5, 6, 6), loop, _square(7, 7, 8, 9)]
    sizes = np.array([len(each) for each in loops])
    assert strictly_convex_loops(np.concatenate(loops), sizes).tolist() == [True, False, True]


def test_convexity_loop_by_loop_sees_rounding_and_short_loops():
    triangle = np.array([[0.0, 0], [1, 0], [0, 1]])
    # a corner straight to within rounding of its products is not certainly
    # a left turn; one bent by more is
    nearly = np.array([[0.0, 0], [3, 1], [6, 2 + 1e-15], [1, 3]])
    bent = np.array([[0.0, 0], [3, 1], [6, 2 + 1e-9], [1, 3]])
    loops = [triangle, nearly, triangle[:2], bent]
    sizes = np.array([len(each) for each in loops])
    assert strictly_convex_loops(np.concatenate(loops), sizes).tolist() == [
        True,
        False,
        False,
        True,
    ]


def test_the_union_takes_the_arrangement_for_a_city_and_matches_shapely():
    # 300 rotated rectangles, cells of the pairing grid crossed everywhere
    rng = np.random.default_rng(4)
    loops = []
    for centre in rng.uniform(0, 200, (300, 2)):
        angle = rng.uniform(0, np.pi)
        axes = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * rng.uniform(2, 8, 2)
        loops.append(centre + corners @ axes)
    scaled = [loop * 1e5 for loop in loops]
    assert convex_union(scaled) is not None
    parts = unite(scaled, groups=lambda: np.arange(len(loops)), form="parts")
    _check_against_shapely(scaled, parts)
    region = unite(scaled, groups=lambda: np.arange(len(loops)))  # to intersect with limits
    assert region.area() == pytest.approx(parts_area(parts), rel=1e-12)


@pytest.mark.parametrize("spread", [20, 100_000], ids=["cell table", "cells bisected"])
def test_box_pairs_are_every_meeting_pair_once_against_brute_force(spread):
    from shadowgeo.arrangement import _box_pairs  # noqa: PLC2701 - the step under test

    rng = np.random.default_rng(2)
    low = rng.integers(0, 20, (300, 2)).astype(float)  # corners on the grid's lines
    low[::2] = rng.integers(0, spread, (150, 2))  # a sparse grid: far more cells than boxes
    high = low + rng.integers(0, 4, (300, 2))  # boxes touching, and points (empty boxes)
    order, first, second = _box_pairs(low, high)
    found = {
        tuple(sorted((int(order[i]), int(order[j])))) for i, j in zip(first, second, strict=True)
    }
    assert len(found) == len(first)  # each pair once
    expected = {
        (i, j)
        for i, j in itertools.combinations(range(300), 2)
        if np.all(low[i] <= high[j]) and np.all(low[j] <= high[i])
    }
    assert found == expected


def _boxes_mesh(corners_low: np.ndarray, size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned boxes [low, low + size] as one (vertices, faces) mesh."""
    unit = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    faces = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )  # fmt: skip
    vertices = corners_low[:, None, :] + unit[None] * size[:, None, :]
    return vertices.reshape(-1, 3), (faces[None] + 8 * np.arange(len(size))[:, None, None]).reshape(
        -1, 3
    )


@pytest.mark.parametrize("terraced", [False, True], ids=["apart", "terraced"])
def test_a_city_shadow_matches_the_union_of_each_box_shadow(monkeypatch, terraced):
    import shadowgeo.arrangement as arrangement
    from shadowgeo import DirectionalLight, Plane, project_shadow

    # Rows of boxes on the ground y = 0; terraced rows share their side
    # walls exactly (the outlines touch along an edge: handed back to the
    # cells), the others stand a little apart and their shadows overlap.
    rng = np.random.default_rng(5)
    rows, per_row, width = 10, 12, 10.0
    x = np.tile(np.arange(per_row) * (width if terraced else width + 0.5), rows)
    z = np.repeat(np.arange(rows) * 30.0, per_row)
    low = np.column_stack([x, np.zeros_like(x), z])
    size = np.column_stack(
        [np.full_like(x, width), rng.uniform(5, 40, len(x)), rng.uniform(8, 12, len(x))]
    )
    sun = DirectionalLight([0.45, -0.75, 0.3])
    ground = Plane([0, 1, 0], 0)
    taken = []
    arranged = arrangement.convex_union_arrays
    monkeypatch.setattr(
        arrangement,
        "convex_union_arrays",
        lambda points, sizes: taken.append(arranged(points, sizes)) or taken[-1],
    )
    shadow = project_shadow(_boxes_mesh(low, size), sun, ground)
    assert [found is None for found in taken] == [terraced]
    # each box's shadow: the hull of its corners' images along the sun
    vertices, _ = _boxes_mesh(low, size)
    direction = sun.direction
    flat = vertices - (vertices[:, 1:2] / direction[1]) * direction
    images = ground.to_2d(flat).reshape(-1, 8, 2)
    expected = shapely.union_all(shapely.convex_hull(shapely.multipoints(images)))
    assert shadow.area == pytest.approx(expected.area, rel=1e-9)
    region = shapely.MultiPolygon([shapely.Polygon(p[0], p[1:]) for p in shadow.polygons])
    assert region.symmetric_difference(expected).area < 1e-9 * expected.area


def test_a_courtyard_spanning_many_grid_cells_keeps_its_hole_and_islands():
    # 160 overlapping squares (side 3, turned a little each) in a ring round
    # a 100 x 100 courtyard: the pairing grid's cells are one square wide,
    # so the hole spans hundreds of them; islands inside it, one of them a
    # ring with its own pond.
    loops = []
    for k in range(160):
        t = k / 40.0
        side, along = divmod(t, 1.0)
        corner = [(0, 0), (100, 0), (100, 100), (0, 100)][int(side)]
        direction = [(1, 0), (0, 1), (-1, 0), (0, -1)][int(side)]
        centre = np.add(corner, np.multiply(direction, 100 * along))
        angle = 0.01 * k
        axes = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
        loops.append(centre + np.array([[-1.5, -1.5], [1.5, -1.5], [1.5, 1.5], [-1.5, 1.5]]) @ axes)
    islands = [_square(20 + 7 * k, 40.3, 25 + 7 * k, 45.3) for k in range(8)]
    pond_ring = [_square(60.0, 60.0, 70.0, 63.0), _square(60.2, 67.1, 70.3, 70.2)]
    pond_ring += [_square(59.5, 59.4, 62.7, 70.6), _square(67.3, 59.7, 70.6, 70.4)]
    everything = loops + islands + pond_ring
    boundary = convex_union(everything)
    assert boundary is not None
    parts = nest(boundary)
    _check_against_shapely(everything, parts)
    assert sum(len(part) - 1 for part in parts) == 2  # the courtyard and the pond
