"""The stacked casters of a scene: world vertices, culling and plane removal
agree with the shapes one by one."""

from __future__ import annotations

import numpy as np
import pytest

import shadowgeo as sg
from shadowgeo.scene.casters import CasterSet


def _shapes(count: int, transforms: int, seed: int = 3) -> list[sg.Shape]:
    rng = np.random.default_rng(seed)
    matrices = []
    for _ in range(transforms):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        matrix = np.eye(4)
        matrix[:3, :3] = q * rng.uniform(0.5, 2.0)
        matrix[:3, 3] = rng.uniform(-5, 5, 3)
        matrices.append(matrix)
    return [
        sg.Shape(
            rng.uniform(-1, 1, (5, 3)),
            [[0, 1, 2], [2, 3, 4]],
            transform=matrices[index % transforms],
            name=f"s{index}",
        )
        for index in range(count)
    ]


@pytest.mark.parametrize("transforms", [1, 3, 40])
def test_stacked_world_vertices_equal_each_shapes_own(transforms):
    shapes = _shapes(60, transforms)
    stacked = CasterSet(shapes)
    for shape, caster in zip(shapes, stacked.casters, strict=True):
        np.testing.assert_allclose(caster.vertices, shape.world_vertices, rtol=0, atol=1e-12)
    faces = np.concatenate([s.faces + 5 * i for i, s in enumerate(shapes)])
    assert np.array_equal(stacked.faces, faces)
    every = np.concatenate([s.world_vertices for s in shapes])
    np.testing.assert_allclose(stacked.bounds, [every.min(axis=0), every.max(axis=0)], atol=1e-12)


def test_culling_drops_exactly_the_casters_a_point_light_cannot_reach():
    # Four unit squares at heights 0.5, 1.5, 5 (above the light at y = 4) and
    # -1 (below the ground), and one far out of the light's radius.
    def square(y: float, x: float = 0.0) -> sg.Shape:
        return sg.Shape(
            [[x, y, 0], [x + 1, y, 0], [x + 1, y, 1], [x, y, 1]], [[0, 2, 1], [0, 3, 2]]
        )

    shapes = [square(0.5), square(1.5), square(5.0), square(-1.0), square(1.0, x=50.0)]
    stacked = CasterSet(shapes)
    light = sg.PointLight([0.5, 4.0, 0.5], radius=10.0)
    ground = sg.Plane([0, 1, 0], 0)
    tolerance = sg.Tolerance.for_points(stacked.bounds, light.position)
    keep = stacked.may_shadow(light, ground, None, tolerance)
    assert keep.tolist() == [True, True, False, False, False]
    # A receiver box far to the side: the images of the first two miss it.
    box = (np.array([20.0, 20.0]), np.array([30.0, 30.0]))
    assert not stacked.may_shadow(light, ground, box, tolerance).any()


def test_faces_in_the_receivers_plane_are_dropped_and_no_others():
    rug = sg.Shape([[0, 0, 0], [1, 0, 0], [1, 0, 1]], [[0, 2, 1]])
    tent = sg.Shape([[0, 0, 0], [1, 0, 0], [0.5, 1, 0.5]], [[0, 1, 2]])
    stacked = CasterSet([rug, tent])
    tolerance = sg.Tolerance.for_points(stacked.bounds)
    assert stacked.off_plane(sg.Plane([0, 1, 0], 0), tolerance).tolist() == [False, True]


def _cube(low: float, high: float, drop: int | None = None) -> sg.Shape:
    import trimesh

    box = trimesh.creation.box(bounds=[[low, 0, low], [high, high - low, high]])
    faces = np.delete(box.faces, drop, axis=0) if drop is not None else box.faces
    return sg.Shape(box.vertices, faces)


def test_closed_casters_keep_their_faces_on_the_plane_and_open_ones_lose_them():
    whole, opened = _cube(0, 1), _cube(2, 3, drop=0)
    stacked = CasterSet([whole, opened])
    assert stacked.closed.tolist() == [True, False]
    tolerance = sg.Tolerance.for_points(stacked.bounds)
    keep = stacked.off_plane(sg.Plane([0, 1, 0], 0), tolerance)
    on_ground = np.all(np.isclose(stacked.vertices[stacked.faces][:, :, 1], 0), axis=1)
    first = stacked.face_owner == 0
    assert keep[first].all()  # the closed cube, bottom included
    assert on_ground[~first].any() and not keep[~first & on_ground].any()
    assert keep[~first & ~on_ground].all()


def test_something_in_front_of_a_patch_is_found_from_boxes_and_vertices():
    from shadowgeo.scene.receivers import _anything_in_front  # noqa: PLC2701

    ground = sg.Plane([0, 1, 0], 0)
    floor = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5]], [[0, 2, 1]])
    # A triangle whose box reaches above y = 0 while every vertex of it is at
    # or below the plane would fool a box-only test: here none reaches up.
    slanted = sg.Shape([[0, 0, 0], [1, -1, 0], [1, 0, 1]], [[0, 1, 2]])
    above = sg.Shape([[0, 1, 0], [1, 1, 0], [1, 2, 1]], [[0, 1, 2]])
    below = sg.Shape([[0, -2, 0], [1, -2, 0], [1, -3, 1]], [[0, 1, 2]])
    tolerance = sg.Tolerance.for_points([[-5, -3, -5], [5, 2, 5]])
    assert not _anything_in_front(ground, CasterSet([floor, slanted]), tolerance, False)
    assert _anything_in_front(ground, CasterSet([floor, slanted, above]), tolerance, False)
    assert not _anything_in_front(ground, CasterSet([floor, below]), tolerance, False)
    assert _anything_in_front(ground, CasterSet([floor, below]), tolerance, True)


def test_owners_and_faces_of_chosen_casters_match_the_owner_arrays():
    rng = np.random.default_rng(8)
    shapes = [
        sg.Shape(rng.uniform(-1, 1, (6, 3)), rng.integers(0, 6, (count, 3)), name=f"s{index}")
        for index, count in enumerate([1, 4, 2, 7, 3])
    ]
    stacked = CasterSet(shapes)
    owner = np.repeat(np.arange(5), [1, 4, 2, 7, 3])
    assert np.array_equal(stacked.face_owner, owner)
    assert np.array_equal(stacked.vertex_owner, np.repeat(np.arange(5), 6))
    for _ in range(20):
        chosen = rng.random(5) < 0.5
        assert np.array_equal(stacked.faces_of(chosen), chosen[owner])
        faces = rng.random(len(owner)) < 0.3
        assert stacked.owners(faces).tolist() == sorted(set(owner[faces].tolist()))
    assert CasterSet([]).owners(np.zeros(0, dtype=bool)).tolist() == []


def test_one_shape_without_a_transform_is_stacked_without_copies():
    # the stack of one big mesh must not double its memory; its numbers are the shape's
    rng = np.random.default_rng(2)
    shape = sg.Shape(rng.normal(size=(30, 3)), rng.integers(0, 30, (40, 3)), name="one")
    stacked = CasterSet([shape])
    assert np.shares_memory(stacked.vertices, shape.vertices)
    assert np.shares_memory(stacked.faces, shape.faces)
    assert np.array_equal(stacked.vertices, shape.vertices)
    mesh = stacked.mesh(np.ones(40, dtype=bool))
    assert np.shares_memory(mesh.vertices, shape.vertices) and not mesh.vertices.flags.writeable
    assert shape.vertices.flags.writeable  # the caster's read-only views leave it as it was
    part = stacked.mesh(np.arange(40) % 2 == 0)
    assert np.array_equal(part.faces, shape.faces[::2])
    moved = sg.Shape(shape.vertices, shape.faces, transform=np.diag([2.0, 1.0, 1.0, 1.0]))
    assert np.array_equal(CasterSet([moved]).vertices[:, 0], 2.0 * shape.vertices[:, 0])


def test_a_closed_casters_face_turned_to_the_light_in_the_plane_is_dropped():
    """Seen on the corpus car: the receiver search found the hood, a flat top
    of the closed car shell, and the hood's own faces shadowed it whole. A
    face lying in the lit plane and turned to the light's side is the
    receiver itself; only faces the caster rests on (turned away) are kept."""
    cube = _cube(0, 1)
    stacked = CasterSet([cube])
    tolerance = sg.Tolerance.for_points(stacked.bounds)
    top = sg.Plane([0, 1, 0], -1.0)  # y = 1, lit from above
    keep = stacked.off_plane(top, tolerance)
    on_top = np.all(np.isclose(stacked.vertices[stacked.faces][:, :, 1], 1), axis=1)
    assert on_top.sum() == 2 and not keep[on_top].any() and keep[~on_top].all()
    below = sg.Plane([0, -1, 0], 1.0)  # the same plane lit from below: the cube rests on it
    assert stacked.off_plane(below, tolerance).all()


def test_a_step_shadows_only_the_part_of_its_lower_top_the_upper_part_hides():
    import manifold3d

    lower = manifold3d.Manifold.cube([2.0, 1.0, 1.0])
    upper = manifold3d.Manifold.cube([1.0, 1.0, 1.0]).translate([0.0, 1.0, 0.0])
    mesh = (lower + upper).to_mesh()
    step = sg.Shape(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts))
    sun = sg.SceneLight(sg.DirectionalLight([0.5, -1.0, 0.0]), name="sun", shadows=True)
    # on the plane y = 1: under the upper part (x in [0, 1]) and its shadow
    # beyond it, 0.5 long (x in [1, 1.5]); the lower top past x = 1.5 is lit
    result = sg.add_shadows(sg.Scene([step], [sun]), plane=(0, 1, 0, -1), offset=0.0)
    (shadow,) = result.shapes_with_role("shadow")
    triangles = shadow.vertices[shadow.faces]
    area = (
        0.5
        * np.linalg.norm(
            np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1
        ).sum()
    )
    assert area == pytest.approx(1.5, rel=1e-9)
    assert triangles[:, :, 0].max() == pytest.approx(1.5, rel=1e-9)


def _tetrahedron(offset: float, open_: bool = False) -> sg.Shape:
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) + offset
    return sg.Shape(corners, faces[:3] if open_ else faces)


@pytest.mark.parametrize("way", ["per topology", "stack's edges", "each big shape alone"])
def test_closedness_of_stacked_casters_is_each_shapes_whichever_way_it_is_found(monkeypatch, way):
    # Copies of one closed mesh and one open mesh: closedness found once per
    # topology, or shape by shape for big shapes, must agree with the stack's
    # own edge test, for every mask of whole casters, and a mask that cuts a
    # caster is tested on its faces.
    import shadowgeo.scene.casters as casters_module
    from shadowgeo.topology import Caster

    if way != "per topology":  # the per-topology test off: the stack's edges decide
        monkeypatch.setattr(casters_module, "_TOPOLOGIES_TESTED", 1)
    if way == "each big shape alone":  # ... unless every shape counts as big
        monkeypatch.setattr(casters_module, "_SMALL_TOPOLOGY", 2)
    shapes = [_tetrahedron(2.0 * i, open_=(i == 3)) for i in range(6)]
    stacked = CasterSet(shapes)
    assert (stacked._shape_closed is None) == (way == "stack's edges")
    assert stacked.closed.tolist() == [True, True, True, False, True, True]
    whole = stacked.mesh(stacked.faces_of(np.ones(6, dtype=bool)))
    # the stack's edge table is made only when no shape-by-shape test answers
    assert ("edge_face_count" in whole.__dict__) == (way == "stack's edges")
    rng = np.random.default_rng(5)
    for _ in range(20):
        chosen = rng.random(6) < 0.5
        faces = stacked.faces_of(chosen)
        mesh = stacked.mesh(faces)
        expected = Caster(stacked.vertices, stacked.faces[faces]).is_closed
        assert mesh.is_closed == expected == (chosen.any() and not chosen[3])
    cut = stacked.faces_of(np.ones(6, dtype=bool))
    cut[0] = False  # one face of the first tetrahedron: the mesh is open
    assert stacked.mesh(cut).is_closed is False


def test_a_caster_told_it_is_closed_keeps_it_and_an_empty_one_never_is():
    from shadowgeo.topology import Caster

    shape = _tetrahedron(0.0)
    assert Caster(shape.vertices, shape.faces, closed=True).is_closed is True
    assert Caster(np.zeros((0, 3)), np.zeros((0, 3), dtype=int), closed=True).is_closed is False


def _box(low, high) -> sg.Shape:
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    faces = [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ]  # fmt: skip
    low, high = np.asarray(low, float), np.asarray(high, float)
    return sg.Shape(low + corners * (high - low), faces, name="post")


def _area(shape: sg.Shape) -> float:
    triangles = shape.vertices[shape.faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return 0.5 * float(np.linalg.norm(normals, axis=1).sum())


@pytest.mark.parametrize("top", [9.0, 5.0])
def test_a_caster_reaching_a_point_lights_height_shadows_a_far_floor(top):
    # A post from y = 1 to y = 9 (or to the lamp's height) beside a lamp at
    # height 5: its shadow has no bound, and reaches a floor 15 to 25 away as
    # the wedge |z| <= x / 9 (the rays through the post's near face x = 0.9,
    # |z| <= 0.1), of area (25^2 - 15^2) / 9. The culling by the boxes of
    # the corners' images once dropped the post (the images of corners
    # above the lamp lie on its far side; at its height they are at
    # infinity), and the floor stayed lit.
    post = _box([0.9, 1.0, -0.1], [1.1, top, 0.1])
    floor = sg.Shape(
        [[15, 0, -5], [25, 0, -5], [25, 0, 5], [15, 0, 5]], [[0, 2, 1], [0, 3, 2]], name="floor"
    )
    lamp = sg.SceneLight(sg.PointLight([0, 5, 0]), name="lamp", shadows=True)
    with np.errstate(all="raise"):
        result = sg.add_shadows(
            sg.Scene([post, floor], [lamp]), receivers=["floor"], surfaces=False, offset=0.0
        )
    (shadow,) = result.shapes_with_role("shadow")
    assert _area(shadow) == pytest.approx(400 / 9, rel=1e-9)


@pytest.mark.parametrize("direction", [[1, 0, 0], [1, 1e-300, 0], [0, 1, 0]])
def test_culling_for_a_sun_along_or_below_a_finite_receiver_computes_no_nan(direction):
    # The image of a vertex along a sun parallel to the floor is at infinity:
    # the culling keeps what it cannot place rather than divide by the zero
    # cosine (numpy's warnings raised).
    box = _box([-0.5, 1.5, -0.5], [0.5, 2.5, 0.5])
    stacked = CasterSet([box])
    sun = sg.DirectionalLight(direction)
    floor = sg.Plane([0, 1, 0], 0)
    window = (np.array([-5.0, -5.0]), np.array([5.0, 5.0]))
    with np.errstate(all="raise"):
        keep = stacked.may_shadow(sun, floor, window, sg.Tolerance.for_points(box.vertices))
    assert keep.tolist() == [True]
