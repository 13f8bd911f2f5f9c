"""Each face's shadowed share without the shadow (issue 33 item 5): the area
of the union of a face's convex pieces by compiled loops
(:func:`shadowgeo.kernels.union_areas`), against GEOS's union (shapely) and
against the shadow :func:`shadowgeo.shadow_on_surface` builds, and the study
option that uses it (``shadows=False``)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
import shapely
import trimesh

import shadowgeo as sg
from shadowgeo.compiled import compiled_loops
from shadowgeo.errors import BudgetError
from shadowgeo.kernels import union_areas
from shadowgeo.surface import shadowed_fractions
from shadowgeo.topology import as_caster


def _padded(polygons: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    width = max(len(p) for p in polygons)
    flat = np.stack([np.concatenate([p, np.repeat(p[-1:], width - len(p), 0)]) for p in polygons])
    return flat, np.full(len(polygons), width)


def _convex(rng: np.random.Generator) -> np.ndarray:
    points = shapely.MultiPoint(rng.normal(size=(int(rng.integers(3, 9)), 2)) + rng.normal(size=2))
    hull = np.asarray(points.convex_hull.exterior.coords)[:-1]
    return hull if shapely.Polygon(hull).exterior.is_ccw else hull[::-1]


def _split(polygon: np.ndarray, rng: np.random.Generator) -> list[np.ndarray]:
    """A convex polygon cut into triangles about a point inside it, each
    corner moved by a few units in the last place (pieces clipped from
    different triangles meet so): shared edges, from either side."""
    centre = polygon.mean(axis=0)
    pieces = []
    for k in range(len(polygon)):
        piece = np.array([centre, polygon[k], polygon[(k + 1) % len(polygon)]])
        pieces.append(piece * (1 + rng.integers(-4, 5, size=piece.shape) * 2.0**-52))
    return pieces


def test_the_union_area_of_convex_pieces_is_geos_union_area():
    rng = np.random.default_rng(7)
    worst = 0.0
    for trial in range(400):
        pieces = [_convex(rng) for _ in range(int(rng.integers(1, 12)))]
        if trial % 2:
            pieces += _split(pieces[0], rng)  # on top of the polygon it splits
        if trial % 3 == 0:
            pieces.append(pieces[-1].copy())  # a piece repeated
        if trial % 5 == 0:
            pieces = _split(pieces[0], rng)  # only the triangles: edges shared from either side
        flat, counts = _padded(pieces)
        face = union_areas(flat, counts, np.array([0]), np.array([len(pieces)]), 1e-9)[0]
        reference = shapely.union_all([shapely.Polygon(p) for p in pieces]).area
        worst = max(worst, abs(face - reference) / reference)
    assert worst < 1e-12


def test_a_piece_with_no_width_covers_nothing():
    # corners repeated, and a sliver there and back along a line through the
    # square: each would cover the edges it meets if taken as a polygon
    square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    point = np.array([[2, 1]] * 4, float)  # on the square's right edge
    sliver = np.array([[-1, 1], [3, 1], [3, 1 + 1e-13], [-1, 1]], float)
    for other in (point, sliver):
        flat, counts = _padded([square, other])
        area = union_areas(flat, counts, np.array([0]), np.array([2]), 1e-9)[0]
        assert area == pytest.approx(4.0, abs=1e-9)


def test_pieces_of_several_faces_are_measured_face_by_face():
    rng = np.random.default_rng(3)
    faces = [[_convex(rng) for _ in range(int(rng.integers(1, 6)))] for _ in range(20)]
    flat, counts = _padded([p for pieces in faces for p in pieces])
    sizes = np.array([len(pieces) for pieces in faces])
    areas = union_areas(flat, counts, np.cumsum(sizes) - sizes, sizes, 1e-9)
    expected = [shapely.union_all([shapely.Polygon(p) for p in ps]).area for ps in faces]
    np.testing.assert_allclose(areas, expected, rtol=1e-12)


def _block(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    boxes = []
    for index in range(count):
        size = rng.uniform([4, 3, 4], [10, 30, 10])
        box = trimesh.creation.box(size)
        box.apply_translation([index % 4 * 14.0, size[1] / 2, index // 4 * 14.0])
        boxes.append(box)
    city = trimesh.util.concatenate(boxes)
    return np.asarray(city.vertices), np.asarray(city.faces)


@pytest.mark.parametrize("direction", [[0.3, -1, 0.2], [-0.9, -0.25, 0.4], [0.05, -0.2, -1]])
def test_shares_are_the_shadows_own_on_every_face_of_a_block(direction):
    block = _block(12, 5)
    light = sg.DirectionalLight(direction)
    shadow = sg.shadow_on_surface(block, light, block)
    for mode in ("always", "never"):
        with compiled_loops(mode):
            fraction, facing = shadowed_fractions(block, light, block)
        np.testing.assert_allclose(fraction, shadow.fraction, rtol=0, atol=1e-11)
        normals = trimesh.Trimesh(*block, process=False).face_normals
        assert np.array_equal(facing, normals @ light.direction < 0)


def test_a_wall_shades_a_quarter_and_three_quarters_of_two_triangles():
    # shadow_on_surface's own example, by hand: the wall at x = 0.5 under
    # light along (1, -1, 0) shades x < 1.5 of the unit square
    ground = ([[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]], [[0, 1, 2], [0, 2, 3]])
    wall = ([[0.5, 0, 1], [0.5, 0, -2], [0.5, 9, -2], [0.5, 9, 1]], [[0, 1, 2], [0, 2, 3]])
    with compiled_loops("always"):
        fraction, facing = shadowed_fractions(wall, sg.DirectionalLight([1, -1, 0]), ground)
    np.testing.assert_allclose(fraction, [0.75, 0.25], atol=1e-14)
    assert facing.all()


def test_a_study_without_shadows_has_the_same_hours_and_refuses_points():
    block = _block(8, 2)
    day = [dt.datetime(2026, 12, 21, h, 30, tzinfo=dt.UTC) for h in range(7, 17)]
    site = dict(latitude=51.5, longitude=-0.12, levels=False)
    with compiled_loops("always"):
        quick = sg.surface_sun_study(block, block, day, shadows=False, **site)
    whole = sg.surface_sun_study(block, block, day, **site)
    np.testing.assert_allclose(quick.mean_hours(), whole.mean_hours(), rtol=0, atol=1e-10)
    assert len(quick.times) == len(whole.times) >= 6
    point = trimesh.Trimesh(*block, process=False).triangles_center[:1]
    with pytest.raises(sg.GeometryError, match="shadows=False"):
        quick.sunlit_hours(point, [0])
    with pytest.raises(sg.GeometryError, match="levels need the shadows"):
        sg.surface_sun_study(block, block, day, shadows=False, latitude=51.5, longitude=-0.12)


def test_shares_refused_for_all_faces_at_once_are_measured_in_halves(monkeypatch):
    # as the shadows are (test_sunlight_surfaces): a stand-in refuses more
    # than 7 faces at once, as a pair search's budget would
    import shadowgeo.sunlight_surfaces as module

    block = _block(6, 4)
    directions = [[0.3, -0.8, -0.5], [-0.6, -0.2, 0.3]]
    with compiled_loops("always"):
        whole = sg.surface_sunlight(block, block, directions, levels=False, shadows=False)
    real = module.shadowed_fractions
    sizes = []

    def refusing(casters, light, surface, **options):
        sizes.append(as_caster(surface).n_faces)
        if sizes[-1] > 7:
            raise BudgetError("past a budget (shadowgeo.limits.MAX_PAIRS)")
        return real(casters, light, surface, **options)

    monkeypatch.setattr(module, "shadowed_fractions", refusing)
    with compiled_loops("always"):
        halves = sg.surface_sunlight(block, block, directions, levels=False, shadows=False)
    assert max(sizes) == len(block[1]) and min(sizes) <= 7
    for one, other in zip(whole.shadows, halves.shadows, strict=True):
        assert np.array_equal(one.dark, other.dark)
        np.testing.assert_allclose(one.fraction, other.fraction, rtol=0, atol=1e-12)
