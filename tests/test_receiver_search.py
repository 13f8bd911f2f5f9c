"""The automatic receiver search at scale: shapes ruled out by their normal
histogram, repeated shapes searched once, at most MAX_FOUND receivers, and the
scene's triangle budget."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowgeo as sg
from shadowgeo import limits
from shadowgeo.plane2d import unite, without_copies
from shadowgeo.scene import patchbound
from shadowgeo.scene.casters import CasterSet, distinct
from shadowgeo.scene.patchbound import may_hold_patch
from shadowgeo.scene.receivers import MAX_FOUND, found, patches, select

TOLERANCE = sg.Tolerance.for_points([[-10, -10, -10], [10, 10, 10]])


def _largest_patch(shape: sg.Shape) -> float:
    """Brute force: the largest box diagonal of any patch of ``shape``."""
    vertices = shape.world_vertices
    sizes = [
        float(np.linalg.norm(np.ptp(vertices[np.unique(shape.faces[member])], axis=0)))
        for _, member, _ in patches(shape, TOLERANCE, vertices)
    ]
    return max(sizes, default=0.0)


def _sphere(centre=(0.0, 0.0, 0.0), radius: float = 1.0) -> sg.Shape:
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=radius)
    return sg.Shape(mesh.vertices + np.asarray(centre), mesh.faces)


def test_a_curved_shape_is_ruled_out_and_a_flat_one_is_not():
    sphere = _sphere(radius=2.0)
    ground = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], [[0, 2, 1], [0, 3, 2]])
    stacked = CasterSet([sphere, ground])
    keep = may_hold_patch(stacked, np.array([0, 1]), 2.0, TOLERANCE)
    # the sphere's largest flat patch is one face, far below 2 across
    assert _largest_patch(sphere) < 1.0
    assert keep.tolist() == [False, True]


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 30),
    st.floats(0.0, 1e-9),
    st.sampled_from([0.5, 1.0, 2.0, 4.0]),
    st.booleans(),
    st.booleans(),
)
def test_no_shape_with_a_patch_that_large_is_ruled_out(seed, n_tiles, tilt, size, coarse, turn):
    """Bound against brute force: tiles of one (slightly tilted) plane, some
    of them facing the other way, slivers lying in it, scattered triangles,
    the whole turned at random or not (a normal on the cells' edges); whenever
    a patch reaches ``size``, the shape is kept, by the histogram of normals
    and offsets and by the coarser one big shapes are tried by first."""

    rng = np.random.default_rng(seed)
    triangles = []
    for _ in range(n_tiles):  # separate tiles of the plane y = tilt * x
        corner = rng.uniform(-4, 4, 2)
        tile = corner + rng.uniform(0, 1, (3, 2))
        if rng.random() < 0.3:
            tile = tile[::-1]  # facing the other way
        triangles.append(np.column_stack([tile[:, 0], tilt * tile[:, 0], tile[:, 1]]))
    for _ in range(rng.integers(0, 4)):  # slivers in the plane, any direction
        start, end = rng.uniform(-4, 4, (2, 2))
        middle = 0.5 * (start + end) + rng.uniform(-1e-9, 1e-9, 2)
        sliver = np.array([start, end, middle])
        triangles.append(np.column_stack([sliver[:, 0], tilt * sliver[:, 0], sliver[:, 1]]))
    for _ in range(rng.integers(0, 20)):  # noise
        triangles.append(rng.uniform(-4, 4, (3, 3)))
    vertices = np.concatenate(triangles)
    if turn:
        rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        vertices = vertices @ rotation.T
    shape = sg.Shape(vertices, np.arange(len(vertices)).reshape(-1, 3))
    with pytest.MonkeyPatch.context() as patch:
        if coarse:  # every shape tried by the coarse bound first
            patch.setattr(patchbound, "_COARSE_FACES", 1)
        keep = may_hold_patch(CasterSet([shape]), np.array([0]), size, TOLERANCE)
    if _largest_patch(shape) >= size:
        assert keep[0]


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(4, 30),
    st.sampled_from([0.5, 1.0, 2.0, 4.0, 6.0]),
    st.sampled_from([0.0, 1e-12, 1e-7, 1e-3, 0.05]),
    st.booleans(),
)
def test_runs_of_faces_taken_whole_keep_every_shape_with_a_patch_that_large(
    seed, n, size, slope, turn
):
    """Bound against brute force on a folded sheet whose faces follow each
    other across it, so that the coarse bound files runs of them whole: a
    grid of ``n`` by ``n`` squares whose height is bent at random columns by
    ``slope`` at most (folds finer than the tolerance, and coarser), its
    normals on the cells' edges (not turned) or turned at random, with a few
    squares flipped; whenever a patch reaches ``size``, the shape is kept."""

    rng = np.random.default_rng(seed)
    x = np.linspace(-4.0, 4.0, n + 1)
    steps = rng.uniform(-slope, slope, n) * (rng.random(n) < 0.3)
    height = np.concatenate([[0.0], np.cumsum(steps * np.diff(x))])
    grid_x, grid_z = np.meshgrid(x, x, indexing="ij")
    vertices = np.column_stack([grid_x.ravel(), np.repeat(height, n + 1), grid_z.ravel()])
    corner = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    faces = (
        np.concatenate(
            [
                np.column_stack([corner, corner + 1, corner + n + 2]),
                np.column_stack([corner, corner + n + 2, corner + n + 1]),
            ]
        )
        .reshape(2, -1, 3)
        .transpose(1, 0, 2)
        .reshape(-1, 3)
    )  # each square's two in turn
    flipped = rng.random(len(faces)) < 0.05
    faces[flipped] = faces[flipped, ::-1]
    if turn:
        rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        vertices = vertices @ rotation.T
    shape = sg.Shape(vertices + rng.uniform(-3, 3, 3), faces)
    largest = _largest_patch(shape)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(patchbound, "_COARSE_FACES", 1)
        # the sampled size, and the largest patch's own (the tightest case)
        for wanted in (size, largest):
            keep = may_hold_patch(CasterSet([shape]), np.array([0]), wanted, TOLERANCE)
            if largest >= wanted:
                assert keep[0]


def _triangle(centre, normal, radius):
    """An equilateral triangle about ``centre``, counter-clockwise seen from
    ``normal``'s side, its corners ``radius`` from the centre."""
    normal = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
    first = np.cross(normal, [0.0, 0.0, 1.0])
    first /= np.linalg.norm(first)
    second = np.cross(normal, first)
    turns = 2.0 * np.pi * np.arange(3) / 3.0
    return np.asarray(centre) + radius * (
        np.cos(turns)[:, None] * first + np.sin(turns)[:, None] * second
    )


@pytest.mark.parametrize(
    ("member", "wider"), [("tilted", False), ("tilted", True), ("sliver", False)]
)
def test_a_run_of_faces_spanning_two_cells_is_filed_under_both(member, wider):
    """Two faces of one patch 3 apart, each tilted within the tolerance from
    the seed's plane, whose normals fall in neighbouring cells (x component
    0.12 and 0.13, cells of 1/8): the seed's run of 32 faces also holds faces
    in the cell below (0.01 below 0). Filed only under its lowest cell, no
    window around an occupied cell would hold both members, and the shape
    would be ruled out for a size its patch reaches. With one of them two
    cells below (``wider``), the run spans three and must go face by face.
    With the member a sliver lying in the plane (its smallest height below
    the tolerance) whose normal is its run's, far from the seed's, its run
    must go face by face too, the sliver a member of any patch."""

    def unit(x, z=0.06):
        return np.array([x, np.sqrt(1.0 - x * x - z * z), z])

    seed_normal = unit(0.12)
    along = np.cross(seed_normal, [0.0, 0.0, 1.0])
    along /= np.linalg.norm(along)
    far = 3.0 * along  # in the seed's plane
    # the seed, the largest face, and its run's other faces, in the cell
    # below, stacked off its plane (a run taken whole: small, of wide faces)
    triangles = [_triangle([0.0, 0.0, 0.0], seed_normal, 6e-3)]
    triangles += [_triangle(1e-4 * k * seed_normal, unit(-0.01), 5e-3) for k in range(1, 32)]
    if wider:  # one of them two cells below: the run is filed face by face
        triangles[5] = _triangle(5e-4 * seed_normal, unit(-0.13), 5e-3)
    # the member, tilted from the seed's plane by 0.01, and its run's others
    if member == "tilted":
        triangles.append(_triangle(far, unit(0.13), 3e-3))
        others = unit(0.13)
    else:  # a sliver in the seed's plane whose normal is its run's, far from the seed's
        others = unit(-0.5)
        length = np.cross(seed_normal, others)
        length /= np.linalg.norm(length)
        triangles.append(
            np.array(
                [far - 0.01 * length, far + 0.01 * length, far + 2e-5 * np.cross(others, length)]
            )
        )
    triangles += [_triangle(far + 1e-4 * k * seed_normal, others, 3e-3) for k in range(1, 32)]
    # a run far the other way, of other normals, so that the shape's middle
    # (where offsets are measured from) is near the seed: its run's
    # offsets a level or two apart
    away = 0.5 * seed_normal - far
    triangles += [_triangle(away + 1e-4 * k * seed_normal, unit(0.5, 0.5), 3e-3) for k in range(32)]
    vertices = np.concatenate(triangles)
    shape = sg.Shape(vertices, np.arange(len(vertices)).reshape(-1, 3))
    assert _largest_patch(shape) > 2.9
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(patchbound, "_COARSE_FACES", 1)
        assert may_hold_patch(CasterSet([shape]), np.array([0]), 2.0, TOLERANCE)[0]


@pytest.mark.parametrize("coarse", [False, True])
@pytest.mark.parametrize("turn", [False, True])
def test_a_patch_of_faces_facing_both_ways_is_kept(coarse, turn):
    """Two small tiles of one plane at opposite corners, one facing down:
    neither reaches 8 across, the patch of both (11.3) does. Turned, the
    normals fall inside cells; not turned, on the cells' edges."""

    tile = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    vertices = np.concatenate([tile - [4.0, 0, 4.0], (tile + [3.0, 0, 3.0])[::-1]])
    if turn:
        rotation, _ = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))
        vertices = vertices @ rotation.T
    shape = sg.Shape(vertices, [[0, 1, 2], [3, 4, 5]])
    assert _largest_patch(shape) > 8.0
    with pytest.MonkeyPatch.context() as patch:
        if coarse:
            patch.setattr(patchbound, "_COARSE_FACES", 1)
        assert may_hold_patch(CasterSet([shape]), np.array([0]), 8.0, TOLERANCE)[0]


def test_a_big_curved_shape_is_ruled_out_by_its_normals_alone(monkeypatch):
    """A sphere of 81,920 faces (past ``_COARSE_FACES``) is ruled out before
    the finer histogram is built; a flat ring of 80,000 faces, a third of
    them flipped, is kept for a size its box reaches (8.49 across)."""

    def finer(*args, **kwargs):
        raise AssertionError("the finer histogram was built")

    sphere = trimesh.creation.icosphere(subdivisions=6, radius=2.0)
    assert len(sphere.faces) >= patchbound._COARSE_FACES
    stacked = CasterSet([sg.Shape(sphere.vertices, sphere.faces)])
    monkeypatch.setattr(patchbound, "_patch_bound", finer)
    assert may_hold_patch(stacked, np.array([0]), 2.0, TOLERANCE).tolist() == [False]
    monkeypatch.undo()
    # a ring of far more faces than the sphere's largest patch: the bound
    # keeps it at a size its patch reaches and rules it out above the ring
    angles = np.linspace(0.0, 2.0 * np.pi, 40_001)[:-1]
    circle = np.column_stack([np.cos(angles), np.zeros_like(angles), np.sin(angles)])
    ring = np.concatenate([circle, 0.9 * circle])
    k = np.arange(len(angles))
    nxt = (k + 1) % len(angles)
    inner = k + len(angles)
    faces = np.concatenate(
        [np.column_stack([k, nxt, inner]), np.column_stack([nxt, nxt + len(angles), inner])]
    )
    faces[::3] = faces[::3, ::-1]  # a third of them facing down
    disc = CasterSet([sg.Shape(ring * 3.0, faces)])
    assert may_hold_patch(disc, np.array([0]), 5.9, TOLERANCE).tolist() == [True]
    assert may_hold_patch(disc, np.array([0]), 8.6, TOLERANCE).tolist() == [False]


def test_the_normals_the_coarse_bound_keeps_are_the_casters_own():
    """The coarse bound writes the face normals it computes for the casters'
    mesh to take: the same numbers, bit for bit, as the mesh computes alone,
    beside a small shape whose normals it did not compute."""
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=2.0)
    rng = np.random.default_rng(3)
    order = rng.permutation(len(sphere.faces))  # faces in no order of the surface
    big = sg.Shape(sphere.vertices + [0.1, 2.3, -0.7], sphere.faces[order])
    box = trimesh.creation.box()
    stacked = CasterSet([sg.Shape(box.vertices, box.faces), big])
    assert may_hold_patch(stacked, np.array([1]), 2.0, TOLERANCE).tolist() == [False]
    everything = np.ones(len(stacked.faces), dtype=bool)
    kept = stacked.mesh(everything).face_normals
    alone = sg.Caster(stacked.vertices, stacked.faces).face_normals
    assert np.array_equal(kept, alone)
    assert "face_normals" in stacked.mesh(everything).__dict__


def test_a_window_at_some_cells_is_the_whole_windows_values_there():
    """_window_at takes the window over the occupied cells' box only; at any
    cell, occupied or its mirror, it gives the whole grid's window."""
    from shadowgeo.scene.patchbound import _window, _window_at

    rng = np.random.default_rng(5)
    for pick, empty in ((np.minimum, np.inf), (np.maximum, -np.inf)):
        grid = np.full((3, 9, 7, 7, 7), empty)
        cells = tuple(rng.integers(1, 4, 40) + offset for offset in (4, 2, 1, 3))
        grid[(slice(None), *cells)] = rng.normal(size=(3, 40))
        occupied = np.nonzero(np.isfinite(grid[0]))
        mirrored = tuple(n - 1 - at for n, at in zip(grid.shape[1:], occupied, strict=True))
        for reach in (1, 2):
            whole = _window(grid, reach, pick)
            for at in (occupied, mirrored):
                assert np.array_equal(
                    _window_at(grid, reach, pick, occupied, at), whole[(slice(None), *at)]
                )


def test_faces_binned_a_block_at_a_time_rule_out_the_same_shapes(monkeypatch):
    """The histogram built from blocks of a few faces, cells merged across
    blocks, decides as one built at once: sphere, ground and a sphere beside
    a wall, each shape's faces split over several blocks."""

    wall = sg.Shape([[-3, 0, -3], [-3, 4, -3], [3, 4, -3], [3, 0, -3]], [[0, 1, 2], [0, 2, 3]])
    ground = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], [[0, 2, 1], [0, 3, 2]])
    shapes = [_sphere(radius=2.0), ground, _sphere((4.0, 1.0, 0.0)), wall]
    stacked = CasterSet(shapes)
    everything = np.arange(len(shapes))
    for size in (0.5, 2.0, 6.0):
        whole = may_hold_patch(stacked, everything, size, TOLERANCE)
        monkeypatch.setattr(patchbound, "_BIN_BLOCK", 37)
        blocks = may_hold_patch(stacked, everything, size, TOLERANCE)
        monkeypatch.undo()
        assert blocks.tolist() == whole.tolist()
        # the flat shapes reach 14.1 and 7.2 across; the spheres' patches a
        # face (their bound, the faces of the cells around a face's, less than 2)
        assert whole[1] and whole[3] == (size <= 7.2)
        if size >= 2.0:
            assert not whole[0] and not whole[2]


def test_copies_of_a_shape_cast_and_receive_once():
    ground = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], [[0, 2, 1], [0, 3, 2]])
    sphere = _sphere((0.0, 2.0, 0.0))
    copies = [
        sg.Shape(sphere.vertices.copy(), sphere.faces.copy(), name=f"ball{k}") for k in range(50)
    ]
    moved = sg.Shape(sphere.vertices + [1.0, 0, 0], sphere.faces)
    assert distinct([ground, *copies, moved]) == [ground, copies[0], moved]
    # shapes that agree on the first and last vertex and all sizes, and differ
    # only inside, in sidedness or in transform, are all kept
    inner = sphere.vertices.copy()
    inner[len(inner) // 2] += 0.5
    dented = sg.Shape(inner, sphere.faces)
    two_sided = sg.Shape(sphere.vertices, sphere.faces, solid=False)
    turned = sg.Shape(sphere.vertices, sphere.faces, transform=np.diag([1.0, -1.0, 1.0, 1.0]))
    shapes = [copies[0], dented, two_sided, turned, copies[1], dented, turned]
    assert distinct(shapes) == [copies[0], dented, two_sided, turned]
    light = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), name="sun", shadows=True)
    one = sg.add_shadows(sg.Scene([ground, copies[0]], [light]), surfaces=False)
    many = sg.add_shadows(sg.Scene([ground, *copies], [light]), surfaces=False)
    assert "49 shapes repeat another's geometry exactly" in " ".join(many.warnings)
    (shadow_one,) = one.shapes_with_role("shadow")
    (shadow_many,) = many.shapes_with_role("shadow")
    assert np.array_equal(shadow_one.vertices, shadow_many.vertices)
    assert len(many.shapes) == len(one.shapes) + 49  # the input's shapes are all kept


def test_at_most_max_found_receivers_the_largest():
    # floors stacked one above the other, each a little larger than the one
    # below, and a post on the top one: every floor has something above it
    shapes = []
    count = MAX_FOUND + 3
    for k in range(count):
        half, y = 10.0 + 0.1 * k, 2.0 * k
        floor = [[-half, y, -half], [half, y, -half], [half, y, half], [-half, y, half]]
        shapes.append(sg.Shape(floor, [[0, 2, 1], [0, 3, 2]], name=f"floor{k}"))
    post = trimesh.creation.box(bounds=[[-0.2, 2.0 * count, -0.2], [0.2, 2.0 * count + 1, 0.2]])
    shapes.append(sg.Shape(post.vertices, post.faces, name="post"))
    scene = sg.Scene(shapes, [sg.SceneLight(sg.DirectionalLight([0, -1, 0]), shadows=True)])
    received, notes = found(scene, shapes, TOLERANCE, ground_fallback=False)
    names = [receiver.name for receiver in received]
    # the MAX_FOUND largest floors, in the scene's order
    assert names == [f"floor{k}" for k in range(count - MAX_FOUND, count)]
    assert f"{count - MAX_FOUND} more flat surfaces qualify" in " ".join(notes)


def test_copies_of_loops_are_dropped_before_the_union_and_the_region_kept():
    rng = np.random.default_rng(5)
    triangles = [rng.uniform(0, 10, (3, 2)) for _ in range(6)]
    triangles = [t if shapely.Polygon(t).exterior.is_ccw else t[::-1] for t in triangles]
    loops = [np.roll(triangles[k % 6], k % 3, axis=0) for k in range(600)]
    kept = without_copies(loops)
    assert len(kept) == 6
    expected = shapely.union_all([shapely.Polygon(t) for t in triangles]).area
    assert unite(loops).area() == unite(triangles).area()
    assert unite(loops).area() == pytest.approx(expected, rel=1e-8)  # Clipper2's precision
    # even-odd is not a union: copies cancel, so they must stay
    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    assert unite([square] * 64 + [square * 3.0], rule="evenodd").area() == pytest.approx(9.0)
    # with a clockwise loop, copies count: two squares less one is a square
    assert len(without_copies([square] * 70 + [square[::-1]])) == 71
    assert unite([square] * 70 + [square[::-1]]).area() == pytest.approx(1.0)
    assert unite([square, square[::-1]] * 40).area() == 0.0


def test_a_scene_past_the_triangle_budget_is_refused_naming_the_file(tmp_path, monkeypatch):
    path = tmp_path / "balls.x3d"
    spheres = "".join(
        f'<Transform translation="{3 * k} 0 0"><Shape><Sphere/></Shape></Transform>'
        for k in range(4)
    )
    path.write_text(f'<X3D version="4.0"><Scene>{spheres}</Scene></X3D>')
    scene = sg.load(path)
    count = sum(shape.n_faces for shape in scene.shapes)
    with pytest.raises(sg.SceneError, match=r"balls\.x3d.*more than the budget of") as error:
        sg.load(path, max_triangles=count - 1)
    assert f"{count:,} triangles" in str(error.value)
    assert len(sg.load(path, max_triangles=count).shapes) == 4
    monkeypatch.setattr(limits, "MAX_TRIANGLES", count - 1)
    with pytest.raises(sg.SceneError, match="MAX_TRIANGLES"):
        sg.load(path)


def test_the_converter_refuses_past_the_budget_and_the_option_raises_it(tmp_path):
    from cli.main import main

    path = tmp_path / "balls.x3d"
    path.write_text('<X3D version="4.0"><Scene><Shape><Sphere/></Shape></Scene></X3D>')
    count = sum(shape.n_faces for shape in sg.load(path).shapes)
    out = tmp_path / "out.x3d"
    assert main(["convert", str(path), str(out), "--max-triangles", str(count - 1)]) == 1
    assert not out.exists()
    assert main(["convert", str(path), str(out), "--max-triangles", str(count)]) == 0
    assert out.exists()


def test_past_the_surface_budget_only_planar_shadows_and_no_surface_work(monkeypatch):
    import shadowgeo.scene.shadows as shadows

    ground = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], [[0, 2, 1], [0, 3, 2]])
    sphere = _sphere((0.0, 2.0, 0.0), radius=1.5)
    light = sg.SceneLight(sg.DirectionalLight([0.3, -1, 0.2]), name="sun", shadows=True)
    scene = sg.Scene([ground, sphere], [light])
    calls = []
    real = shadows.receiving_faces
    monkeypatch.setattr(shadows, "receiving_faces", lambda *a: calls.append(1) or real(*a))
    within = sg.add_shadows(scene)
    assert calls  # the sphere's faces are searched for shadows (a convex one gets none)
    assert "faces besides the planar receivers" not in " ".join(within.warnings)
    monkeypatch.setattr(limits, "MAX_SURFACE_FACES", sphere.n_faces - 1)
    calls.clear()
    past = sg.add_shadows(scene)
    assert not calls  # the bound (faces less the receivers') settles it
    assert f"{sphere.n_faces:,} faces besides the planar receivers" in " ".join(past.warnings)
    (shadow,) = past.shapes_with_role("shadow")
    assert shadow.name == "shadow_sun_shape"  # the ground (unnamed) only


def test_the_search_returns_its_notes_with_the_receivers_it_chose():
    # a lone box: nothing lies in front of its faces, so none receives, and
    # the ground plane under its lowest corner (y = 1.5, by hand) does
    box = trimesh.creation.box(bounds=[[-1.0, 1.5, -1.0], [1.0, 2.5, 1.0]])
    shapes = [sg.Shape(box.vertices, box.faces, name="box")]
    scene = sg.Scene(shapes, [sg.SceneLight(sg.DirectionalLight([0, -1, 0]), shadows=True)])
    received, notes = found(scene, shapes, TOLERANCE)
    assert [receiver.name for receiver in received] == ["ground"]
    assert received[0].plane.normal.tolist() == [0.0, 1.0, 0.0]
    assert received[0].plane.offset == -1.5
    assert len(notes) == 1 and notes[0].startswith("shadows: no receiver found")
    assert "the ground plane y = 1.5 under the scene's lowest point" in notes[0]
    # without the fallback: nothing found, nothing noted
    assert found(scene, shapes, TOLERANCE, ground_fallback=False) == ([], [])
    # a plane given is chosen, not searched for: no note
    given, given_notes = select(scene, shapes, None, [0, 1, 0, 0], TOLERANCE)
    assert [receiver.name for receiver in given] == ["plane"] and given_notes == []
