"""shadow_volume: closed, manifold, finite, and the right region.

References are independent of shadowgeo: manifold3d and trimesh judge
closedness; a vectorised Moller-Trumbore segment test against the caster
decides which points are in shadow; the volume's own winding number (solid
angles, written here) decides which points it contains; volumes are checked
against hand-derived formulas.
"""

from __future__ import annotations

import math

import manifold3d
import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from shadowgeo import DirectionalLight, GeometryError, PointLight, SpotLight, shadow_volume

# -- independent references ----------------------------------------------------------------


def segment_hits(points, triangles, light):
    """(n,) bool: the segment from each point to a point light (or the ray
    towards a directional light) crosses a triangle. Two-sided, brute force."""
    points = np.asarray(points, dtype=float)
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    hits = np.zeros(len(points), dtype=bool)
    for chunk in range(0, len(points), 512):
        start = points[chunk : chunk + 512, None, :]  # (k, 1, 3)
        if isinstance(light, DirectionalLight):
            direction = np.broadcast_to(-light.direction, start.shape)
            t_max = np.inf
        else:
            direction = light.position - start
            t_max = 1.0
        p = _cross(direction, e2)  # (k, t, 3)
        det = np.einsum("ktj,tj->kt", p, e1)
        ok = np.abs(det) > 1e-300
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = start - a
        u = np.einsum("ktj,ktj->kt", s, p) * inv
        q = _cross(s, e1)
        v = np.einsum("ktj,ktj->kt", q, direction) * inv
        t = np.einsum("ktj,tj->kt", q, e2) * inv
        inside = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0) & (t < t_max)
        hits[chunk : chunk + 512] = inside.any(axis=1)
    return hits


def _cross(u, v):
    """Cross product along the last axis, by components (np.cross is slower)."""
    return np.stack(
        [
            u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1],
            u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2],
            u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0],
        ],
        axis=-1,
    )


def winding_numbers(points, mesh):
    """(n,) generalised winding number of a triangle mesh around each point
    (sum of signed solid angles over 4 pi, Van Oosterom and Strackee)."""
    triangles = np.asarray(mesh.vertices)[np.asarray(mesh.faces)]
    corners = [np.ascontiguousarray(triangles[:, k].T) for k in range(3)]  # (3, t) each
    result = np.empty(len(points))
    for chunk in range(0, len(points), 512):
        block = points[chunk : chunk + 512]
        # (3, k, t) coordinates of each corner relative to each point
        a, b, c = (corner[:, None, :] - block.T[:, :, None] for corner in corners)
        la, lb, lc = (np.sqrt((x * x).sum(axis=0)) for x in (a, b, c))
        numerator = (
            a[0] * (b[1] * c[2] - b[2] * c[1])
            + a[1] * (b[2] * c[0] - b[0] * c[2])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
        )
        denominator = (
            la * lb * lc
            + (a * b).sum(axis=0) * lc
            + (b * c).sum(axis=0) * la
            + (c * a).sum(axis=0) * lb
        )
        angles = 2.0 * np.arctan2(numerator, denominator)
        result[chunk : chunk + 512] = angles.sum(axis=1) / (4 * math.pi)
    return result


def distance_to_triangles(points, triangles):
    """(n,) distance from each point to the nearest of the triangles."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.where(length > 0, length, 1.0)[:, None]
    result = np.empty(len(points))
    for chunk in range(0, len(points), 256):
        rel = points[chunk : chunk + 256, None, :]
        best = np.full((len(rel), len(triangles)), np.inf)
        for p, q in ((a, b), (b, c), (c, a)):
            edge = q - p
            t = np.einsum("ktj,tj->kt", rel - p, edge) / np.maximum(
                np.einsum("tj,tj->t", edge, edge), 1e-300
            )
            t = np.clip(t, 0.0, 1.0)
            closest = p + t[:, :, None] * edge
            best = np.minimum(best, np.linalg.norm(rel - closest, axis=2))
        height = np.einsum("ktj,tj->kt", rel - a, unit)
        foot = rel - height[:, :, None] * unit
        inside = length > 0
        for p, q in ((a, b), (b, c), (c, a)):
            inside = inside & (np.einsum("ktj,tj->kt", foot - p, np.cross(unit, q - p)) >= 0)
        best = np.where(inside, np.minimum(best, np.abs(height)), best)
        result[chunk : chunk + 256] = best.min(axis=1)
    return result


def assert_closed_manifold(volume):
    """The guarantee: watertight, consistently and outward wound, positive
    volume, finite, and manifold3d accepts it as a manifold."""
    assert len(volume.faces) > 0
    assert np.all(np.isfinite(volume.vertices))
    assert volume.is_watertight
    assert volume.is_winding_consistent
    assert volume.volume > 0
    # Every directed edge exactly once, its reverse exactly once.
    directed = volume.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    _, counts = np.unique(directed, axis=0, return_counts=True)
    assert counts.max() == 1
    mesh = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(volume.vertices, dtype=np.float64),
        tri_verts=np.ascontiguousarray(volume.faces, dtype=np.uint64),
    )
    manifold = manifold3d.Manifold(mesh)
    assert manifold.status() == manifold3d.Error.NoError
    assert manifold.volume() > 0


def assert_right_region(caster, light, volume, n_points=10_000, seed=0, margin=1e-7):
    """>= n_points random points near the caster and in its shadow: inside
    the volume (winding number >= 1/2) exactly where the segment to the light
    hits the caster, except within ``margin`` (relative) of the volume's or
    the caster's surface, where either test may go either way."""
    rng = np.random.default_rng(seed)
    lower, upper = caster.bounds
    size = float(np.linalg.norm(upper - lower))
    if isinstance(light, DirectionalLight):
        behind = light.direction
    else:
        behind = caster.centroid - light.position
        behind = behind / np.linalg.norm(behind)
    # Around the caster, and the same box again 1.5 sizes further from the light.
    box_low = np.minimum(lower, lower + 1.5 * size * behind) - 0.3 * size
    box_high = np.maximum(upper, upper + 1.5 * size * behind) + 0.3 * size
    points = rng.uniform(box_low, box_high, size=(n_points, 3))
    expected = segment_hits(points, caster.vertices[caster.faces], light)
    winding = winding_numbers(points, volume)
    inside = winding > 0.5
    # Away from the boundary the winding number is a whole number.
    suspect = (inside != expected) | (np.abs(winding - np.rint(winding)) > 1e-6)
    suspect = np.flatnonzero(suspect)
    if len(suspect):
        near = distance_to_triangles(points[suspect], volume.vertices[volume.faces])
        near = np.minimum(
            near, distance_to_triangles(points[suspect], caster.vertices[caster.faces])
        )
        far = suspect[near > margin * size]
        assert len(far) == 0, f"{len(far)} points disagree, e.g. {points[far[:3]].tolist()}"
        assert len(suspect) <= 0.01 * n_points
    assert expected.sum() > 0.05 * n_points and (~expected).sum() > 0.05 * n_points
    return points, inside


# -- meshes ----------------------------------------------------------------------------------


def bumpy_sphere(subdivisions=2, amplitude=0.25):
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    direction = mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True)
    wave = 1 + amplitude * np.sin(5 * direction[:, 0]) * np.cos(6 * direction[:, 2])
    mesh.vertices = direction * wave[:, None]
    return mesh


def torus():
    mesh = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.35, major_sections=20, minor_sections=10
    )
    mesh.apply_transform(trimesh.transformations.rotation_matrix(0.4, [1, 0, 0]))
    return mesh


def boolean_mesh():
    """A box with a cylindrical hole and a sphere stuck on: manifold3d booleans."""
    box = manifold3d.Manifold.cube([2.0, 2.0, 1.0], center=True)
    hole = manifold3d.Manifold.cylinder(3.0, 0.45, circular_segments=16, center=True)
    ball = manifold3d.Manifold.sphere(0.6, circular_segments=12).translate([0.9, 0.9, 0.5])
    result = (box - hole + ball).to_mesh()
    return trimesh.Trimesh(result.vert_properties[:, :3], result.tri_verts, process=False)


# -- closed and manifold ---------------------------------------------------------------------

CLOSED_CASES = {
    "convex icosphere, point": (
        lambda: trimesh.creation.icosphere(subdivisions=2),
        PointLight([0.4, 3.0, 0.3]),
    ),
    "torus, point above": (torus, PointLight([0.7, 0.3, 4.0])),
    "torus, point beside": (torus, PointLight([3.0, 0.3, 0.2])),
    "torus, directional": (torus, DirectionalLight([0.2, -0.3, -1.0])),
    "bumpy sphere, point (self-shadowing)": (bumpy_sphere, PointLight([2.2, 0.4, 0.3])),
    "bumpy sphere, directional": (bumpy_sphere, DirectionalLight([-1.0, -0.2, 0.1])),
    "manifold3d booleans, point": (boolean_mesh, PointLight([1.5, 1.0, 3.0])),
    "manifold3d booleans, spot": (
        boolean_mesh,
        SpotLight([-2.0, 0.5, 2.5], [1, 0, -1], cut_off_angle=1.2),
    ),
}


@pytest.mark.parametrize("case", list(CLOSED_CASES))
def test_closed_casters_give_closed_volumes_of_the_right_region(case):
    make, light = CLOSED_CASES[case]
    caster = make()
    assert caster.is_watertight and caster.is_winding_consistent
    volume = shadow_volume(caster, light)
    assert_closed_manifold(volume)
    assert not volume.metadata["shadowgeo"]["two_sided"]
    assert_right_region(caster, light, volume)


def test_self_shadowing_caster_needs_split_saddle_vertices():
    # A light low beside the bumpy sphere: lit fans meet at saddle vertices.
    # A volume that kept one far vertex per caster vertex would put four
    # triangles on those side edges; this one stays manifold.
    caster = bumpy_sphere(subdivisions=2, amplitude=0.35)
    light = PointLight([0.1, 0.3, 2.4])
    volume = shadow_volume(caster, light)
    assert_closed_manifold(volume)
    # Near vertices come first, far copies after: repeated near positions are
    # the split saddle vertices.
    near = volume.vertices[: len(volume.vertices) // 2]
    assert len(np.unique(near, axis=0)) < len(near), "this light is meant to pinch the cap"
    assert_right_region(caster, light, volume, seed=7)


def test_directional_volume_of_a_convex_solid_is_extent_times_its_shadow_area():
    # Every line along the light through the shadow meets the cap once and
    # runs exactly `extent` inside: volume = extent * sum over front faces of
    # area * cos, which for the unit cube is |dx| + |dy| + |dz|.
    rng = np.random.default_rng(5)
    cube = trimesh.creation.box()
    for _ in range(5):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        volume = shadow_volume(cube, DirectionalLight(direction), extent=2.5)
        assert_closed_manifold(volume)
        assert volume.volume == pytest.approx(2.5 * np.abs(direction).sum(), rel=1e-12)


def test_point_light_volume_of_a_square_matches_the_pyramid_formula():
    # A unit square at z = 0 under a light at height 2 over its centre. The
    # volume is the pyramid from the light to the far square minus the one
    # to the square, (s^3 - 1) * 2/3 for far corners s times as far as the
    # square's. The far cap must not come nearer the light than D = 6:
    # checked by sampling its triangles densely.
    square = (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), [[0, 1, 2], [0, 2, 3]])
    light = PointLight([0.5, 0.5, 2.0])
    volume = shadow_volume(square, light, extent=6.0)
    assert_closed_manifold(volume)
    far_corners = volume.vertices[4:]
    assert np.allclose(far_corners[:, 2], far_corners[0, 2])  # symmetric about the light
    scale = np.linalg.norm(far_corners - light.position, axis=1) / math.sqrt(4.5)
    assert np.allclose(scale, scale[0], rtol=1e-13) and scale[0] >= 6.0 / math.sqrt(4.5)
    assert volume.volume == pytest.approx((scale[0] ** 3 - 1) * 2.0 / 3.0, rel=1e-12)
    weights = np.random.default_rng(0).dirichlet([1, 1, 1], size=20_000)
    far_faces = volume.faces[np.all(volume.faces >= 4, axis=1)]
    samples = np.einsum("sk,fkj->fsj", weights, volume.vertices[far_faces])
    nearest = np.linalg.norm(samples - light.position, axis=2).min()
    assert 6.0 <= nearest < 6.0 * 1.01


# -- edge-on faces, close lights, grazing directions -----------------------------------------


def random_rotation(seed):
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


@pytest.mark.parametrize("seed", range(6))
def test_faces_edge_on_to_a_directional_light_leave_no_crack(seed):
    # The light runs exactly along four of the (rotated) cube's faces: after
    # rounding their n . l is a few ulps of either sign, face by face.
    rotation = random_rotation(seed)
    cube = trimesh.creation.box()
    cube.vertices = cube.vertices @ rotation.T
    light = DirectionalLight(rotation @ [0.0, 0.0, -1.0])
    volume = shadow_volume(cube, light, extent=3.0)
    assert_closed_manifold(volume)
    assert volume.volume == pytest.approx(3.0, rel=1e-9)
    # Along one face plane exactly (the x faces are edge-on).
    along = shadow_volume(cube, DirectionalLight(rotation @ [0.0, 1.0, 0.0]), extent=2.0)
    assert_closed_manifold(along)
    assert along.volume == pytest.approx(2.0, rel=1e-9)


def test_point_light_in_the_plane_of_faces_and_a_cylinder_along_its_axis():
    cube = trimesh.creation.box()
    light = PointLight([2.0, 0.0, 0.5])  # in the plane of the top face
    volume = shadow_volume(cube, light)
    assert_closed_manifold(volume)
    assert_right_region(cube, light, volume, seed=1)
    cylinder = trimesh.creation.cylinder(radius=0.5, height=1.0, sections=24)
    along_axis = DirectionalLight([0, 0, -1])  # every side face edge-on
    volume = shadow_volume(cylinder, along_axis, extent=2.0)
    assert_closed_manifold(volume)
    polygon_area = 0.5 * 24 * 0.25 * math.sin(2 * math.pi / 24)
    assert volume.volume == pytest.approx(2.0 * polygon_area, rel=1e-9)


@pytest.mark.parametrize("gap", [1e-3, 1e-6])
def test_light_very_close_to_the_surface(gap):
    sphere = trimesh.creation.icosphere(subdivisions=2)
    face = 7
    center = sphere.triangles_center[face]
    normal = sphere.face_normals[face]
    light = PointLight(center + gap * normal)
    volume = shadow_volume(sphere, light)
    assert_closed_manifold(volume)
    # So close to a face of a convex solid, the light is behind every other
    # face's plane: the cap is that one face, seen across nearly a hemisphere.
    assert volume.metadata["shadowgeo"]["n_cap_faces"] == 1
    assert_right_region(sphere, light, volume, n_points=10_000, seed=2)


def test_light_touching_or_inside_the_caster_is_refused():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    with pytest.raises(GeometryError, match="touches the caster"):
        shadow_volume(sphere, PointLight(sphere.vertices[3]))
    with pytest.raises(GeometryError, match="inside the closed caster"):
        shadow_volume(sphere, PointLight([0.1, 0.2, 0.0]))


def test_extent_and_radius_end_the_volume():
    sphere = trimesh.creation.icosphere(subdivisions=3)
    light = PointLight([0.0, 0.0, 3.0], radius=6.0)
    volume = shadow_volume(sphere, light)
    distance = np.linalg.norm(volume.vertices - light.position, axis=1)
    # Small cap triangles: the far vertices sit barely past the radius.
    assert 6.0 <= distance.max() < 6.0 * 1.01
    assert_closed_manifold(volume)
    points = np.array([[0, 0, -2.9], [0.1, 0, -2.95], [0, 0, -3.1], [0.05, 0, -10.0]])
    assert (winding_numbers(points, volume) > 0.5).tolist() == [True, True, False, False]
    # An extent shorter than the radius wins; one inside the caster is an error.
    shorter = shadow_volume(sphere, light, extent=5.0)
    assert 5.0 <= np.linalg.norm(shorter.vertices - light.position, axis=1).max() < 5.05
    # The lit cap reaches at most sqrt(3^2 - 1) from the light (the tangent
    # circle), so 3.5 is enough, but 2.5 ends inside the caster.
    assert_closed_manifold(shadow_volume(sphere, light, extent=3.5))
    with pytest.raises(GeometryError, match="does not reach past the caster"):
        shadow_volume(sphere, light, extent=2.5)
    # A radius ending inside the caster is lengthened to just past its lit cap.
    short = shadow_volume(sphere, PointLight([0.0, 0.0, 3.0], radius=2.5))
    assert_closed_manifold(short)
    lit = sphere.face_normals @ [0, 0, 3.0] - np.einsum(
        "ij,ij->i", sphere.face_normals, sphere.triangles[:, 0]
    )
    reach = np.linalg.norm(sphere.triangles[lit > 0] - [0, 0, 3.0], axis=2).max()
    assert reach < 3.0  # vertices of faces that straddle the tangent circle
    assert reach < short.metadata["shadowgeo"]["far_distance"] < reach + 0.01
    assert np.linalg.norm(short.vertices - [0, 0, 3.0], axis=1).min() > 1.9  # the cap
    # The default: the caster's farthest bounding-box corner plus 100 diagonals.
    default = shadow_volume(sphere, PointLight([0.0, 0.0, 3.0]))
    corner = math.sqrt(1 + 1 + 16)
    diagonal = np.linalg.norm([2.0, 2.0, 4.0])  # caster and light
    assert default.metadata["shadowgeo"]["far_distance"] == pytest.approx(
        corner + 100 * diagonal, rel=1e-12
    )
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(GeometryError, match="extent"):
            shadow_volume(sphere, light, extent=bad)


def test_spot_light_counts_as_a_point_light_at_its_position():
    caster = torus()
    spot = shadow_volume(caster, SpotLight([0.5, 0.2, 3.0], [0, 0, -1], 0.3))
    point = shadow_volume(caster, PointLight([0.5, 0.2, 3.0]))
    assert np.array_equal(spot.faces, point.faces)
    assert np.array_equal(spot.vertices, point.vertices)


def test_topology_is_reused_across_lights():
    caster = torus()
    first = shadow_volume(caster, PointLight([0.7, 0.3, 4.0]))
    cached = caster._cache["shadowgeo_caster"]
    second = shadow_volume(caster, PointLight([-3.0, 0.3, 0.2]))
    assert caster._cache["shadowgeo_caster"] is cached
    assert_closed_manifold(first)
    assert_closed_manifold(second)


def test_no_casting_face_gives_an_empty_volume():
    square = (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), [[0, 1, 2], [0, 2, 3]])
    flat = shadow_volume(square, DirectionalLight([1, 0, 0]))
    assert len(flat.faces) == 0
    assert (
        len(shadow_volume((np.zeros((0, 3)), np.zeros((0, 3), int)), PointLight([0, 0, 1])).faces)
        == 0
    )


# -- open and non-manifold casters -----------------------------------------------------------


@pytest.mark.parametrize(
    "light",
    [PointLight([0.3, 0.4, 2.0]), PointLight([0.3, 0.4, -2.0]), DirectionalLight([0.3, 0.1, -1])],
    ids=["above", "below", "directional"],
)
def test_a_single_quad_casts_from_both_sides(light):
    quad = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], process=False
    )
    volume = shadow_volume(quad, light, extent=8.0)
    assert_closed_manifold(volume)
    assert volume.metadata["shadowgeo"]["two_sided"]
    # The cap is the quad itself and the four border edges are swept.
    assert volume.metadata["shadowgeo"]["n_side_faces"] == 8
    assert_right_region(quad, light, volume, seed=3)


def test_mesh_with_holes_and_an_open_tube():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    holes = trimesh.Trimesh(sphere.vertices, np.delete(sphere.faces, [0, 1, 2, 40, 41], axis=0))
    assert not holes.is_watertight
    light = PointLight([0.3, 2.5, 0.4])
    volume = shadow_volume(holes, light)
    assert_closed_manifold(volume)
    assert_right_region(holes, light, volume, seed=4)
    # A tube open at both ends, lit from the side: the surface folds over
    # as seen from the light, and both of its sides cast.
    tube = trimesh.creation.cylinder(radius=0.5, height=2.0, sections=16)
    keep = np.abs(tube.face_normals[:, 2]) < 0.5
    tube = trimesh.Trimesh(tube.vertices, tube.faces[keep])
    light = PointLight([2.5, 0.3, 1.8])
    volume = shadow_volume(tube, light)
    assert_closed_manifold(volume)
    assert_right_region(tube, light, volume, seed=5)


def test_inconsistently_wound_closed_mesh_is_treated_as_two_sided():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    faces = sphere.faces.copy()
    faces[::3] = faces[::3, ::-1]
    caster = trimesh.Trimesh(sphere.vertices, faces, process=False)
    light = PointLight([0.2, 0.3, 2.5])
    volume = shadow_volume(caster, light)
    assert volume.metadata["shadowgeo"]["two_sided"]
    assert_closed_manifold(volume)
    assert_right_region(caster, light, volume, n_points=10_000, seed=6)


def test_edges_with_more_than_two_faces_are_named():
    vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]]
    fins = [[0, 1, 2], [0, 1, 3], [0, 1, 4]]  # three fins on the edge 0-1
    with pytest.raises(GeometryError, match=r"1 edges used by more than two faces.*\[0, 1\]"):
        shadow_volume((vertices, fins), PointLight([0.3, 0.3, 3]))


# -- hypothesis: random casters and lights ----------------------------------------------------


@st.composite
def caster_and_light(draw):
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    kind = draw(st.sampled_from(["hull", "bumpy", "torus"]))
    if kind == "hull":
        points = rng.normal(size=(draw(st.integers(4, 40)), 3)) * rng.uniform(0.2, 3, size=3)
        mesh = trimesh.convex.convex_hull(points)
    elif kind == "bumpy":
        mesh = trimesh.creation.icosphere(subdivisions=draw(st.integers(1, 2)))
        direction = mesh.vertices
        k = rng.uniform(2, 7, size=3)
        wave = 1 + rng.uniform(0, 0.35) * np.sin(k[0] * direction[:, 0] + k[1] * direction[:, 1])
        mesh.vertices = direction * (wave * np.cos(k[2] * direction[:, 2]) ** 2 + 0.3)[:, None]
    else:
        mesh = trimesh.creation.torus(
            major_radius=1.0,
            minor_radius=rng.uniform(0.1, 0.6),
            major_sections=draw(st.integers(6, 20)),
            minor_sections=draw(st.integers(4, 10)),
        )
    rotation = np.eye(4)
    rotation[:3, :3] = random_rotation(seed % 1000)
    mesh.apply_transform(rotation)
    damage = draw(st.sampled_from(["none", "none", "holes", "flips"]))
    if damage == "holes":
        keep = rng.random(len(mesh.faces)) > rng.uniform(0.02, 0.5)
        keep[rng.integers(len(keep))] = True  # a small hull could lose every face
        mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
    elif damage == "flips":
        faces = mesh.faces.copy()
        flip = rng.random(len(faces)) < 0.3
        faces[flip] = faces[flip][:, ::-1]
        mesh = trimesh.Trimesh(mesh.vertices, faces, process=False)
    if draw(st.booleans()):
        light = DirectionalLight(rng.normal(size=3))
    else:
        direction = rng.normal(size=3)
        distance = draw(st.floats(0.01, 20.0)) + np.linalg.norm(mesh.extents) / 2
        light = PointLight(mesh.centroid + distance * direction / np.linalg.norm(direction))
    return mesh, light


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(caster_and_light())
def test_random_casters_and_lights_give_closed_manifold_volumes(case):
    # Closed casters, and the same with holes punched or faces flipped (then
    # swept two-sided): always a closed manifold volume of the right region.
    mesh, light = case
    assume(len(mesh.faces) > 0)
    closed = mesh.is_watertight and mesh.is_winding_consistent
    if isinstance(light, PointLight):
        # Lights inside a closed caster or touching any are refused; skip those.
        assume(not closed or abs(winding_numbers(light.position[None], mesh)[0]) < 0.5)
        assume(distance_to_triangles(light.position[None], mesh.triangles)[0] > 1e-6)
    volume = shadow_volume(mesh, light)
    if len(volume.faces) == 0:
        return  # nothing casts (every remaining face edge-on): nothing to close
    assert volume.metadata["shadowgeo"]["two_sided"] == (not closed)
    assert_closed_manifold(volume)
    # A few hundred points of the region check per example.
    rng = np.random.default_rng(0)
    points = mesh.bounds[0] + rng.uniform(-0.5, 1.5, size=(300, 3)) * mesh.extents
    expected = segment_hits(points, mesh.triangles, light)
    scale = float(np.linalg.norm(mesh.extents))
    near = distance_to_triangles(points, volume.triangles) <= 1e-7 * scale
    near |= distance_to_triangles(points, mesh.triangles) <= 1e-7 * scale
    inside = winding_numbers(points, volume) > 0.5
    assert np.array_equal(inside[~near], expected[~near])


# -- X3D surfaces ------------------------------------------------------------------------------

OPEN_BOX_X3D = """<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0">
  <Scene>
    <Shape>
      <IndexedFaceSet solid="false"
          coordIndex="0 1 2 3 -1 4 5 1 0 -1 5 6 2 1 -1 6 7 3 2 -1 7 4 0 3 -1">
        <Coordinate point="0 0 0 1 0 0 1 0 1 0 0 1 0 1 0 1 1 0 1 1 1 0 1 1"/>
      </IndexedFaceSet>
    </Shape>
  </Scene>
</X3D>
"""


def test_x3d_open_box_with_solid_false_is_swept_two_sided(tmp_path):
    # A box with no top, as an X3D author writes it: solid="false", lit from
    # above and to the side so the light sees both the inside and the outside.
    import shadowgeo

    path = tmp_path / "open_box.x3d"
    path.write_text(OPEN_BOX_X3D)
    scene = shadowgeo.load(path)
    (shape,) = [shape for shape in scene.shapes if shape.n_faces]
    assert not shape.solid
    caster = trimesh.Trimesh(shape.world_vertices, shape.faces, process=False)
    assert not caster.is_watertight
    light = PointLight([1.6, 2.5, 0.3])
    volume = shadow_volume(caster, light)
    assert volume.metadata["shadowgeo"]["two_sided"]
    assert_closed_manifold(volume)
    assert_right_region(caster, light, volume, seed=8)


def test_every_shape_of_the_corpus_gives_a_closed_volume(corpus_dir):
    # Real scenes: mostly solid="false" surfaces, some closed solids. Each
    # gives a closed manifold volume or a GeometryError; never an open one.
    import shadowgeo

    checked = 0
    for path in sorted(corpus_dir.rglob("*.x3d")):
        scene = shadowgeo.load(path)
        shapes = [shape for shape in scene.shapes if shape.n_faces][:12]
        if not shapes:
            continue
        lower, upper = scene.bounds
        size = upper - lower
        light = PointLight((lower + upper) / 2 + [0.3 * size[0], 1.5 * size[1] + 1, 0.2 * size[2]])
        for shape in shapes:
            try:
                volume = shadow_volume((shape.world_vertices, shape.faces), light)
            except GeometryError:
                continue
            if len(volume.faces):
                assert_closed_manifold(volume)
                checked += 1
    assert checked >= 50
