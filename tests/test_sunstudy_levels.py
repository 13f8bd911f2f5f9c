"""cover_levels against shapely: each point's level is the number of regions
that contain it, counted one region at a time, and the areas add up."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from manifold3d import CrossSection, FillRule

from shadowgeo.levels import cover_level_areas, cover_levels


def _loops(polygon: shapely.Polygon | shapely.MultiPolygon) -> list[np.ndarray]:
    """Outer loops counter-clockwise, holes clockwise, without the closing point."""
    loops = []
    for part in getattr(polygon, "geoms", [polygon]):
        part = shapely.geometry.polygon.orient(part, 1.0)
        loops.append(np.asarray(part.exterior.coords)[:-1])
        loops.extend(np.asarray(ring.coords)[:-1] for ring in part.interiors)
    return loops


def _regions(seed: int, count: int) -> list[shapely.Geometry]:
    """Unions of random boxes, rings and stars: holes, touching parts, concave parts."""
    rng = np.random.default_rng(seed)
    regions = []
    for _ in range(count):
        pieces = []
        for _ in range(rng.integers(1, 5)):
            x, y = rng.uniform(0, 100, size=2)
            kind = rng.integers(3)
            if kind == 0:
                pieces.append(shapely.box(x, y, x + rng.uniform(5, 40), y + rng.uniform(5, 40)))
            elif kind == 1:
                pieces.append(
                    shapely.Point(x, y)
                    .buffer(rng.uniform(8, 20), 4)
                    .difference(shapely.Point(x, y).buffer(rng.uniform(2, 6), 3))
                )
            else:
                angles = np.linspace(0, 2 * np.pi, 14, endpoint=False)
                radii = np.where(np.arange(14) % 2, 4.0, rng.uniform(10, 25))
                pieces.append(
                    shapely.Polygon(
                        np.column_stack([x + radii * np.cos(angles), y + radii * np.sin(angles)])
                    )
                )
        regions.append(shapely.union_all(pieces))
    return regions


def _multipolygon(parts: list[list[np.ndarray]]) -> shapely.MultiPolygon:
    return shapely.MultiPolygon([shapely.Polygon(part[0], part[1:]) for part in parts])


@pytest.mark.parametrize("tile_vertices", [30, 200, 100_000])
def test_levels_count_the_regions_covering_each_point(tile_vertices):
    regions = _regions(seed=3, count=12)
    # a concave window, partly outside the regions' extent
    window = shapely.Polygon([(-10, -10), (90, -10), (90, 50), (40, 50), (40, 115), (-10, 115)])
    levels = cover_levels(
        [_loops(region) for region in regions],
        CrossSection(_loops(window), FillRule.Positive),
        tile_vertices=tile_vertices,
    )
    assert len(levels) >= 5  # the sample really overlaps
    shapes = {m: _multipolygon(parts) for m, parts in levels.items()}
    for m, parts in levels.items():
        # pieces of one level never overlap
        pieces = sum(shapely.Polygon(part[0], part[1:]).area for part in parts)
        assert pieces == pytest.approx(shapely.union_all(shapes[m].geoms).area, rel=1e-9)
    assert sum(shape.area for shape in shapes.values()) == pytest.approx(window.area, rel=1e-9)
    expected = sum(shapely.intersection(region, window).area for region in regions)
    assert sum(m * shape.area for m, shape in shapes.items()) == pytest.approx(expected, rel=1e-9)

    rng = np.random.default_rng(11)
    xy = rng.uniform(-15, 120, size=(4000, 2))
    points = shapely.points(xy)
    edges = shapely.union_all(
        [shapely.boundary(region) for region in regions]
        + [shapely.boundary(window)]
        + [shapely.boundary(shape) for shape in shapes.values()]
    )
    clear = shapely.distance(points, edges) > 1e-6
    count = sum(shapely.contains_xy(region, xy[:, 0], xy[:, 1]).astype(int) for region in regions)
    level = np.full(len(xy), -1)
    for m, shape in shapes.items():
        level[shapely.contains_xy(shape, xy[:, 0], xy[:, 1])] = m
    inside = shapely.contains_xy(window, xy[:, 0], xy[:, 1])
    assert clear.sum() > 3900
    np.testing.assert_array_equal(level[clear & inside], count[clear & inside])
    assert np.all(level[clear & ~inside] == -1)


@pytest.mark.parametrize("tile_vertices", [30, 100_000])
def test_level_areas_alone_are_the_levels_areas(tile_vertices):
    """cover_level_areas: each level's area without its polygons, against the
    areas of cover_levels' polygons (checked point by point above), and two
    identities of GEOS's areas: the levels add up to the window, and their
    sum weighted by m to the regions' areas within it."""
    regions = _regions(seed=3, count=12)
    window = shapely.Polygon([(-10, -10), (90, -10), (90, 50), (40, 50), (40, 115), (-10, 115)])
    loops = [_loops(region) for region in regions]
    section = CrossSection(_loops(window), FillRule.Positive)
    areas = cover_level_areas(loops, section, tile_vertices=tile_vertices)
    polygons = cover_levels(loops, section, tile_vertices=tile_vertices)
    exact = {m: _multipolygon(parts).area for m, parts in polygons.items()}
    assert len(areas) >= 5
    assert {m for m, a in areas.items() if a > 1e-9} == {m for m, a in exact.items() if a > 1e-9}
    for m, area in areas.items():
        assert area == pytest.approx(exact.get(m, 0.0), rel=1e-9, abs=1e-9 * window.area)
    assert sum(areas.values()) == pytest.approx(window.area, rel=1e-12)
    expected = sum(shapely.intersection(region, window).area for region in regions)
    assert sum(m * a for m, a in areas.items()) == pytest.approx(expected, rel=1e-9)
    empty = CrossSection(_loops(shapely.box(0, 0, 1, 1)), FillRule.Positive) - section
    assert cover_level_areas(loops, empty) == {}


def test_no_regions_and_empty_window():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    levels = cover_levels([], CrossSection([square]))
    assert list(levels) == [0] and CrossSection(levels[0][0]).area() == pytest.approx(1.0)
    assert cover_levels([[square]], CrossSection()) == {}
