"""silhouette: front faces, oriented silhouette edges, loops, border edges.

References: face orientation by trimesh's own normals and face centres,
edges by a Python dictionary over the faces, outlines by shapely hulls of
ray/plane intersections (tests/reference.py).
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
import trimesh
from reference import hull_area_2d, ray_plane

from shadowgeo import (
    DirectionalLight,
    GeometryError,
    Plane,
    PointLight,
    SpotLight,
    as_caster,
    project_shadow,
    silhouette,
)


def brute_force_front(mesh, light):
    normals = np.cross(
        mesh.triangles[:, 1] - mesh.triangles[:, 0], mesh.triangles[:, 2] - mesh.triangles[:, 0]
    )
    if isinstance(light, DirectionalLight):
        towards = np.broadcast_to(-light.direction, normals.shape)
    else:
        towards = light.position - mesh.triangles_center
    return np.einsum("ij,ij->i", normals, towards) > 0


def brute_force_silhouette(faces, front):
    """Directed edges between a front face and a non-front one, as the front
    face runs them; edges used once, directed as their face."""
    uses: dict[tuple[int, int], list[tuple[int, int, int]]] = {}
    for index, face in enumerate(np.asarray(faces).tolist()):
        for k in range(3):
            a, b = face[k], face[(k + 1) % 3]
            uses.setdefault((min(a, b), max(a, b)), []).append((index, a, b))
    outline, border = set(), set()
    for users in uses.values():
        if len(users) == 1:
            border.add(users[0][1:])
        elif len(users) == 2:
            (f, a, b), (g, c, d) = users
            if front[f] != front[g]:
                outline.add((a, b) if front[f] else (c, d))
    return outline, border


def loop_edges(loops):
    return [
        (int(loop[i]), int(loop[(i + 1) % len(loop)])) for loop in loops for i in range(len(loop))
    ]


@pytest.mark.parametrize(
    "light",
    [
        PointLight([0.4, 3.0, 0.3]),
        DirectionalLight([0.3, -1.0, 0.2]),
        SpotLight([3, 1, 0.5], [-1, 0, 0]),
    ],
    ids=["point", "directional", "spot"],
)
def test_convex_silhouette_is_the_hull_of_the_projected_vertices(light):
    sphere = trimesh.creation.icosphere(subdivisions=3)
    outline = silhouette(sphere, light)
    front = brute_force_front(sphere, light)
    assert np.array_equal(outline.front, front)
    expected, border = brute_force_silhouette(sphere.faces, front)
    assert set(map(tuple, outline.edges.tolist())) == expected and len(outline.edges) == len(
        expected
    )
    assert border == set() and len(outline.border) == 0 and outline.is_closed
    # One closed loop, using every silhouette edge once.
    assert len(outline.loops) == 1
    assert sorted(loop_edges(outline.loops)) == sorted(expected)
    # Projected from the light onto a plane behind the sphere, the loop is
    # the convex hull of all projected vertices, counter-clockwise seen from
    # the light.
    if isinstance(light, DirectionalLight):
        normal = -light.direction
        points = sphere.vertices - np.outer(sphere.vertices @ normal + 5.0, normal)
    else:
        normal = light.position / np.linalg.norm(light.position)
        points = ray_plane(sphere.vertices, light.position, normal, 5.0)
    plane = Plane(normal, 5.0)
    uv = plane.to_2d(points)
    loop = uv[outline.loops[0]]
    polygon = shapely.Polygon(loop)
    assert polygon.is_valid
    assert polygon.area == pytest.approx(hull_area_2d(uv), rel=1e-12)
    assert shapely.Polygon(loop).exterior.is_ccw


def test_torus_lit_along_its_axis_has_the_two_equators_as_loops():
    sections = 20
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.3, major_sections=sections, minor_sections=12
    )
    outline = silhouette(torus, DirectionalLight([0, 0, -1]))
    radii = sorted(
        float(np.linalg.norm(torus.vertices[loop][:, :2], axis=1).mean()) for loop in outline.loops
    )
    assert [len(loop) for loop in outline.loops] == [sections, sections]
    assert radii == pytest.approx([0.7, 1.3], rel=1e-12)
    for loop in outline.loops:
        ring = torus.vertices[loop]
        assert np.allclose(ring[:, 2], 0.0, atol=1e-12)
        area = shapely.Polygon(ring[:, :2]).area * (
            1 if shapely.Polygon(ring[:, :2]).exterior.is_ccw else -1
        )
        outer = np.linalg.norm(ring[0, :2]) > 1.0
        # Seen from the light (above): the outer loop counter-clockwise, the hole clockwise.
        assert (area > 0) == outer


def test_silhouette_of_a_self_shadowing_mesh_matches_brute_force():
    mesh = trimesh.creation.icosphere(subdivisions=3)
    direction = mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True)
    mesh.vertices = (
        direction * (1 + 0.3 * np.sin(5 * direction[:, 0]) * np.cos(6 * direction[:, 2]))[:, None]
    )
    light = PointLight([2.5, 0.1, 0.3])
    outline = silhouette(mesh, light)
    front = brute_force_front(mesh, light)
    assert np.array_equal(outline.front, front)
    expected, _ = brute_force_silhouette(mesh.faces, front)
    assert sorted(map(tuple, outline.edges.tolist())) == sorted(expected)
    assert sorted(loop_edges(outline.loops)) == sorted(expected)
    assert len(outline.loops) > 1  # the bumps cast their own outlines


@pytest.mark.parametrize("seed", range(8))
def test_edge_on_faces_never_break_the_loops(seed):
    # A cube rotated at random, lit exactly along one of its faces' planes:
    # those faces' n . l are rounding noise of either sign. Whatever the bits,
    # the loops close and run along exactly the front/non-front edges.
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    rotation = q @ np.diag(np.sign(np.diag(r)))
    cube = trimesh.creation.box()
    cube.vertices = cube.vertices @ rotation.T
    for light in (
        DirectionalLight(rotation @ [0.0, 0.0, -1.0]),
        PointLight(rotation @ [2.0, 0.3, 0.5]),  # in the plane of the top face
    ):
        outline = silhouette(cube, light)
        expected, _ = brute_force_silhouette(cube.faces, outline.front)
        assert sorted(loop_edges(outline.loops)) == sorted(expected)
        assert sorted(map(tuple, outline.edges.tolist())) == sorted(expected)
        # (It may pinch into two loops where one triangle of an edge-on face
        # rounds to front and its sibling does not.)
        # The faces truly turned to the light are front, the ones turned away are not.
        facing = brute_force_front(cube, light)
        normals = cube.face_normals
        towards = (
            -light.direction
            if isinstance(light, DirectionalLight)
            else light.position - cube.triangles_center
        )
        cosine = np.einsum("ij,ij->i", normals, np.broadcast_to(towards, normals.shape))
        clear = np.abs(cosine) > 1e-9
        assert np.array_equal(outline.front[clear], (cosine > 0)[clear])
        assert np.array_equal(facing[clear], outline.front[clear])


def test_open_meshes_report_their_border():
    quad = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], process=False
    )
    seen = silhouette(quad, PointLight([0.5, 0.5, 2.0]))
    assert not seen.is_closed
    assert sorted(map(tuple, seen.border.tolist())) == [(0, 1), (1, 2), (2, 3), (3, 0)]
    assert len(seen.edges) == 0
    assert len(seen.loops) == 1 and sorted(loop_edges(seen.loops)) == [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 0),
    ]
    behind = silhouette(quad, PointLight([0.5, 0.5, -2.0]))
    assert not behind.front.any() and behind.loops == [] and len(behind.border) == 4

    sphere = trimesh.creation.icosphere(subdivisions=2)
    faces = np.delete(sphere.faces, [0, 1, 2, 40, 41], axis=0)
    light = PointLight([0.3, 2.5, 0.4])
    holes = silhouette((sphere.vertices, faces), light)
    front = brute_force_front(trimesh.Trimesh(sphere.vertices, faces, process=False), light)
    expected, border = brute_force_silhouette(faces, front)
    assert set(map(tuple, holes.border.tolist())) == border and len(holes.border) == len(border)
    assert sorted(map(tuple, holes.edges.tolist())) == sorted(expected)
    assert holes.non_manifold.shape == (0, 2)


def test_non_manifold_edges_are_listed():
    vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]]
    outline = silhouette((vertices, [[0, 1, 2], [0, 1, 3], [0, 1, 4]]), PointLight([0.3, 0.3, 3]))
    assert outline.non_manifold.tolist() == [[0, 1]]


def test_planar_fast_path_projects_the_same_loops():
    # A closed caster with nothing to clip: project_shadow hands the union
    # exactly the silhouette's loops, and is chosen without being asked.
    sphere = trimesh.creation.icosphere(subdivisions=3)
    sphere.apply_translation([0, 2, 0])
    light = PointLight([0.4, 5.0, 0.3])
    ground = Plane([0, 1, 0], 0)
    outline = silhouette(sphere, light)
    shadow = project_shadow(sphere, light, ground)
    union = project_shadow(sphere, light, ground, method="triangles")
    assert not any(shadow.diagnostics.clipped.values())
    assert shadow.diagnostics.n_loops == len(outline.loops) == 1
    assert union.diagnostics.n_loops == int(outline.front.sum())
    assert shadow.area == pytest.approx(union.area, rel=1e-9)
    # The same area as the hull of the ray/plane intersections.
    hits = ray_plane(sphere.vertices, light.position, ground.normal, 0.0)
    assert shadow.area == pytest.approx(hull_area_2d(hits[:, [0, 2]]), rel=1e-9)


def test_topology_is_computed_once_for_many_lights():
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    first = silhouette(torus, PointLight([0, 0, 3]))
    caster = as_caster(torus)
    second = silhouette(torus, PointLight([3, 0, 0]))
    assert as_caster(torus) is caster
    assert not np.array_equal(first.front, second.front)


def canonical(loop) -> tuple:
    """A loop as a tuple starting at its smallest vertex (rotation removed)."""
    loop = list(loop)
    first = loop.index(min(loop))
    return tuple(loop[first:] + loop[:first])


def shuffled_cycles(rng, shortest: int):
    lengths = rng.integers(shortest, 60, size=rng.integers(2, 12))
    vertices = rng.permutation(10 * int(lengths.sum()))[: int(lengths.sum())]
    cycles = np.split(vertices, np.cumsum(lengths)[:-1])
    starts = np.concatenate(cycles)
    ends = np.concatenate([np.roll(cycle, -1) for cycle in cycles])
    shuffle = rng.permutation(len(starts))
    return [c.tolist() for c in cycles], starts[shuffle], ends[shuffle]


@pytest.mark.parametrize("seed", range(6))
def test_chain_recovers_shuffled_cycles(seed):
    from shadowgeo.silhouette import chain

    cycles, starts, ends = shuffled_cycles(np.random.default_rng(seed), shortest=1)
    # Loops of one or two edges enclose nothing and are dropped.
    expected = sorted(canonical(c) for c in cycles if len(c) >= 3)
    assert sorted(canonical(loop.tolist()) for loop in chain(starts, ends)) == expected


@pytest.mark.parametrize("seed", range(6))
def test_chain_of_loops_touching_at_a_vertex_uses_every_edge_once(seed):
    from shadowgeo.silhouette import chain

    cycles, starts, ends = shuffled_cycles(np.random.default_rng(seed), shortest=3)
    shared = cycles[0][0]
    # The last cycle passes through the first one's vertex too (a figure 8).
    starts = np.where(starts == cycles[-1][0], shared, starts)
    ends = np.where(ends == cycles[-1][0], shared, ends)
    loops = chain(starts, ends)
    assert sorted(loop_edges(loops)) == sorted(zip(starts.tolist(), ends.tolist(), strict=True))


def test_silhouettes_of_many_lights_at_once_equal_each_lights_own():
    from shadowgeo.silhouette import light_homogeneous, silhouette_loops, silhouette_loops_many

    # A dented sphere (loops that touch at vertices) and two cubes sharing a
    # corner (outlines meeting there), lit from 150 directions and points:
    # more than two 64-light words, the last one partly filled.
    sphere = trimesh.creation.icosphere(subdivisions=3)
    sphere.vertices[sphere.vertices[:, 1] > 0.5] *= [1, 0.5, 1]
    cubes = trimesh.util.concatenate(
        [trimesh.creation.box(), trimesh.creation.box().apply_translation([1, 1, 1])]
    )
    cubes.merge_vertices()
    rng = np.random.default_rng(4)
    for mesh in (sphere, cubes):
        caster = as_caster(mesh)
        assert caster.is_closed
        lights = [DirectionalLight(rng.normal(size=3)) for _ in range(75)]
        lights += [PointLight(rng.normal(size=3) * 4 + [0, 0, 6]) for _ in range(75)]
        fronts = [caster.facing(light_homogeneous(caster, light)) > 0 for light in lights]
        together = silhouette_loops_many(caster, fronts)
        assert len(together) == len(lights)
        for light, front, (loops, vertices) in zip(lights, fronts, together, strict=True):
            alone_loops, alone_vertices = silhouette_loops(caster, front)
            np.testing.assert_array_equal(vertices, alone_vertices)
            assert len(loops) == len(alone_loops)
            assert all(np.array_equal(a, b) for a, b in zip(loops, alone_loops, strict=True))
            # and against the brute-force outline: every silhouette edge once
            expected, _ = brute_force_silhouette(mesh.faces, brute_force_front(mesh, light))
            assert sorted(loop_edges(loops)) == sorted(expected)


def test_vertex_components_label_each_part_by_its_least_vertex():
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from shadowgeo.silhouette import vertex_components

    rng = np.random.default_rng(2)
    parts = [
        trimesh.creation.icosphere(subdivisions=2).apply_translation(rng.uniform(-9, 9, 3))
        for _ in range(5)
    ] + [trimesh.creation.box().apply_translation(rng.uniform(-9, 9, 3)) for _ in range(7)]
    mesh = trimesh.util.concatenate(parts)
    order = rng.permutation(len(mesh.vertices))  # interleave the parts' vertex numbers
    inverse = np.argsort(order)
    vertices, faces = mesh.vertices[order], inverse[mesh.faces]
    labels = vertex_components(as_caster((vertices, faces)))
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), (len(vertices),) * 2)
    count, expected = connected_components(graph, directed=False)
    assert count == len(parts) == len(np.unique(labels))
    for part in range(count):
        members = np.flatnonzero(expected == part)
        assert np.all(labels[members] == members.min())


def _closed_meshes():
    rng = np.random.default_rng(21)
    sphere = trimesh.creation.icosphere(subdivisions=3)
    bumpy = sphere.copy()  # not convex: several silhouette loops, some nested
    bumpy.vertices = bumpy.vertices * (1.0 + 0.3 * rng.random((len(bumpy.vertices), 1)))
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.3, major_sections=24, minor_sections=12
    )
    pair = trimesh.util.concatenate([sphere, torus.copy().apply_translation([0.5, 0.2, 0.1])])
    # Zero-area faces: a vertex moved onto its neighbour keeps the mesh closed.
    pinched = sphere.copy()
    vertices = pinched.vertices.copy()
    vertices[pinched.faces[0, 0]] = vertices[pinched.faces[0, 1]]
    pinched = trimesh.Trimesh(vertices, pinched.faces, process=False)
    box = trimesh.creation.box()  # edge-on faces for axis-aligned lights
    return {"bumpy": bumpy, "torus": torus, "pair": pair, "pinched": pinched, "box": box}


@pytest.mark.parametrize("name", ["bumpy", "torus", "pair", "pinched", "box"])
def test_silhouette_from_the_faces_near_it_equals_the_whole_edge_table(name):
    from shadowgeo.silhouette import front_boundary, light_homogeneous, silhouette_loops
    from shadowgeo.topology import Caster

    mesh = _closed_meshes()[name]
    rng = np.random.default_rng(len(name))
    lights = [DirectionalLight([0.0, 0.0, -1.0]), DirectionalLight([1.0, 0.0, 0.0])]
    lights += [DirectionalLight(rng.normal(size=3)) for _ in range(4)]
    lights += [PointLight(rng.normal(size=3) * 4.0) for _ in range(3)]
    for light in lights:
        near = Caster(mesh.vertices, mesh.faces)  # no edge table: the near faces only
        whole = Caster(mesh.vertices, mesh.faces)
        assert near.is_closed and len(whole.edges) and whole.has_edge_table
        front = near.facing(light_homogeneous(near, light)) > 0
        starts, ends = front_boundary(near, front)
        expected_starts, expected_ends = front_boundary(whole, front)
        assert not near.has_edge_table
        # the same edges in the same order, so the same loops
        assert np.array_equal(starts, expected_starts) and np.array_equal(ends, expected_ends)
        loops, used = silhouette_loops(near, front)
        expected_loops, expected_used = silhouette_loops(whole, front)
        assert len(loops) == len(expected_loops) and np.array_equal(used, expected_used)
        assert all(np.array_equal(a, b) for a, b in zip(loops, expected_loops, strict=True))
        expected, _ = brute_force_silhouette(mesh.faces, front)
        assert sorted(zip(starts.tolist(), ends.tolist(), strict=True)) == sorted(expected)


def test_silhouette_of_a_closed_mesh_with_no_mixed_vertex_is_empty():
    from shadowgeo.silhouette import front_boundary
    from shadowgeo.topology import Caster

    sphere = trimesh.creation.icosphere(subdivisions=1)
    caster = Caster(sphere.vertices, sphere.faces)
    for front in (np.ones(len(sphere.faces), bool), np.zeros(len(sphere.faces), bool)):
        starts, ends = front_boundary(caster, front)
        assert len(starts) == 0 and len(ends) == 0


@pytest.mark.parametrize("name", ["bumpy", "torus", "pair", "pinched", "box"])
def test_chained_flat_outline_is_the_chained_loops_end_to_end(name):
    from shadowgeo.silhouette import chain, chain_flat, front_boundary, light_homogeneous
    from shadowgeo.topology import Caster

    mesh = _closed_meshes()[name]
    rng = np.random.default_rng(len(name) + 1)
    for light in [DirectionalLight(rng.normal(size=3)) for _ in range(4)]:
        caster = Caster(mesh.vertices, mesh.faces)
        starts, ends = front_boundary(caster, caster.facing(light_homogeneous(caster, light)) > 0)
        # a two-edge loop (enclosing nothing) is dropped by both
        starts, ends = np.append(starts, [10**6, 10**6 + 1]), np.append(ends, [10**6 + 1, 10**6])
        loops = chain(starts, ends)
        corners, lengths = chain_flat(starts, ends)
        assert lengths.tolist() == [len(loop) for loop in loops] and min(lengths) >= 3
        assert np.array_equal(corners, np.concatenate(loops))


@pytest.mark.parametrize("seed", range(4))
def test_compiled_successors_equal_the_sorted_ones_in_blocks_and_touching(seed, monkeypatch):
    import importlib

    from shadowgeo.compiled import compiled_loops
    from shadowgeo.kernels import successors

    module = importlib.import_module(
        "shadowgeo.silhouette"
    )  # the package's silhouette is a function

    rng = np.random.default_rng(seed)
    span, starts, ends = 0, [], []
    for _ in range(int(rng.integers(1, 6))):  # blocks of edges, as lights of a batch
        cycles, block_starts, block_ends = shuffled_cycles(rng, shortest=1)
        shared = cycles[0][0]  # loops touching at a vertex: several edges in and out
        block_starts = np.where(block_starts == cycles[-1][0], shared, block_starts)
        block_ends = np.where(block_ends == cycles[-1][0], shared, block_ends)
        starts.append(block_starts)
        ends.append(block_ends)
        span = max(span, int(block_starts.max()) + 1, int(block_ends.max()) + 1)
    offsets = [span * k for k in range(len(starts))]
    starts = np.concatenate([s + o for s, o in zip(starts, offsets, strict=True)])
    ends = np.concatenate([e + o for e, o in zip(ends, offsets, strict=True)])
    with compiled_loops("never"):
        sorted_way = module._successors(starts, ends, span)
    compiled, matched = successors(starts, ends, span)
    assert matched and np.array_equal(compiled, sorted_way)
    with compiled_loops("always"):
        assert np.array_equal(module._successors(starts, ends, span), sorted_way)
    # Blocks out of order, or an outline that does not close: not matched,
    # and the sorting way tells which.
    if len(offsets) > 1:
        assert not successors(starts[::-1].copy(), ends[::-1].copy(), span)[1]
    broken = ends.copy()
    other = int(np.flatnonzero(ends != ends[0])[0])
    broken[0] = broken[other]
    assert not successors(starts, broken, span)[1]
    with pytest.raises(GeometryError, match="not closed"):
        module._successors(starts, broken, span)
