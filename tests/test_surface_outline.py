"""The fast paths under shadow_on_surface, each against a brute-force or shapely reference.

* ``Outline.cut``: a closed caster's outline cut to receiver faces seen from the
  light (wholly covered faces, and the exact part of the others) against
  shapely's intersection, including faces whose centre lies on the outline's
  edge (cut by Clipper2 instead) and faces the outline crosses many times;
  ``OutlineSet.cut``: each triangle by its own caster's outline, where the
  outlines overlap one another; ``make_outlines``: each caster's region the
  union of its own loops, a convex loop taken as it is;
* ``overlapping_boxes``: every overlapping pair, against all pairs tested;
* ``candidate_pairs``: triangles given as shared points and faces pair exactly
  as the same triangles given corner by corner;
* ``stitch``: a face wholly in shadow comes back as the face itself;
* ``clip_batch``: convex polygons cut by half-planes, against shapely.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from shadowgeo import GeometryError
from shadowgeo.lightframe import candidate_pairs, clip_batch, clip_one, overlapping_boxes
from shadowgeo.outline import Outline, OutlineSet, make_outlines, padded_loops
from shadowgeo.seams import loops_of, stitch


def star(center, radius, count=40, lobes=5, depth=0.4):
    angles = np.linspace(0.0, 2 * np.pi, count, endpoint=False)
    reach = radius * (1 + depth * np.sin(lobes * angles))
    return np.column_stack([center[0] + reach * np.cos(angles), center[1] + reach * np.sin(angles)])


def outline_of(loops):
    """An Outline in the plane z = 0 seen along -z (a directional light)."""
    down = np.array([0.0, 0.0, -1.0])
    outline = Outline(None, down, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), down)
    outline.unite(loops)
    return outline


@pytest.fixture(scope="module")
def outline():
    # two overlapping stars (united into one part) with a hole, and an island
    return outline_of(
        [
            star((0.0, 0.0), 1.0),
            star((1.5, 0.3), 0.7, count=31),
            star((0.0, 0.0), 0.3)[::-1],  # a hole
            star((-2.2, -1.5), 0.4, count=12, lobes=3),  # an island
        ]
    )


def signed_area(loop):
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def check_cut(outline, triangles, margin, owner=None):
    """``outline.cut`` against shapely (for an OutlineSet, triangle k by the
    region of its outline ``owner[k]``)."""
    covered, pieces, owners = outline.cut(triangles, margin, owner)
    assert pieces.shape[0] == owners.shape[0]
    for k, triangle in enumerate(triangles):
        polygon = shapely.Polygon(triangle)
        region = outline.region if owner is None else outline.outlines[owner[k]].region
        exact = region.intersection(polygon).area
        if covered[k]:
            assert region.covers(polygon)
            assert not np.any(owners == k)
            continue
        mine = pieces[owners == k]
        # outer loops counter-clockwise, holes clockwise: the signed areas add up
        area = sum(signed_area(loop) for loop in mine)
        assert area == pytest.approx(exact, rel=1e-11, abs=1e-14 * polygon.area + 1e-300)
        for loop in mine:  # in the triangle
            assert polygon.buffer(1e-9 * np.sqrt(polygon.area)).covers(shapely.MultiPoint(loop))


def test_cut_matches_shapely_on_random_triangles_of_both_windings(outline):
    rng = np.random.default_rng(7)
    centres = rng.uniform(-2.6, 2.4, (400, 2))
    sizes = rng.uniform(0.02, 1.5, 400)
    triangles = centres[:, None, :] + sizes[:, None, None] * rng.normal(size=(400, 3, 2))
    check_cut(outline, triangles, 1e-12)
    covered, _, _ = outline.cut(triangles, 1e-12)
    assert 0 < covered.sum() < len(triangles)


def test_cut_of_triangles_the_boundary_crosses_many_times(outline):
    big = np.array(
        [[[-3.0, -3.0], [3.5, -2.0], [0.0, 3.0]], [[-1.2, 0.1], [1.2, -0.1], [0.0, 0.05]]]
    )
    check_cut(outline, big, 1e-12)
    check_cut(outline, big[:, ::-1], 1e-12)


def test_cut_where_the_centre_lies_on_the_outline_uses_clipper(outline):
    # centroids exactly at boundary points: not sure which side, cut exactly instead
    points = np.concatenate(outline.loops)[::7]
    offsets = np.array([[0.05, 0.0], [-0.025, 0.04], [-0.025, -0.04]])
    triangles = points[:, None, :] + offsets[None]
    check_cut(outline, triangles, 1e-9)
    # a margin wider than every triangle sends them all to Clipper2: same answers
    check_cut(outline, triangles, 10.0)


def test_cut_of_a_square_from_every_side_and_corner():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    outline = outline_of([square])
    base = np.array([[-0.2, -0.15], [0.2, -0.1], [0.0, 0.2]])
    spots = [(x, y) for x in (0.0, 0.5, 1.0) for y in (0.0, 0.5, 1.0)]
    triangles = np.array([base + spot for spot in spots] + [base * 8 + (0.5, 0.5)])
    check_cut(outline, triangles, 1e-12)
    check_cut(outline, triangles[:, ::-1], 1e-12)


def test_outline_set_cuts_each_triangle_by_its_own_outline():
    # three casters' outlines over one another in the light's one frame; each
    # triangle is cut by one of them, not by their union
    outlines = [
        outline_of([star((0.0, 0.0), 1.0)]),
        outline_of([star((0.8, 0.2), 0.9, count=31), star((0.8, 0.2), 0.3)[::-1]]),
        outline_of([np.array([[-1.5, -1.0], [1.5, -1.0], [1.5, -0.2], [-1.5, -0.2]])]),
    ]
    together = OutlineSet(outlines)
    # the set's regions, made in one call, are each outline's own
    two_parts = outline_of([star((0.0, 0.0), 1.0), star((0.0, 0.0), 0.4)[::-1], star((3, 0), 0.5)])
    everyone = [*outlines, two_parts]
    for outline, region in zip(everyone, OutlineSet(everyone).regions, strict=True):
        assert shapely.equals_exact(outline.region, region, tolerance=0.0)
    # and so are their boxes, an empty outline's NaN among them
    empty = outline_of([star((0.0, 0.0), 1.0)[::-1]])  # clockwise: nothing inside
    boxes = [outline.bounds for outline in [empty, *everyone, empty]]
    assert empty.n_loops == 0
    assert np.array_equal(OutlineSet([empty, *everyone, empty]).bounds, boxes, equal_nan=True)
    rng = np.random.default_rng(11)
    centres = rng.uniform(-1.8, 1.8, (300, 2))
    sizes = rng.uniform(0.02, 0.8, 300)
    triangles = centres[:, None, :] + sizes[:, None, None] * rng.normal(size=(300, 3, 2))
    owner = rng.integers(0, 3, 300)
    check_cut(together, triangles, 1e-12, owner)
    # and a triangle's centre on its own outline's edge goes to Clipper2
    points = np.concatenate(outlines[1].loops)[::9]
    near = points[:, None, :] + np.array([[0.05, 0.0], [-0.025, 0.04], [-0.025, -0.04]])[None]
    check_cut(together, near, 1e-9, np.ones(len(near), dtype=np.int64))
    # triangles that hold their outline whole (a small caster's outline on
    # a large face, either winding) get its loops as they are, holes too
    large = np.array([[-40.0, -30.0], [40.0, -30.0], [0.0, 50.0]])
    holding = np.stack([large, large[::-1], large + 0.5])
    check_cut(together, holding, 1e-12, np.array([1, 1, 0]))
    _, pieces, owners = together.cut(holding, 1e-12, np.array([1, 1, 0]))
    kept = [pieces[owners == 0][k][: len(loop)] for k, loop in enumerate(outlines[1].loops)]
    for mine, loop in zip(kept, outlines[1].loops, strict=True):
        assert np.array_equal(mine, loop)
    # the same triangles covered as by each outline alone
    covered, _, _ = together.cut(triangles, 1e-12, owner)
    for k, outline in enumerate(outlines):
        assert np.array_equal(covered[owner == k], outline.cut(triangles[owner == k], 1e-12)[0])


@pytest.mark.parametrize("light_point", [None, np.array([0.3, 0.2, 9.0])])
def test_outlines_made_together_are_each_casters_own_union(light_point):
    """make_outlines: a caster of one convex loop takes it without Clipper2,
    others are united; each region is the union of its own loops' images."""
    rng = np.random.default_rng(5)
    down = np.array([0.0, 0.0, -1.0])
    casters = []
    for index in range(12):
        # prisms' top rings at z = 1 (only the ring is projected): hexagons,
        # a concave dart, two overlapping squares, and a clockwise square
        centre = rng.uniform(-3, 3, 2)
        angles = np.linspace(0, 2 * np.pi, 6, endpoint=False) + rng.uniform(0, 1)
        hexagon = np.column_stack([np.cos(angles), np.sin(angles)]) * 0.5 + centre
        rings = {
            0: [hexagon],
            1: [np.array([[0.0, 0], [2, 1], [4, 0], [2, 3]]) * 0.2 + centre],
            2: [_square(*centre, *(centre + 1)), _square(*(centre + 0.5), *(centre + 1.5))],
            3: [_square(*centre, *(centre + 1))[::-1]],
        }[index % 4]
        vertices = np.concatenate([np.column_stack([r, np.ones(len(r))]) for r in rings])
        starts = np.cumsum([0] + [len(r) for r in rings])
        loops = [np.arange(a, b) for a, b in zip(starts[:-1], starts[1:], strict=True)]
        casters.append((vertices, loops))
    casters.append((np.zeros((3, 3)), []))  # no silhouette: no outline
    made = make_outlines(casters, light_point, None if light_point is not None else down, 1e-9)
    assert made[-1] is None
    for (vertices, loops), outline in zip(casters[:-1], made[:-1], strict=True):
        images = [outline.to_frame(vertices[loop]) for loop in loops]
        expected = shapely.union_all(
            [shapely.Polygon(image) for image in images if signed_area(image) > 0]
        )
        got = outline.region
        assert got.symmetric_difference(expected).area <= 1e-12 * max(expected.area, 1.0)
        assert outline.cross_section.area() == pytest.approx(
            expected.area * outline.scale**2, rel=1e-12, abs=1e-9
        )
    # the hexagons took the fast path: their region is their loop exactly
    vertices, loops = casters[0]
    assert np.array_equal(made[0].loops[0], made[0].to_frame(vertices[loops[0]]))


def _square(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def test_padded_loops_repeat_the_last_point():
    points = np.arange(14.0).reshape(7, 2)
    loops = padded_loops(points, np.array([3, 4]))
    assert loops.shape == (2, 4, 2)
    assert loops[0].tolist() == [[0, 1], [2, 3], [4, 5], [4, 5]]
    assert loops[1].tolist() == points[3:].tolist()


def brute_pairs(first, second):
    overlap = (
        (first[:, None, 0] <= second[None, :, 2])
        & (second[None, :, 0] <= first[:, None, 2])
        & (first[:, None, 1] <= second[None, :, 3])
        & (second[None, :, 1] <= first[:, None, 3])
    )
    return set(zip(*np.nonzero(overlap), strict=True))


@pytest.mark.parametrize(
    "sizes",
    [
        (2000, 60, 0.01, 0.02),  # a terrain against a small caster
        (300, 400, 0.05, 0.05),  # alike
        (300, 300, 0.002, 0.9),  # tiny boxes against huge ones: the tree
        (400, 400, 0.3, 0.3),  # piled up (a grazing light): crowded cells, the tree
        (200, 200, 0.01, 0.01),  # no common ground
    ],
)
def test_overlapping_boxes_finds_every_pair_once(sizes):
    count_a, count_b, size_a, size_b = sizes
    rng = np.random.default_rng(count_a + count_b)

    def boxes(count, size, shift):
        low = rng.uniform(0, 1, (count, 2)) + shift
        return np.column_stack([low, low + rng.uniform(0, size, (count, 2))])

    first = boxes(count_a, size_a, 0.0)
    second = boxes(count_b, size_b, 5.0 if sizes[0] == 200 else 0.0)
    i, j = overlapping_boxes(first, second)
    found = list(zip(i.tolist(), j.tolist(), strict=True))
    assert len(found) == len(set(found))
    assert set(found) == brute_pairs(first, second)


@pytest.mark.parametrize(("count_a", "count_b"), [(6, 15), (40, 100), (64, 64)])
def test_few_boxes_are_paired_directly_as_the_grid_pairs_them(count_a, count_b):
    """Up to _DIRECT_PAIRS candidate pairs every pair is tested (a caster's
    outline against the faces near it): the grid's pairs, in its order."""
    from shadowgeo import lightframe

    assert count_a * count_b <= lightframe._DIRECT_PAIRS
    rng = np.random.default_rng(count_a)
    low_a, low_b = rng.uniform(0, 1, (count_a, 2)), rng.uniform(0, 1, (count_b, 2))
    first = np.column_stack([low_a, low_a + rng.uniform(0, 0.3, (count_a, 2))])
    second = np.column_stack([low_b, low_b + rng.uniform(0, 0.2, (count_b, 2))])
    second[0] = [first[0, 2], first[0, 3], 2.0, 2.0]  # touching at a corner: a pair
    i, j = overlapping_boxes(first, second)
    grid_i, grid_j = lightframe._grid_pairs(first, second)
    assert len(i) > 0 and np.array_equal(i, grid_i) and np.array_equal(j, grid_j)
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == brute_pairs(first, second)
    with pytest.raises(GeometryError, match="MAX_SURFACE_PAIRS"):
        overlapping_boxes(first, second, budget=len(i) - 1)


@pytest.mark.parametrize("light", ["point", "sun"])
def test_candidate_pairs_of_shared_points_equal_those_of_corners(light):
    rng = np.random.default_rng(3)
    points = rng.normal(size=(400, 3)) * [3.0, 0.3, 3.0]
    faces = rng.integers(0, 400, (700, 3))
    casters = rng.normal(size=(200, 3, 3)) * 0.3 + [0.0, 2.0, 0.0]
    position = np.array([0.5, 6.0, 0.2]) if light == "point" else None
    direction = None if light == "point" else np.array([0.3, -1.0, 0.1]) / np.sqrt(1.1)
    pad = 1e-9 if light == "point" else 1e-6
    shared = candidate_pairs((points, faces), casters, position, direction, pad)
    corners = candidate_pairs(points[faces], casters, position, direction, pad)
    assert np.array_equal(shared[0], corners[0]) and np.array_equal(shared[1], corners[1])
    assert len(shared[0]) > 0


def _loop_area(points):
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_repeated_points_and_spike_tips_go_loop_by_loop_as_each_loop_alone():
    """simplify._without_spikes on many loops at once: each loop comes out as
    it does alone (loops that settle early are set aside, the others go on),
    in its place; no point repeats the one before, no tip of a zero-width
    spike is left, and each loop keeps its area."""
    from shadowgeo.simplify import _without_spikes

    rng = np.random.default_rng(3)
    eps = 1e-9
    loops = []
    for index in range(60):
        corners = star((index, 0.0), 1.0, count=int(rng.integers(3, 12)), lobes=2, depth=0.2)
        rows = []
        for corner in corners:
            rows.append(corner)
            kind = index % 4
            if kind == 1:  # a run of repeats, a few passes' worth
                rows += [corner + rng.uniform(-1e-10, 1e-10, 2)] * int(rng.integers(0, 9))
            elif kind == 2 and rng.random() < 0.5:  # out to a spike's tip and back
                rows += [corner + rng.normal(size=2), corner.copy()]
        loops.append(np.array(rows))
    loops.append(np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [1.0, 1.0]]))  # goes
    sizes = np.array([len(loop) for loop in loops])
    regions = (np.concatenate(loops), sizes, np.arange(len(loops)) // 2)
    points, out_sizes, out_region = _without_spikes(regions, eps)
    alone = [
        _without_spikes((loop, np.array([len(loop)]), np.array([k // 2])), eps)
        for k, loop in enumerate(loops)
    ]
    assert np.array_equal(points, np.concatenate([a[0] for a in alone]))
    assert np.array_equal(out_sizes, np.concatenate([a[1] for a in alone]))
    assert np.array_equal(out_region, np.concatenate([a[2] for a in alone]))
    assert len(out_sizes) == len(loops) - 1  # the last loop had no area to keep
    kept = np.split(points, np.cumsum(out_sizes)[:-1])
    survivors = [loop for loop, a in zip(loops, alone, strict=True) if len(a[1])]
    for before, after in zip(survivors, kept, strict=True):
        assert np.all(np.hypot(*(after - np.roll(after, 1, axis=0)).T) > eps)
        assert np.all(np.hypot(*(np.roll(after, -1, axis=0) - np.roll(after, 1, axis=0)).T) > eps)
        assert signed_area(after) == pytest.approx(signed_area(before), rel=1e-8)


def test_points_on_a_straight_run_are_dropped_and_corners_kept():
    """A square whose sides carry extra points (a run of three on one side,
    a duplicate, a zero-width spike), a hole with one extra point, and a
    sliver loop of three points on a line: the corners alone are left, in
    order, the same areas, and the sliver goes."""
    from shadowgeo.simplify import without_collinear

    square = np.array(
        [[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [4, 2], [4, 2], [4, 4], [2, 4],
         [2, 5], [2, 4], [0, 4], [0, 1]], dtype=float,
    )  # fmt: skip
    hole = np.array([[1, 1], [1, 3], [3, 3], [3, 2], [3, 1]], dtype=float)  # clockwise
    sliver = np.array([[5, 5], [6, 6], [7, 7]], dtype=float)
    loops = [square, hole, sliver]
    regions = (np.concatenate(loops), np.array([len(x) for x in loops]), np.array([0, 0, 1]))
    points, sizes, region = without_collinear(regions, 1e-9)
    assert sizes.tolist() == [4, 4] and region.tolist() == [0, 0]
    outer, inner = points[:4], points[4:]
    assert outer.tolist() == [[0, 0], [4, 0], [4, 4], [0, 4]]
    assert inner.tolist() == [[1, 1], [1, 3], [3, 3], [3, 1]]
    assert _loop_area(outer) == _loop_area(square) and _loop_area(inner) == _loop_area(hole)


def _distance_to_loop(points, loop):
    """Each point's distance to the closed polyline ``loop``."""
    a, b = loop, np.roll(loop, -1, axis=0)
    step = b - a
    t = np.einsum("pkd,kd->pk", points[:, None] - a[None], step) / np.sum(step * step, axis=1)
    near = a[None] + np.clip(t, 0, 1)[:, :, None] * step[None]
    return np.linalg.norm(points[:, None] - near, axis=2).min(axis=1)


def test_dropping_points_moves_a_region_by_at_most_eps():
    """Rectangles whose sides carry points nudged off them by less than eps
    and by several eps: the corners stay, every point left is one of the
    loop's in its order, no point left is within eps of its neighbours'
    line (a second pass changes nothing), every point dropped lies within
    eps of what is left, and each loop's area moves by no more than eps
    times its perimeter."""
    from shadowgeo.simplify import without_collinear

    rng = np.random.default_rng(11)
    eps = 1e-6
    loops, corner_sets = [], []
    for _ in range(40):
        corners = rng.uniform(-5, 5, (1, 2)) + np.array([[0, 0], [3, 0], [3, 2], [0, 2]])
        corner_sets.append(corners)
        points = []
        for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
            points.append(a)
            normal = np.array([-(b - a)[1], (b - a)[0]]) / np.linalg.norm(b - a)
            for t in np.sort(rng.uniform(0.1, 0.9, rng.integers(0, 6))):
                off = rng.uniform(3, 9) if rng.random() < 0.3 else rng.uniform(-0.4, 0.4)
                points.append(a + t * (b - a) + normal * off * eps)
        loops.append(np.array(points))
    regions = (np.concatenate(loops), np.array([len(x) for x in loops]), np.arange(len(loops)))
    points, sizes, region = without_collinear(regions, eps)
    assert region.tolist() == list(range(len(loops))) and len(points) < len(regions[0])
    again = without_collinear((points, sizes, region), eps)
    assert np.array_equal(again[0], points) and np.array_equal(again[1], sizes)
    starts = np.cumsum(sizes) - sizes
    for k, (loop, corners) in enumerate(zip(loops, corner_sets, strict=True)):
        left = points[starts[k] : starts[k] + sizes[k]]
        index = [int(np.flatnonzero((loop == p).all(axis=1))[0]) for p in left]
        assert index == sorted(index)  # the loop's own points, in order
        assert all(np.any(np.all(left == c, axis=1)) for c in corners)  # the corners stay
        assert _distance_to_loop(loop, left).max() <= eps * (1 + 1e-9)
        perimeter = np.sum(np.linalg.norm(loop - np.roll(loop, -1, axis=0), axis=1))
        assert abs(_loop_area(left) - _loop_area(loop)) <= eps * perimeter


@pytest.mark.parametrize("touches_shared_edge", [False, True])
def test_stitch_gives_a_whole_face_back_as_itself(touches_shared_edge):
    vertices = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0], [1.0, 1, 0]])
    faces = np.array([[0, 1, 2], [1, 3, 2]])
    origin = vertices[faces].mean(axis=1)
    u = np.tile([1.0, 0, 0], (2, 1))
    v = np.tile([0.0, 1, 0], (2, 1))
    whole = (vertices[faces[0]] - origin[0])[:, :2]
    corner = [0.5, 0.5] if touches_shared_edge else [0.6, 1.0]
    part = np.array([[1.0, 0.4], [1.0, 1.0], corner]) - origin[1, :2]
    points, triangles, face_index = stitch(
        vertices, faces, np.array([0, 1]), (origin, u, v), loops_of([[whole], [part]]), 1e-12
    )
    corners = points[triangles]
    area = 0.5 * np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2]
    assert np.all(area > 0)
    assert area[face_index == 0].sum() == pytest.approx(0.5)
    assert area[face_index == 1].sum() == pytest.approx(signed_area(part))
    first = triangles[face_index == 0].tolist()
    if touches_shared_edge:
        # the region's corner on the shared edge splits the whole face too: no T-junction
        middle = int(np.argmin(np.linalg.norm(points - [0.5, 0.5, 0.0], axis=1)))
        assert np.allclose(points[middle], [0.5, 0.5, 0.0], atol=1e-15)
        assert len(first) == 2 and all(middle in triangle for triangle in first)
    else:
        assert first == [[0, 1, 2]]


def test_clip_batch_cuts_convex_polygons_as_shapely_does():
    rng = np.random.default_rng(11)
    count = 300
    triangles = rng.normal(size=(count, 3, 2))
    homogeneous = np.concatenate([triangles, np.ones((count, 3, 1))], axis=2)
    # three random half-planes a x + b y + c >= 0 per triangle
    planes = np.concatenate(
        [rng.normal(size=(count, 3, 2)), rng.uniform(-0.5, 1.0, (count, 3, 1))], axis=2
    )
    clipped, counts = clip_batch(homogeneous, np.full(count, 3), planes)
    far = 1e3
    for k in range(count):
        region = shapely.Polygon(triangles[k]).buffer(0)
        for a, b, c in planes[k]:
            # the half-plane as a big polygon: points p with n . p + c >= 0
            normal = np.array([a, b]) / np.hypot(a, b)
            foot = -c / np.hypot(a, b) * normal
            along = np.array([-normal[1], normal[0]])
            half = [foot + far * along, foot - far * along, foot - far * along + far * normal]
            half.append(foot + far * along + far * normal)
            region = region.intersection(shapely.Polygon(half))
        mine = clipped[k, : counts[k], :2]
        area = abs(signed_area(mine)) if counts[k] >= 3 else 0.0
        assert area == pytest.approx(region.area, rel=1e-9, abs=1e-12)


def test_one_polygon_is_a_batch_of_one_and_shared_planes_cut_every_row():
    # the unit square cut by x <= 0.5 and y >= x - 0.25, by hand: the pentagon
    # (0, 0), (0.25, 0), (0.5, 0.25), (0.5, 1), (0, 1); the second row, shifted
    # by (2, 0), lies wholly at x >= 2 and is cut away
    square = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]])
    planes = np.array([[-1.0, 0.0, 0.5], [-1.0, 1.0, 0.25]])
    expected = [[0.0, 0.0], [0.25, 0.0], [0.5, 0.25], [0.5, 1.0], [0.0, 1.0]]
    one = clip_one(square, planes)
    assert one.shape == (5, 3)
    assert np.allclose(one[:, :2] / one[:, 2:], expected, atol=1e-15)
    shifted = square + [2.0, 0.0, 0.0]
    clipped, counts = clip_batch(np.stack([square, shifted]), np.array([4, 4]), planes)
    assert counts.tolist() == [5, 0]
    assert np.array_equal(clipped[0, :5], one)
    assert len(clip_one(shifted, planes)) == 0


def test_a_surfaces_geometry_is_kept_on_its_mesh_and_right():
    import trimesh

    from shadowgeo import PointLight, shadow_on_surface
    from shadowgeo.topology import as_caster

    ground = trimesh.creation.icosphere(subdivisions=2, radius=3.0)
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.5)
    ball.apply_translation([0.0, 0.0, 5.0])
    shadow_on_surface(ball, PointLight([0.0, 0.0, 9.0]), ground)

    def recompute(_):
        raise AssertionError("computed twice")

    kept = as_caster(ground).derived("surface_geometry", recompute)
    # trimesh's own unit normals and centroids, independently
    assert np.allclose(kept.unit, ground.face_normals, atol=1e-12)
    assert np.allclose(kept.centroid + as_caster(ground).center, ground.triangles_center)
    assert np.allclose(np.cross(kept.u, kept.v), kept.unit, atol=1e-12)
    assert not kept.single_sheet  # a closed sphere is no sheet
