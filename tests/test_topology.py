import numpy as np
import pytest
import trimesh

from shadowgeo import GeometryError, as_caster


def test_closed_mesh_is_closed_and_open_mesh_is_not():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    assert as_caster(sphere).is_closed
    open_mesh = (sphere.vertices, sphere.faces[1:])
    assert not as_caster(open_mesh).is_closed
    flipped = sphere.faces.copy()
    flipped[0] = flipped[0, ::-1]
    assert not as_caster((sphere.vertices, flipped)).is_closed


def test_topology_is_cached_on_the_mesh_and_dropped_when_it_changes():
    mesh = trimesh.creation.box()
    first = as_caster(mesh)
    assert as_caster(mesh) is first
    mesh.vertices = mesh.vertices * 2.0
    assert as_caster(mesh) is not first


def test_winding_number_inside_and_outside():
    caster = as_caster(trimesh.creation.box(extents=[2, 2, 2]))
    assert caster.winding_number([0.1, 0.2, 0.3]) == pytest.approx(1.0)
    assert caster.winding_number([3, 0, 0]) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], "missing vertex"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, -1, 2]], "missing vertex"),
        ([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], "not finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2, 0]], r"\(m, 3\)"),
    ],
)
def test_bad_casters_are_refused(vertices, faces, message):
    with pytest.raises(GeometryError, match=message):
        as_caster((vertices, faces))


def _brute_force_edges(faces):
    """Edge -> list of (face, corner) slots, by a Python dictionary."""
    table: dict[tuple[int, int], list[int]] = {}
    for face_index, face in enumerate(np.asarray(faces).tolist()):
        for corner in range(3):
            start, end = face[corner], face[(corner + 1) % 3]
            table.setdefault((min(start, end), max(start, end)), []).append(3 * face_index + corner)
    return table


@pytest.mark.parametrize("closed", [True, False], ids=["closed", "open"])
def test_edge_table_matches_a_brute_force_dictionary(closed):
    mesh = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.3, major_sections=9, minor_sections=7
    )
    faces = mesh.faces if closed else mesh.faces[::2]
    rng = np.random.default_rng(0)
    faces = faces[rng.permutation(len(faces))]
    caster = as_caster((mesh.vertices, faces))
    table = _brute_force_edges(faces)
    assert caster.is_closed == closed
    assert sorted(map(tuple, caster.edges.tolist())) == sorted(table)
    assert caster.edges.tolist() == sorted(caster.edges.tolist())
    for edge_index, edge in enumerate(map(tuple, caster.edges.tolist())):
        begin, end = caster.edge_slot_starts[edge_index : edge_index + 2]
        assert sorted(caster.edge_slots[begin:end].tolist()) == table[edge]
        assert caster.edge_face_count[edge_index] == len(table[edge])
        directions = [
            1 if faces.reshape(-1)[slot] == edge[0] else -1 for slot in table[edge]
        ]  # +1 where the face runs the edge from its lower vertex
        assert caster.edge_net_direction[edge_index] == sum(directions)
    for slot in range(3 * len(faces)):
        face_index, corner = divmod(slot, 3)
        start, end = faces[face_index, corner], faces[face_index, (corner + 1) % 3]
        edge = tuple(caster.edges[caster.face_edges[face_index, corner]])
        assert edge == (min(start, end), max(start, end))
        assert caster.face_edge_signs[face_index, corner] == (1 if start < end else -1)
    if closed:
        assert caster.edge_face_slots.tolist() == [table[tuple(e)] for e in caster.edges.tolist()]


def test_face_normals_and_bounds_against_direct_formulas():
    mesh = trimesh.creation.icosphere(subdivisions=2)
    # An unused far vertex must not enter the bounds.
    vertices = np.vstack([mesh.vertices, [[50.0, 50.0, 50.0]]])
    caster = as_caster((vertices, mesh.faces))
    triangles = vertices[mesh.faces]
    expected = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    assert np.allclose(caster.face_normals, expected, rtol=0, atol=1e-15)
    assert np.allclose(caster.bounds, [mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)])


def test_a_sequence_that_is_not_a_pair_is_refused_by_name():
    mesh = trimesh.creation.box()
    with pytest.raises(GeometryError, match=r"\(vertices, faces\) pair, got tuple of 3 items"):
        as_caster((mesh.vertices, mesh.faces, mesh.faces))
    with pytest.raises(GeometryError, match="got str"):
        as_caster("box")


def test_bounding_box_equals_numpys_reductions_and_carries_nan():
    from shadowgeo.boxes import bounding_box

    rng = np.random.default_rng(5)
    for shape in [(1, 3), (7, 2), (1000, 3)]:
        points = rng.normal(size=shape) * 1e3
        expected = np.array([points.min(axis=0), points.max(axis=0)])
        assert np.array_equal(bounding_box(points), expected)
    points = rng.normal(size=(10, 3))
    points[4, 1] = np.nan
    box = bounding_box(points)
    assert np.isnan(box[:, 1]).all() and np.isfinite(box[:, [0, 2]]).all()


def _closed_by_dictionary(faces):
    """Every edge used exactly twice, once each way (a loop edge a -> a never is)."""
    uses: dict[tuple[int, int], list[int]] = {}
    for face in np.asarray(faces).tolist():
        for corner in range(3):
            start, end = face[corner], face[(corner + 1) % 3]
            uses.setdefault((min(start, end), max(start, end)), []).append(1 if start < end else -1)
    return bool(uses) and all(sorted(signs) == [-1, 1] for signs in uses.values())


def _closedness_cases():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.3, major_sections=9, minor_sections=7
    )
    faces = sphere.faces
    n = len(sphere.vertices)
    tetra = np.array([[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]])
    flipped = faces.copy()
    flipped[5] = flipped[5, ::-1]
    yield "sphere", sphere.vertices, faces
    yield "torus", torus.vertices, torus.faces
    yield "one face less", sphere.vertices, faces[1:]
    yield "one face flipped", sphere.vertices, flipped
    yield "a face twice", sphere.vertices, np.vstack([faces, faces[:1]])
    yield (
        "a face and its reverse added",
        sphere.vertices,
        np.vstack([faces, faces[:1], faces[:1, ::-1]]),
    )
    # a -> a edges: a repeated corner, in both windings
    yield "repeated corner", sphere.vertices, np.vstack([faces, [[0, 0, 1], [0, 1, 0]]])
    # two tetrahedra sharing the edge 0-1: that edge has four uses
    other = np.array([[1, 0, 5], [4, 1, 5], [0, 4, 5], [0, 1, 4]])
    yield "edge of four faces", np.zeros((6, 3)), np.vstack([tetra, other])
    # two spheres touching at one vertex: closed by edges, not a manifold at the vertex
    yield (
        "pinched at a vertex",
        np.zeros((2 * n - 1, 3)),
        np.vstack([faces, np.where(faces == 0, 0, faces + n - 1)]),
    )
    yield "odd face count", np.zeros((4, 3)), tetra[:3]
    rng = np.random.default_rng(3)
    for seed in range(6):
        # random relabelling and face order, and random damage half the time
        perm = rng.permutation(n)
        shuffled = perm[faces][rng.permutation(len(faces))]
        shuffled = np.roll(shuffled, rng.integers(3), axis=1)
        if seed % 2:
            index = rng.integers(len(shuffled))
            shuffled[index, 0] = shuffled[index, 1]
        yield f"random {seed}", sphere.vertices, shuffled


@pytest.mark.parametrize(
    ("vertices", "faces"),
    [case[1:] for case in _closedness_cases()],
    ids=[case[0] for case in _closedness_cases()],
)
def test_closedness_by_one_sort_matches_a_dictionary_of_edges(vertices, faces):
    from shadowgeo.topology import Caster, closed_by_sort

    expected = _closed_by_dictionary(faces)
    assert closed_by_sort(np.asarray(faces), len(vertices)) == expected
    fresh = Caster(vertices, faces)
    assert fresh.is_closed == expected
    assert not fresh.has_edge_table  # closedness alone builds no edge table
    with_table = Caster(vertices, faces)
    assert len(with_table.edges) > 0 and with_table.has_edge_table
    assert with_table.is_closed == expected


def test_closedness_of_many_meshes_by_one_sort_is_each_ones_own():
    from shadowgeo.topology import closed_each

    cases = list(_closedness_cases())
    rng = np.random.default_rng(11)
    # every case several times, in a random order, some meshes with unused
    # vertices past their faces' (their neighbours' keys come right after)
    order = rng.permutation(np.repeat(np.arange(len(cases)), 3))
    meshes = []
    for k in order.tolist():
        _, vertices, faces = cases[k]
        meshes.append((np.asarray(faces), len(vertices) + int(rng.integers(0, 3))))
    meshes.append((np.zeros((0, 3), dtype=np.int64), 3))
    expected = [_closed_by_dictionary(faces) for faces, _ in meshes[:-1]] + [False]
    assert closed_each(meshes).tolist() == expected
    assert closed_each([(np.array([[0, 1, 2]]), 2**31 + 1)]) is None


def test_closedness_by_sort_declines_keys_that_do_not_fit():
    from shadowgeo.topology import closed_by_sort

    assert closed_by_sort(np.array([[0, 1, 2]]), 2**31 + 1) is None
    assert closed_by_sort(np.zeros((0, 3), dtype=np.int64), 3) is False


def test_face_normals_and_facing_in_blocks_equal_the_whole_array_formulas():
    from shadowgeo.topology import Caster

    rng = np.random.default_rng(11)
    vertices = rng.normal(size=(500, 3)) * 10.0
    faces = rng.integers(0, 500, size=(150_017, 3))  # a few blocks and a part
    caster = Caster(vertices, faces)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    u, v = b - a, c - a
    expected = np.column_stack(
        [
            u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
            u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0],
        ]
    )
    assert np.array_equal(caster.face_normals, expected)  # the same operations, bit for bit
    corners = caster.centered[faces[:, 0], :3]
    offsets = np.einsum("ij,ij->i", expected, corners)
    assert np.array_equal(caster.face_offsets, offsets)
    point = np.array([1.0, -2.0, 3.0, 1.0])

    def dot(light):  # written out, as facing does (no BLAS call)
        return expected[:, 0] * light[0] + expected[:, 1] * light[1] + expected[:, 2] * light[2]

    assert np.array_equal(caster.facing(point), dot(point) - offsets)
    direction = np.array([0.3, -1.0, 0.2, 0.0])
    assert np.array_equal(caster.facing(direction) > 0, dot(direction) > 0)
    # A fresh caster's first light goes a block at a time and keeps nothing;
    # the second keeps the normals: the same numbers both ways.
    fresh = Caster(vertices, faces)
    assert np.array_equal(fresh.facing(point), dot(point) - offsets)
    assert "face_normals" not in fresh.__dict__
    assert np.array_equal(fresh.facing(point), dot(point) - offsets)
    assert np.array_equal(fresh.facing(direction), dot(direction))


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("seed", range(5))
def test_cycle_walk_follows_every_cycle_of_a_permutation(seed, compiled, monkeypatch):
    import shadowgeo.topology as topology
    from shadowgeo.compiled import compiled_loops

    rng = np.random.default_rng(seed)
    successor = rng.permutation(int(rng.integers(1, 400)))
    if seed == 4:  # long cycles and fixed points: a permutation of cycles of 1 .. 300 items
        sizes = [1, 1, 300, 2, 50, 1, 17]
        items = rng.permutation(sum(sizes))
        successor = np.empty(len(items), dtype=np.int64)
        for cycle in np.split(items, np.cumsum(sizes)[:-1]):
            successor[cycle] = np.roll(cycle, -1)
    # the compiled walk, or the doubling one
    with compiled_loops("always" if compiled else "never"):
        walk, cuts = topology.cycle_walk(successor)
    # brute force: walk each cycle from its least item, cycles by that item
    seen, expected, starts = set(), [], []
    for item in range(len(successor)):
        if item in seen:
            continue
        starts.append(len(expected))
        while item not in seen:
            seen.add(item)
            expected.append(item)
            item = int(successor[item])
    assert walk.tolist() == expected
    assert cuts.tolist() == starts[1:]


def test_the_compiled_cycle_walk_refuses_a_successor_out_of_range():
    from shadowgeo.kernels import cycle_walk

    with pytest.raises(IndexError, match="out of range"):
        cycle_walk(np.array([1, 2, 3], dtype=np.int64))


def test_numba_is_not_loaded_for_shadows_that_do_not_need_it():
    # A convex caster (one outline loop a light), many shapes as one caster
    # (thousands of loops), a few shapes side by side (a few loops, none
    # holding the others), a few small loops and a long outline's walk: numpy
    # only. numba's
    # import costs about 0.8 s and 100 MB, paid only for a light whose outline
    # has a few loops (a dented caster) or by a caller who loads it.
    script = """
import sys
import numpy as np
import trimesh
import shadowgeo as sg
sphere = trimesh.creation.icosphere(subdivisions=6)
sphere.apply_translation([0, 3, 0])
boxes = [trimesh.creation.box(extents=[0.5, 1, 0.5]) for _ in range(900)]
for k, box in enumerate(boxes):
    box.apply_translation([k % 30, 2, k // 30])
city = trimesh.util.concatenate(boxes)
# a few shapes side by side (a light sees a few loops, none holding the rest)
street = trimesh.util.concatenate(boxes[:5] + [sphere])
# a box half inside a coarse ball: two small loops, one round the other's box
ball = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
ball_and_box = trimesh.util.concatenate([ball, trimesh.creation.box(extents=[1.5, 1.5, 1.5])])
ball_and_box.apply_translation([0, 2, 0])
ground = sg.Plane([0, 1, 0], 0)
for caster in (sphere, city, street, ball_and_box):
    sg.project_shadow(caster, sg.DirectionalLight([0.3, -1, 0.2]), ground)
    sg.project_shadow(caster, [sg.PointLight([1, 9, 2]), sg.DirectionalLight([0, -1, 0.1])], ground)
print("numba" in sys.modules)
"""
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=300, check=True
    )
    assert result.stdout.strip() == "False"


def test_centred_columns_are_the_centred_arrays_columns_before_and_after_it_exists():
    from shadowgeo.topology import Caster

    rng = np.random.default_rng(5)
    vertices = rng.normal(size=(1000, 3)) * 3.0 + [1e6, -2e5, 7.5]  # far from the origin
    faces = rng.integers(0, 1000, size=(400, 3))
    caster = Caster(vertices, faces)
    before = caster.centered_columns()
    assert "centered" not in caster.__dict__  # made without the (n, 4) array
    for axis in range(3):
        assert np.array_equal(before[axis], caster.centered[:, axis])
        assert before[axis].flags.c_contiguous
    after = caster.centered_columns()
    assert all(np.array_equal(a, b) for a, b in zip(before, after, strict=True))


def test_edge_face_slots_are_a_read_only_view_lower_slot_first():
    mesh = trimesh.creation.icosphere(subdivisions=2)
    faces = mesh.faces[np.random.default_rng(2).permutation(len(mesh.faces))]
    caster = as_caster((mesh.vertices, faces))
    slots = caster.edge_face_slots
    assert np.all(slots[:, 0] < slots[:, 1])
    assert not slots.flags.writeable
    with pytest.raises(ValueError):
        slots[0, 0] = 0
