"""Polygon helpers shared by the X3D and USD readers: convexity and
triangulation of same-size polygon blocks, checked against shapely areas and
hand-derived triangles."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from reference import check_tiling

from shadowgeo.plane2d import fan, is_convex, polygons_triangles
from shadowgeo.topology import empty_mesh


def _in_plane(flat: np.ndarray, seed: int) -> np.ndarray:
    """(k, 2) points placed on a random plane in 3-D by a random rotation and offset."""
    rng = np.random.default_rng(seed)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return np.column_stack([flat, np.zeros(len(flat))]) @ rotation.T + rng.normal(size=3) * 10


SQUARE = np.array([[0.0, 0], [2, 0], [2, 2], [0, 2]])
DART = np.array([[0.0, 0], [2, 1], [4, 0], [2, 3]])  # concave at (2, 1)
HEXAGON = np.array([[np.cos(a), np.sin(a)] for a in np.arange(6) * np.pi / 3])
PENTAGRAM = np.array([[np.cos(a), np.sin(a)] for a in np.arange(5) * 4 * np.pi / 5])


@pytest.mark.parametrize(
    "flat, expected",
    [(SQUARE, True), (SQUARE[::-1], True), (HEXAGON, True), (DART, False), (DART[::-1], False)],
)
def test_convexity_in_any_plane_and_winding(flat, expected):
    corners = np.stack([_in_plane(flat, seed) for seed in range(5)])
    assert is_convex(corners).tolist() == [expected] * 5


def test_a_star_that_winds_twice_is_not_convex():
    # Every turn is to the same side, but the turns add up to two full turns.
    assert not is_convex(_in_plane(PENTAGRAM, 3)[None])[0]


def test_fan_is_from_the_first_corner():
    assert fan(np.array([[5, 6, 7, 8, 9]])).tolist() == [[5, 6, 7], [5, 7, 8], [5, 8, 9]]


def test_mixed_block_is_triangulated_with_the_area_of_each_polygon():
    points = np.concatenate([_in_plane(SQUARE, 1), _in_plane(DART, 2), _in_plane(DART, 4)])
    block = np.arange(12).reshape(3, 4)
    triangles, rows = polygons_triangles(points, block)
    assert triangles.shape == (6, 3) and len(rows) == 6
    corners = points[triangles]
    areas = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    for row, flat in enumerate([SQUARE, DART, DART]):
        mine = rows == row
        assert set(triangles[mine].ravel()) <= set(block[row])
        assert np.isclose(areas[mine].sum(), shapely.Polygon(flat).area)
    # The non-convex polygons come first, then the fans.
    assert rows.tolist() == [1, 1, 2, 2, 0, 0]


def test_known_convex_polygons_are_fanned_untested():
    points = _in_plane(DART, 0)
    triangles, rows = polygons_triangles(points, np.array([[0, 1, 2, 3]]), convex=True)
    assert triangles.tolist() == [[0, 1, 2], [0, 2, 3]] and rows.tolist() == [0, 0]


def test_empty_mesh_has_nothing():
    mesh = empty_mesh()
    assert mesh.vertices.shape == (0, 3) and mesh.faces.shape == (0, 3)
    assert mesh.faces.dtype == np.int64


def _random_outlines(count: int, seed: int) -> list[np.ndarray]:
    """``count`` random overlapping convex outlines (counter-clockwise) in a
    square that holds about four of them per side: unions with holes,
    islands in holes and one big part."""
    rng = np.random.default_rng(seed)
    outlines = []
    for centre in rng.uniform(0, 40, (count, 2)):
        angles = np.sort(rng.uniform(0, 2 * np.pi, rng.integers(3, 9)))
        radius = rng.uniform(1, 6)
        outlines.append(centre + radius * np.column_stack([np.cos(angles), np.sin(angles)]))
    return outlines


@pytest.mark.parametrize("seed", range(4))
def test_parts_match_clipper_decompose_and_shapely(seed):
    from shadowgeo.plane2d import components, parts_area, unite

    outlines = _random_outlines(300, seed)
    region = unite([loop * 1e6 for loop in outlines])
    parts = components(region)
    reference = shapely.union_all([shapely.Polygon(loop * 1e6) for loop in outlines])
    assert parts_area(parts) == pytest.approx(reference.area, rel=1e-12)

    # each part is one of shapely's connected polygons: same outer area, same holes
    def areas(loops):  # rounded to a millionth of the unit: far above Clipper's grid
        return round(shapely.Polygon(loops[0]).area, -6), sorted(
            round(shapely.Polygon(hole).area, -6) for hole in loops[1:]
        )

    expected = sorted(
        areas([p.exterior, *p.interiors]) for p in getattr(reference, "geoms", [reference])
    )
    got = sorted(areas(loops) for loops in parts)
    assert got == expected
    assert len(parts) == len(region.decompose())


def test_nest_puts_an_island_in_a_hole_in_its_own_part():
    from shadowgeo.plane2d import nest

    outer = np.array([[0.0, 0], [10, 0], [10, 10], [0, 10]])
    hole = np.array([[2.0, 2], [2, 8], [8, 8], [8, 2]])  # clockwise
    island = np.array([[4.0, 4], [6, 4], [6, 6], [4, 6]])
    parts = nest([island, hole, outer])
    assert sorted(len(part) for part in parts) == [1, 2]
    big = next(part for part in parts if len(part) == 2)
    assert big[0] is outer and big[1] is hole


def test_a_part_with_many_holes_is_triangulated_in_tiles_with_its_exact_area():
    from shadowgeo.plane2d import components, parts_area, triangulate_parts, unite

    grid = np.arange(20) * 3.0
    square = np.array([[0.0, 0], [0, 1], [1, 1], [1, 0]])  # clockwise: holes
    holes = [square + [x, y] for x in grid for y in grid]
    outer = np.array([[-1.0, -1], [60, -1], [60, 60], [-1, 60]])
    parts = components(unite([outer * 1e6] + [hole * 1e6 for hole in holes]))
    assert len(parts) == 1 and len(parts[0]) == 401
    points, faces = triangulate_parts(parts)
    corners = points[faces]
    first, second = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    doubled = first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]
    assert np.all(doubled > 0)
    expected = (61.0 * 61.0 - 400.0) * 1e12
    assert doubled.sum() / 2 == pytest.approx(expected, rel=1e-12)
    assert parts_area(parts) == pytest.approx(expected, rel=1e-12)


def test_union_parts_equal_one_union_and_shapely_past_the_cell_threshold():
    from shadowgeo.plane2d import components, parts_area, unite

    rng = np.random.default_rng(9)
    outlines = _random_outlines(2400, 1)
    outlines = [loop * 4.0 for loop in outlines]  # radius 4 to 24, about half the square covered
    outlines = [loop + rng.uniform(0, 1500, 2) for loop in outlines]
    groups = list(range(len(outlines)))
    # Groups of several loops: rings (outer counter-clockwise, hole clockwise),
    # whose hole loop alone winds -1: it must stay in its outer's cell.
    rings = []
    for centre in rng.uniform(0, 1500, (60, 2)):
        angles = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        circle = np.column_stack([np.cos(angles), np.sin(angles)])
        rings.append((centre + 30 * circle, centre + 12 * circle[::-1]))
    for row in range(3):  # long bars with a hole near one end: far from the bar's centre
        y = 200.0 + 500 * row
        bar = np.array([[0.0, y], [1500, y], [1500, y + 40], [0, y + 40]])
        rings.append(
            (bar, np.array([[1400.0, y + 10], [1400, y + 30], [1450, y + 30], [1450, y + 10]]))
        )
    loops = outlines + [loop for ring in rings for loop in ring]
    groups = np.array(groups + [len(outlines) + k for k in range(len(rings)) for _ in range(2)])
    scaled = [loop * 1e4 for loop in loops]
    grouped = unite(scaled, groups=lambda: groups, form="parts")
    direct = unite(scaled)
    reference = shapely.union_all(
        [shapely.Polygon(loop * 1e4) for loop in outlines]
        + [shapely.Polygon(outer * 1e4, [hole * 1e4]) for outer, hole in rings]
    )
    assert parts_area(grouped) == pytest.approx(reference.area, rel=1e-12)
    assert parts_area(components(direct)) == pytest.approx(reference.area, rel=1e-12)
    assert len(grouped) == len(getattr(reference, "geoms", [reference]))
    region = unite(scaled, groups=lambda: groups)
    assert region.area() == pytest.approx(reference.area, rel=1e-12)
    # a few loops take the one-union path, the same region
    few = scaled[:50]
    few_parts = unite(few, groups=lambda: groups[:50], form="parts")
    assert parts_area(few_parts) == pytest.approx(unite(few).area())


def test_union_parts_keep_an_islands_hole_when_the_part_around_it_is_united_again():
    from shadowgeo.plane2d import parts_area, unite

    def square(x0, y0, x1, y1):
        return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)

    # A square ring whose outline reaches a neighbour cell's filler square
    # (so the ring is united again), and in its courtyard an island with a
    # pond, in the ring's own cell: the island's part is final, pond and all.
    ring = [square(0, 0, 100, 100), square(10, 10, 90, 90)[::-1]]
    island = [square(40, 40, 60, 60), square(45, 45, 55, 55)[::-1]]
    fillers = [
        square(200 + 3 * (k % 50), 3 * (k // 50), 201 + 3 * (k % 50), 1 + 3 * (k // 50))
        for k in range(2500)
    ]
    fillers.append(square(95, 50, 205, 52))  # reaches from the fillers into the ring
    loops = ring + island + fillers
    groups = np.array([0, 0, 1, 1] + list(range(2, 2 + len(fillers))))
    parts = unite([loop * 1e5 for loop in loops], groups=lambda: groups, form="parts")
    reference = shapely.union_all(
        [shapely.Polygon(ring[0], [ring[1]]), shapely.Polygon(island[0], [island[1]])]
        + [shapely.Polygon(loop) for loop in fillers]
    )
    assert parts_area(parts) == pytest.approx(reference.area * 1e10, rel=1e-12)
    assert sorted(len(part) for part in parts)[-2:] == [2, 2]  # ring and island keep their holes


@pytest.mark.parametrize("batch", [4_000_000, 7])
def test_nest_puts_each_hole_in_the_smallest_loop_around_it(monkeypatch, batch):
    import shadowgeo.plane2d as plane2d

    # Concentric rings of squares, two nests side by side: outer loops
    # (counter-clockwise) at half-widths 10, 6, 2 and holes (clockwise) at
    # 8, 4; every hole has all the larger outer loops of its nest as
    # candidates, and the test must pick the nearest one. Small batches
    # split one hole's candidates between batches.
    monkeypatch.setattr(plane2d.nesting, "_NEST_EDGES", batch)

    def square(centre, half, clockwise):
        loop = centre + half * np.array([[-1.0, -1], [1, -1], [1, 1], [-1, 1]])
        return loop[::-1] if clockwise else loop

    loops = [
        square(np.array([x, 0.0]), half, half % 4 == 0)
        for x in (0.0, 30.0)
        for half in (10, 8, 6, 4, 2)
    ]
    order = np.random.default_rng(1).permutation(len(loops))
    parts = plane2d.nest([loops[i] for i in order])
    shapes = sorted(
        (float(part[0][:, 0].mean()), float(part[0][:, 0].max() - part[0][:, 0].mean()),
         [float(hole[:, 0].max() - hole[:, 0].mean()) for hole in part[1:]])
        for part in parts
    )  # fmt: skip
    expected = [(x, 2.0, []) for x in (0.0, 30.0)]
    expected += [(x, 6.0, [4.0]) for x in (0.0, 30.0)]
    expected += [(x, 10.0, [8.0]) for x in (0.0, 30.0)]
    assert shapes == sorted(expected)
    reference = shapely.union_all([shapely.Polygon(part[0], part[1:]) for part in parts])
    assert reference.area == pytest.approx(2 * (400 - 256 + 144 - 64 + 16))


def test_union_parts_of_one_group_past_the_cell_threshold_is_one_part():
    # A fan of 2,400 triangles round one point, all of one group (the
    # triangles of one connected caster, as method="triangles" gives them):
    # every loop lands in one cell, which unites into one part. (The cells'
    # box helper used to fail on a single part: its loop starts came out
    # as floats.) The triangles share the centre, so the arrangement hands
    # them back to the cells.
    from shadowgeo.arrangement import convex_union
    from shadowgeo.plane2d import parts_area, unite

    count = 2400
    angles = np.arange(count + 1) * 2 * np.pi / count
    rim = 1e6 * np.column_stack([np.cos(angles), np.sin(angles)])
    loops = [np.array([[0.0, 0.0], rim[k], rim[k + 1]]) for k in range(count)]
    assert convex_union(loops) is None
    parts = unite(loops, groups=lambda: np.zeros(count, dtype=np.int64), form="parts")
    assert len(parts) == 1 and len(parts[0]) == 1
    expected = 0.5 * count * np.sin(2 * np.pi / count) * 1e12  # the regular 2,400-gon
    assert parts_area(parts) == pytest.approx(expected, rel=1e-12)


def test_loops_that_are_all_holes_bound_no_region():
    """Found by the fuzzing campaign (x3dv mutant 2618): Clipper2 rounds a
    sliver to its grid and can hand back only clockwise loops; nesting them
    with no outer loop raised from an argmax over nothing."""
    from shadowgeo.plane2d import nest, nest_flat

    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    holes = [square[::-1], square[::-1] + 3.0]
    assert nest(holes) == []
    assert nest_flat(np.concatenate(holes), np.array([0, 4])) == []
    # a hole beside an outer loop it is not in stays out of every part
    parts = nest_flat(np.concatenate([square * 2.0, square[::-1] + 5.0]), np.array([0, 4]))
    assert len(parts) == 1 and len(parts[0]) == 1


def test_flat_parts_give_the_area_and_reach_of_their_nested_loops():
    # Two squares with a hole each, one with an island in its hole, a hole
    # in nothing: the flat parts' area and reach are those of the parts
    # nest gives, loop arrays cut from one array.
    from shadowgeo.plane2d import FlatParts, nest, parts_area

    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    loops = [
        square * 10,
        (square * 4 + 3)[::-1],
        square * 2 + 4,
        square * 10 + [20, -30],
        (square * 3 + [22, -27])[::-1],
        (square + 50)[::-1],
    ]
    lengths = np.array([len(loop) for loop in loops])
    flat = FlatParts.nested(np.concatenate(loops), np.cumsum(lengths) - lengths)
    expected = nest(loops)
    parts = flat.parts()
    assert [[loop.tolist() for loop in part] for part in parts] == [
        [loop.tolist() for loop in part] for part in expected
    ]
    assert flat.area == pytest.approx(parts_area(expected), rel=1e-15)
    assert flat.area == pytest.approx(100 - 16 + 4 + 100 - 9, rel=1e-15)
    # the second square's outer loop (x 20..30, y -30..-20); the stray hole is no part
    assert flat.reach() == 30.0
    moved = flat.parts(flat.cut(flat.points + 1.0))
    pairs = [(a, b) for p, q in zip(parts, moved, strict=True) for a, b in zip(p, q, strict=True)]
    assert all(np.array_equal(a + 1.0, b) for a, b in pairs)


def _star(n: int, rng: np.random.Generator, spikes: bool = True) -> np.ndarray:
    """A loop of ``n`` (even) corners star-shaped round the mean of its
    corners: nearly even angles, radii alternating long and short (spikes)
    or drawn from [0.6, 1] (a wobbly disc)."""
    gaps = rng.uniform(0.95, 1.05, n)
    angles = np.cumsum(gaps) / gaps.sum() * 2 * np.pi
    if spikes:
        radius = np.where(np.arange(n) % 2 == 0, 1.0, 0.3) + rng.uniform(-0.01, 0.01, n)
    else:
        radius = rng.uniform(0.6, 1.0, n)
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("spikes", [True, False])
def test_a_star_shaped_loop_is_cut_into_ears_of_its_own_corners(seed, spikes):
    from shadowgeo.plane2d import star_triangles

    rng = np.random.default_rng(seed)
    n = 2 * int(rng.integers(3, 200)) if spikes else 2 * int(rng.integers(3, 30))
    loop = _star(n, rng, spikes) * 10.0 ** rng.uniform(-6, 6)
    loop += rng.uniform(-1, 1, 2) * np.abs(loop).max()  # the mean off the origin
    faces = star_triangles(loop)
    assert faces is not None
    check_tiling(loop, faces)


def test_loops_not_star_shaped_round_their_mean_are_left_to_the_general_way():
    from shadowgeo.plane2d import star_triangles

    # a C whose corners' mean lies in its gap; the same loop clockwise; a
    # star that winds twice
    c_shape = np.array([[0, 0], [4, 0], [4, 1], [1, 1], [1, 3], [4, 3], [4, 4], [0, 4]], float)
    assert star_triangles(c_shape) is None
    rng = np.random.default_rng(1)
    assert star_triangles(_star(50, rng)[::-1]) is None
    angles = np.arange(5) * 4 * np.pi / 5
    assert star_triangles(np.column_stack([np.cos(angles), np.sin(angles)])) is None


def test_a_rectangle_whose_diagonals_meet_at_its_mean_is_still_triangulated():
    from shadowgeo.plane2d import star_triangles

    square = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    faces = star_triangles(square)
    assert faces is not None
    check_tiling(square, faces)


def test_a_star_of_many_spikes_is_not_handed_to_manifold3d(monkeypatch):
    """manifold3d's ear clipping is quadratic in reflex corners (a star of
    50,000 spikes takes it 7 s): polygon_triangles and triangulate_parts cut
    such a loop themselves, and still tile it exactly."""
    import shadowgeo.plane2d as plane2d

    rng = np.random.default_rng(3)
    loop = _star(8000, rng)

    def refuse(loops):
        raise AssertionError("manifold3d triangulated the star")

    monkeypatch.setattr(plane2d.triangulation, "triangulate", refuse)
    points, faces = plane2d.triangulate_parts([[loop * 1e6]])
    check_tiling(points / 1e6, faces)
    spatial = np.column_stack([loop[:, 0], np.full(len(loop), 2.0), loop[:, 1]])
    # counter-clockwise in (x, z) is clockwise seen from +y: its normal is -y
    for corners, sign in ((spatial, -1.0), (spatial[::-1], 1.0)):
        faces = plane2d.polygon_triangles(corners)
        triangles = corners[faces]
        normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        assert len(faces) == len(loop) - 2
        assert np.all(sign * normals[:, 1] > 0)  # wound as the polygon is
        assert np.allclose(normals[:, [0, 2]], 0.0)
        area = 0.5 * np.abs(normals[:, 1]).sum()
        assert np.isclose(area, shapely.Polygon(loop).area, rtol=1e-12)


def test_copies_of_loops_from_any_start_are_dropped_the_first_kept():
    from shadowgeo.plane2d import without_copies

    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    with_repeat = np.array([[0.0, 0], [1, 0], [1, 0], [0, 1]])  # a corner twice
    loops = [
        square,
        np.zeros((0, 2)),  # empty: dropped
        square + 5,
        np.roll(square, 3, axis=0),  # a copy of the first, from another corner
        np.roll(with_repeat, 2, axis=0),
        with_repeat,  # a copy of the one before, its repeated corner too
        square[[0, 1, 3, 2]],  # the same points in another order: not a copy
        np.roll(square + 5, 1, axis=0),  # a copy of the third
    ]
    kept = without_copies(loops)
    assert [id(loop) for loop in kept] == [id(loops[k]) for k in (0, 2, 4, 6)]
    # with a clockwise loop the copies count, and all are kept
    assert len(without_copies([*loops, square[::-1]])) == len(loops) - 1 + 1
