"""Convex bodies as one ring a face (:mod:`shadowgeo.bodies`, issue 33 item
5): which parts of a caster are convex closed bodies, the ring of a body cut
by a face's plane against the hull of the cut solid worked out by hand, and
the shadowed shares they give against shadows measured by hand and against
:func:`shadowgeo.shadow_on_surface`'s union."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
import trimesh

import shadowgeo as sg
from shadowgeo.bodies import convex_bodies, light_bodies, ring_pieces
from shadowgeo.compiled import compiled_loops
from shadowgeo.surface import shadowed_fractions
from shadowgeo.topology import Caster


def _box(low, high) -> trimesh.Trimesh:
    low, high = np.asarray(low, float), np.asarray(high, float)
    box = trimesh.creation.box(high - low)
    box.apply_translation((low + high) / 2)
    return box


def _ell() -> trimesh.Trimesh:
    """An L-shaped prism: closed, not convex."""
    outline = shapely.Polygon([(0, 0), (4, 0), (4, 1), (1, 1), (1, 3), (0, 3)])
    return trimesh.creation.extrude_polygon(outline, 2.0)


def _caster(*meshes: trimesh.Trimesh) -> Caster:
    mesh = trimesh.util.concatenate(list(meshes))
    return Caster(mesh.vertices, mesh.faces)


def test_a_city_of_boxes_is_its_boxes_and_an_ell_is_not_convex():
    boxes = [_box([3 * k, 0, 0], [3 * k + 1 + k % 2, 2 + k, 1]) for k in range(5)]
    found = convex_bodies(_caster(*boxes), 1e-9)
    assert found.count == 5 and len(found.rest) == 0
    assert np.array_equal(np.diff(found.face_starts), [12] * 5)
    assert np.array_equal(np.diff(found.vertex_starts), [8] * 5)
    assert np.array_equal(np.diff(found.edge_starts), [18] * 5)  # a box's edges, diagonals too
    mixed = _caster(boxes[0], _ell().apply_translation([10, 0, 0]))
    found = convex_bodies(mixed, 1e-9)
    assert found.count == 1
    assert np.array_equal(
        np.sort(np.concatenate([found.faces, found.rest])), np.arange(mixed.n_faces)
    )
    assert set(found.rest) == set(range(12, mixed.n_faces))  # the ell's faces, none of the box's
    # an open sheet (a box without its top) has no bodies: all of it casts as triangles
    box = _box([0, 0, 0], [1, 1, 1])
    up = box.face_normals[:, 2] > 0.5
    sheet = Caster(box.vertices, box.faces[~up])
    assert convex_bodies(sheet, 1e-9).count == 0
    # turned inside out, a box is not convex seen from outside
    inside_out = Caster(box.vertices, box.faces[:, ::-1])
    assert convex_bodies(inside_out, 1e-9).count == 0


def _frames(corners) -> np.ndarray:
    """(f, 7, 3) frames of triangles (f, 3, 3), counter-clockwise seen from
    their normals, as ring_pieces takes them (the origin at the centroid)."""
    corners = np.asarray(corners, float)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    u = corners[:, 1] - corners[:, 0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normal, u)
    origin = corners.mean(axis=1)
    return np.concatenate(
        [corners, normal[:, None], u[:, None], v[:, None], origin[:, None]], axis=1
    )


def _area(piece: np.ndarray, count: int) -> float:
    x, y = piece[:count, 0], piece[:count, 1]
    return float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) / 2)


def _pieces(mesh: Caster, direction, triangles, faces=None):
    direction = np.asarray(direction, float) / np.linalg.norm(direction)
    bodies = light_bodies([mesh], [convex_bodies(mesh, 1e-9)], np.zeros(3), direction)
    faces = np.arange(len(triangles)) if faces is None else np.asarray(faces)
    body = np.zeros(len(faces), np.int64)
    return ring_pieces(bodies, body, faces, _frames(triangles), direction, 1e-9)


def test_a_cube_through_a_plane_casts_its_part_ahead_only():
    # light along (1, 0, -1): (x, y, z) falls on the plane z = c at
    # (x + z - c, y, c); the unit cube's part above z = 0.25 covers x' 0..1.75,
    # above z = 0.75 x' 0..1.25 (the whole cube would cover -0.25..1.75)
    cube = _caster(_box([0, 0, 0], [1, 1, 1]))
    big = [[[-10, -10, c], [10, -10, c], [0, 10, c]] for c in (0.25, 0.75)]
    pieces, counts, covers = _pieces(cube, [1, 0, -1], big)
    assert not covers.any() and list(counts) == [4, 4]
    areas = [_area(pieces[i], counts[i]) for i in range(2)]
    np.testing.assert_allclose(areas, [1.75, 1.25], rtol=1e-14)
    # a plane the cube lies wholly behind, and one through its top face: nothing ahead
    pieces, counts, _ = _pieces(
        cube, [1, 0, -1], [[[-10, -10, c], [10, -10, c], [0, 10, c]] for c in (1.5, 1.0)]
    )
    assert list(counts) == [0, 0]


def test_a_box_casts_the_hull_of_its_corners_images_cut_to_the_face():
    box = _caster(_box([0, 0, 0], [2, 1, 3]))
    direction = np.array([0.3, -0.5, -0.8])
    unit = direction / np.linalg.norm(direction)
    images = box.vertices + np.outer((box.vertices[:, 2] + 10) / -unit[2], unit)
    hull = shapely.MultiPoint(images[:, :2]).convex_hull
    wide = [[-40, -40, -10], [40, -40, -10], [0, 40, -10]]  # the plane z = -10, facing up
    pieces, counts, covers = _pieces(box, direction, [wide])
    assert counts[0] == len(hull.exterior.coords) - 1 and not covers[0]
    np.testing.assert_allclose(_area(pieces[0], counts[0]), hull.area, rtol=1e-13)
    # a triangle the hull cuts: the piece is the intersection
    middle = hull.centroid
    narrow = [
        [middle.x, middle.y, -10],
        [middle.x + 20, middle.y, -10],
        [middle.x, middle.y + 20, -10],
    ]
    pieces, counts, _ = _pieces(box, direction, [narrow])
    expected = hull.intersection(shapely.Polygon(np.asarray(narrow)[:, :2])).area
    assert expected > 0
    np.testing.assert_allclose(_area(pieces[0], counts[0]), expected, rtol=1e-12)
    # a triangle inside the hull: wholly shadowed, and the face's next pair not measured
    inside = hull.centroid
    small = [
        [inside.x, inside.y, -10],
        [inside.x + 0.1, inside.y, -10],
        [inside.x, inside.y + 0.1, -10],
    ]
    pieces, counts, covers = _pieces(box, direction, [small], faces=[0, 0])
    assert list(covers) == [True, False] and list(counts) == [0, 0]


def _wall_and_box(box_low, box_high):
    """The wall x = 0 (y 0..4, z 0..4, facing +x) as two triangles, and a box."""
    wall = ([[0, 0, 0], [0, 4, 0], [0, 4, 4], [0, 0, 4]], [[0, 1, 2], [0, 2, 3]])
    return wall, _box(box_low, box_high)


@pytest.mark.parametrize("mode", ["always", "never"])
def test_a_box_before_a_wall_shades_the_rectangle_worked_out_by_hand(mode):
    # light along (-1, 0, -1): a point (x, y, z) falls on the wall at (0, y, z - x);
    # the box x 1..2, y 1..3, z 2..3.5 shades y 1..3, z 0..2.5 there (z - x from 2 - 2 to 3.5 - 1)
    wall, box = _wall_and_box([1, 1, 2], [2, 3, 3.5])
    light = sg.DirectionalLight([-1, 0, -1])
    with compiled_loops(mode):
        fraction, facing = shadowed_fractions(box, light, wall)
    shaded = shapely.box(1, 0, 3, 2.5)  # (y, z)
    halves = [shapely.Polygon([(0, 0), (4, 0), (4, 4)]), shapely.Polygon([(0, 0), (4, 4), (0, 4)])]
    expected = [half.intersection(shaded).area / half.area for half in halves]
    np.testing.assert_allclose(fraction, expected, rtol=0, atol=1e-13)
    assert facing.all()


@pytest.mark.parametrize("mode", ["always", "never"])
def test_a_box_through_a_wall_shades_by_its_part_ahead_only(mode):
    # the box x -1..2 passes through the wall's plane: only x 0..2 casts,
    # along (-1, 0, -1) onto z 0 - ... : z - x for z 1..2, x 0..2 gives z -1..2,
    # cut to the wall: y 1..3, z 0..2
    wall, box = _wall_and_box([-1, 1, 1], [2, 3, 2])
    light = sg.DirectionalLight([-1, 0, -1])
    with compiled_loops(mode):
        fraction, _ = shadowed_fractions(box, light, wall)
    shaded = shapely.box(1, 0, 3, 2)
    halves = [shapely.Polygon([(0, 0), (4, 0), (4, 4)]), shapely.Polygon([(0, 0), (4, 4), (0, 4)])]
    expected = [half.intersection(shaded).area / half.area for half in halves]
    np.testing.assert_allclose(fraction, expected, rtol=0, atol=1e-13)


def test_a_face_a_body_hides_whole_is_wholly_shadowed():
    wall, box = _wall_and_box([1, -1, 1], [2, 5, 9])  # hides the wall and more under (-1, 0, -1)
    with compiled_loops("always"):
        fraction, _ = shadowed_fractions(box, sg.DirectionalLight([-1, 0, -1]), wall)
    assert list(fraction) == [1.0, 1.0]


def _scene(seed: int, ell: bool) -> list[trimesh.Trimesh]:
    """Rotated boxes over a ground slab, some crossing each other's planes and
    the ground's; with an ell (a closed caster that is not convex: its
    outline's pieces take the union's way for every face)."""
    rng = np.random.default_rng(seed)
    parts = []
    for _ in range(10):
        box = trimesh.creation.box(rng.uniform(0.5, 3, 3))
        box.apply_transform(trimesh.transformations.random_rotation_matrix(rng.random(3)))
        box.apply_translation(rng.uniform([-6, -0.5, -6], [6, 4, 6]))
        parts.append(box)
    if ell:
        parts.append(_ell().apply_translation([-2, 0, -2]))
    parts.append(trimesh.creation.box([20, 0.2, 20]).apply_translation([0, -0.1, 0]))
    return parts


def _assert_shares_are_the_unions(mesh, directions) -> None:
    """Every face's compiled share under each sun is shadow_on_surface's."""
    for direction in directions:
        light = sg.DirectionalLight(direction)
        shadow = sg.shadow_on_surface(mesh, light, mesh)
        with compiled_loops("always"):
            fraction, _ = shadowed_fractions(mesh, light, mesh)
        np.testing.assert_allclose(fraction, shadow.fraction, rtol=0, atol=1e-10)


@pytest.mark.parametrize("ell", [False, True])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_shares_of_crossing_bodies_are_the_unions_on_every_face(seed, ell, monkeypatch):
    import shadowgeo.surface as surface

    city = trimesh.util.concatenate(_scene(seed, ell))
    mesh = (np.asarray(city.vertices), np.asarray(city.faces))
    rung = []
    monkeypatch.setattr(surface, "ring_pieces", lambda *a: rung.append(1) or ring_pieces(*a))
    _assert_shares_are_the_unions(mesh, ([0.3, -1, 0.2], [-0.8, -0.3, 0.5]))
    assert rung  # the rings measured every face (the ell by its triangles)


def test_pieces_past_their_budget_are_measured_by_the_union(monkeypatch):
    import shadowgeo.surface as surface

    city = trimesh.util.concatenate(_scene(4, False))
    mesh = (np.asarray(city.vertices), np.asarray(city.faces))
    light = sg.DirectionalLight([0.3, -1, 0.2])
    with compiled_loops("always"):
        within, _ = shadowed_fractions(mesh, light, mesh)
    unions = []
    real = surface._SurfaceProjector._regions
    monkeypatch.setattr(
        surface._SurfaceProjector, "_regions", lambda *a: unions.append(1) or real(*a)
    )
    monkeypatch.setattr(surface, "MAX_PIECE_PAIRS", 3)
    with compiled_loops("always"):
        past, _ = shadowed_fractions(mesh, light, mesh)
    assert unions  # the 2-D union measured them
    np.testing.assert_allclose(past, within, rtol=0, atol=1e-10)
    assert 0 < np.count_nonzero((within > 0) & (within < 1))


def test_a_box_repeated_in_the_data_casts_once_and_an_open_one_keeps_its_faces():
    boxes = [_box([4 * k, 0, 0], [4 * k + 2, 3 + k, 2]) for k in range(4)]
    lid = _box([0, 0, 6], [2, 5, 8])
    keep = lid.face_normals[:, 1] < 0.5  # without its top: open
    open_box = trimesh.Trimesh(lid.vertices, lid.faces[keep], process=False)
    city = trimesh.util.concatenate([*boxes, boxes[1].copy(), boxes[1].copy(), open_box])
    found = convex_bodies(Caster(city.vertices, city.faces), 1e-9)
    assert found.count == 4  # the two repeats left out, the open box not a body
    assert np.array_equal(found.rest, np.arange(72, 72 + len(open_box.faces)))
    mesh = (np.asarray(city.vertices), np.asarray(city.faces))
    _assert_shares_are_the_unions(mesh, ([0.3, -1, 0.2], [-0.9, -0.4, 0.1]))
