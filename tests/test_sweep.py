"""The sweep that certifies one polygon simple and cuts it into triangles
(shadowgeo.sweep), against GEOS (shapely) on random polygons."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import check_tiling

from shadowgeo.sweep import simple_triangles


def _counter_clockwise(polygon: shapely.Polygon) -> np.ndarray:
    """The polygon's outer ring, counter-clockwise, without the repeated corner."""
    ring = np.asarray(shapely.geometry.polygon.orient(polygon, 1.0).exterior.coords)[:-1]
    return ring


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(20, 400), st.floats(0.05, 0.6))
def test_a_random_simple_polygon_is_certified_and_tiled(seed, count, ratio):
    """Concave hulls of random points: simple polygons with many reflex
    corners, as GEOS builds them."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, (count, 2)) * rng.uniform(0.1, 10, 2)
    hull = shapely.concave_hull(shapely.MultiPoint(points), ratio=ratio)
    if not isinstance(hull, shapely.Polygon) or len(hull.exterior.coords) < 4:
        return
    loop = _counter_clockwise(hull)
    simple, faces = simple_triangles(loop)
    assert simple
    if faces is not None:  # (three corners in line a triangle needs: not certified)
        check_tiling(loop, faces)


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(4, 60))
def test_a_loop_that_crosses_itself_is_never_called_simple(seed, count):
    """Random corners in random order: whenever GEOS finds the ring not
    simple, the sweep does not certify it (and it refuses clockwise ones)."""
    rng = np.random.default_rng(seed)
    loop = rng.uniform(-1, 1, (count, 2))
    simple, faces = simple_triangles(loop)
    ring_simple = shapely.is_simple(shapely.LinearRing(loop))
    if simple:
        assert ring_simple
        assert shapely.LinearRing(loop).is_ccw
        if faces is not None:
            check_tiling(loop, faces)


@pytest.mark.parametrize("scale", [1e-200, 1e-8, 1.0, 1e12, 1e200])
def test_combs_and_spirals_at_any_scale(scale):
    """A comb (its teeth's feet in line) and a spiral, far from the origin
    or not: certified and tiled whatever the scale."""
    xs = np.linspace(-3.9, 3.9, 2 * 50)
    teeth = []
    for x0, x1 in zip(xs[0::2], xs[1::2], strict=True):
        teeth += [(x0, 0.5), (x0, 3.0), (x1, 3.0), (x1, 0.5)]
    comb = np.array([(4.0, 0.0), (4.0, 0.5), *teeth[::-1], (-4.0, 0.5), (-4.0, 0.0)])
    turns = np.linspace(0, 6 * np.pi, 300)
    outer = np.column_stack([(1 + turns) * np.cos(turns), (1 + turns) * np.sin(turns)])
    inner = np.column_stack([(0.6 + turns) * np.cos(turns), (0.6 + turns) * np.sin(turns)])
    spiral = np.concatenate([outer, inner[::-1]])
    for loop in (comb, spiral):
        assert shapely.Polygon(loop).is_valid
        moved = (loop + [3.0, -7.0]) * scale
        simple, faces = simple_triangles(moved)
        assert simple
        assert faces is not None
        check_tiling(moved / scale, faces)


def test_loops_that_touch_or_run_clockwise_are_not_certified():
    figure_eight = np.array([[0, 0], [1, 1], [2, 0], [2, 2], [1, 1], [0, 2]], float)
    touching = np.array([[0, 0], [4, 0], [4, 4], [2, 0.0], [0, 4]], float)  # a corner on an edge
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert simple_triangles(figure_eight) == (False, None)
    assert simple_triangles(touching) == (False, None)
    assert simple_triangles(square[::-1]) == (False, None)
    simple, faces = simple_triangles(square)
    assert simple and faces is not None
    check_tiling(square, faces)


def test_a_crossing_is_found_by_the_neighbours_test():
    """The bow tie's two long edges become neighbours along the sweep line
    as they start, and their crossing is found there (Shamos and Hoey),
    before any later step could stumble on the order it breaks."""
    from shadowgeo.sweep import _Sweep

    bow_tie = np.array([[-1, 10], [1, 0], [-1, 0], [1, 10]], float) * 2.0**20
    sweep = _Sweep(bow_tie)
    sweep.run()
    assert sweep.crossed
    assert simple_triangles(bow_tie) == (False, None)


def test_a_certified_outline_is_cut_by_the_sweep_that_certified_it(monkeypatch):
    """A shadow's outline is certified (whole_loop) and then triangulated: with
    keep_triangles the certifying sweep's triangles serve the triangulation,
    so a comb of 4,096 teeth is swept once, not twice; a loop that differs in
    one bit is swept again (the kept triangles are found by content)."""
    import shadowgeo.plane2d as plane2d
    import shadowgeo.sweep as sweep

    xs = np.linspace(-3.9, 3.9, 2 * 4096)
    teeth = []
    for x0, x1 in zip(xs[0::2], xs[1::2], strict=True):
        teeth += [(x0, 0.5), (x0, 3.0), (x1, 3.0), (x1, 0.5)]
    comb = np.array([(4.0, 0.0), (4.0, 0.5), *teeth[::-1], (-4.0, 0.5), (-4.0, 0.0)])
    assert shapely.Polygon(comb).is_valid and shapely.Polygon(comb).exterior.is_ccw
    calls = []
    original = sweep.simple_triangles

    def counted(loop, triangles=True):
        calls.append(triangles)
        return original(loop, triangles)

    # the name each certifies and triangulates by
    monkeypatch.setattr(plane2d.predicates, "simple_triangles", counted)
    monkeypatch.setattr(plane2d.triangulation, "simple_triangles", counted)
    assert plane2d.whole_loop([comb], keep_triangles=True)
    _, faces = plane2d.triangulate_parts([[comb]])
    assert calls == [True]  # one sweep for the certificate and the triangles
    assert np.array_equal(faces, original(comb)[1])
    check_tiling(comb, faces)
    nudged = comb.copy()
    nudged[5, 1] = np.nextafter(nudged[5, 1], 2.0)
    plane2d.triangulate_parts([[nudged]])
    assert calls == [True, True]  # not the kept triangles of another loop
    assert plane2d.whole_loop([comb])  # without keep_triangles: a certificate only
    assert calls == [True, True, False]
